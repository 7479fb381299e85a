// The only translation unit that compiles tinygltf's implementation (TINYGLTF_IMPLEMENTATION).
//
// - TINYGLTF_NO_STB_IMAGE / TINYGLTF_NO_STB_IMAGE_WRITE: tinygltf neither decodes nor writes
//   images. keepEncodedImage() below stores each image's encoded bytes; TextureSampler decodes
//   only those used as a base colour, so a broken normal map cannot fail an import.
// - TINYGLTF_ENABLE_DRACO is deliberately NOT defined: tinygltf 2.7.0's Draco path indexes
//   bufferViews and accessors from the file without bounds checks, dereferences a null attribute
//   for an unknown Draco attribute id and truncates uint8 indices. GltfDraco.cpp decodes
//   KHR_draco_mesh_compression itself, after validation. Without Draco, tinygltf 2.7.0 rejects
//   a Draco primitive's index accessor (it has no bufferView), so hideDracoIndices() removes
//   those `indices` from the JSON before parsing and they are restored afterwards.
// - File access goes through safeFsCallbacks(): only regular files, at most 4 GiB, so a URI
//   naming a directory or a device cannot make tinygltf allocate or read without bound.
// - nlohmann/json comes from the system include path (Debian's tiny_gltf.h includes
//   <nlohmann/json.hpp>); JSON is parsed without exceptions.
#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE

#include "GltfLoader.h"

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <cstring>
#include <exception>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <string_view>

namespace ff::builder {

namespace {

constexpr std::uint32_t kGlbMagic = 0x46546C67;     // "glTF"
constexpr std::uint32_t kGlbChunkJson = 0x4E4F534A; // "JSON"
constexpr std::uint32_t kGlbChunkBin = 0x004E4942;  // "BIN\0"
constexpr std::size_t kGlbHeaderSize = 12;
constexpr std::size_t kGlbChunkHeaderSize = 8;

std::uint32_t readU32(const std::vector<unsigned char>& bytes, std::size_t offset) {
    std::uint32_t v = 0;
    std::memcpy(&v, bytes.data() + offset, sizeof v);
    return v; // GLB is little-endian, as is every platform we build for
}

/** tinygltf's messages are newline-terminated lines; we want them one per entry. */
void appendLines(
        const std::string& text, const std::string& prefix, std::vector<std::string>& out) {
    std::istringstream in(text);
    std::string line;
    while (std::getline(in, line)) {
        if (!line.empty())
            out.push_back(prefix + line);
    }
}

std::string joinLines(const std::string& text) {
    std::vector<std::string> lines;
    appendLines(text, "", lines);
    std::string joined;
    for (const std::string& line : lines)
        joined += (joined.empty() ? "" : "; ") + line;
    return joined.empty() ? std::string("tinygltf could not parse the file") : joined;
}

/** Checks the GLB framing (header, chunk table) the way the glTF validator does. */
Status checkGlbFraming(const std::vector<unsigned char>& bytes) {
    if (bytes.size() < kGlbHeaderSize)
        return {ErrorCode::InvalidInput, "GLB: file shorter than the 12-byte header"};
    if (readU32(bytes, 0) != kGlbMagic)
        return {ErrorCode::InvalidInput, "GLB: bad magic"};
    const std::uint32_t version = readU32(bytes, 4);
    if (version != 2)
        return {ErrorCode::Unsupported, "GLB: container version " + std::to_string(version)};
    const std::uint32_t length = readU32(bytes, 8);
    if (length != bytes.size()) {
        return {ErrorCode::InvalidInput,
                "GLB: header length " + std::to_string(length) + " but the file has " +
                        std::to_string(bytes.size()) + " bytes"};
    }
    std::size_t offset = kGlbHeaderSize;
    int chunkIndex = 0;
    bool sawBin = false;
    while (offset < bytes.size()) {
        const std::string where = "GLB chunk " + std::to_string(chunkIndex) + ": ";
        if (bytes.size() - offset < kGlbChunkHeaderSize)
            return {ErrorCode::InvalidInput, where + "truncated chunk header"};
        const std::uint32_t chunkLength = readU32(bytes, offset);
        const std::uint32_t chunkType = readU32(bytes, offset + 4);
        offset += kGlbChunkHeaderSize;
        if (chunkLength > bytes.size() - offset)
            return {ErrorCode::InvalidInput, where + "data runs past the end of the file"};
        if (chunkLength % 4 != 0)
            return {ErrorCode::InvalidInput, where + "length is not a multiple of 4"};
        if (chunkIndex == 0 && chunkType != kGlbChunkJson)
            return {ErrorCode::InvalidInput, where + "the first chunk must be JSON"};
        if (chunkIndex > 0 && chunkType == kGlbChunkJson)
            return {ErrorCode::InvalidInput, where + "second JSON chunk"};
        if (chunkType == kGlbChunkBin) {
            if (sawBin || chunkIndex != 1)
                return {ErrorCode::InvalidInput,
                        where + "BIN chunk must be the second chunk, once"};
            sawBin = true;
        }
        offset += chunkLength;
        ++chunkIndex;
    }
    if (chunkIndex == 0)
        return {ErrorCode::InvalidInput, "GLB: no JSON chunk"};
    return Status::ok();
}

/**
 * tinygltf image callback: keep the encoded bytes, decode nothing. For images stored in a
 * bufferView, tinygltf 2.7.0 hands over `&buffer.data[view.byteOffset]` with `view.byteLength`
 * unchecked, so the range is checked here against the buffer before a byte is copied.
 */
bool keepEncodedImage(
        tinygltf::Image* image,
        const int /*imageIndex*/,
        std::string* /*err*/,
        std::string* warn,
        int /*reqWidth*/,
        int /*reqHeight*/,
        const unsigned char* bytes,
        int size,
        void* userData) {
    image->width = 0;
    image->height = 0;
    image->component = 0;
    image->bits = 0;
    image->image.clear();
    if (bytes == nullptr || size <= 0)
        return true;
    const auto* model = static_cast<const tinygltf::Model*>(userData);
    if (image->bufferView >= 0) {
        const auto viewIndex = static_cast<std::size_t>(image->bufferView);
        bool inRange = model != nullptr && viewIndex < model->bufferViews.size();
        if (inRange) {
            const tinygltf::BufferView& view = model->bufferViews[viewIndex];
            inRange = view.buffer >= 0 &&
                      static_cast<std::size_t>(view.buffer) < model->buffers.size();
            if (inRange) {
                const std::size_t bufferSize =
                        model->buffers[static_cast<std::size_t>(view.buffer)].data.size();
                inRange = view.byteOffset <= bufferSize &&
                          view.byteLength <= bufferSize - view.byteOffset &&
                          static_cast<std::size_t>(size) <= view.byteLength;
            }
        }
        if (!inRange) {
            if (warn != nullptr)
                *warn += "image bufferView out of range; image ignored\n";
            return true;
        }
    }
    image->image.assign(bytes, bytes + size);
    return true;
}

/** A Draco primitive's `indices`, hidden from tinygltf and restored after parsing. */
struct DeferredIndices {
    std::size_t mesh = 0;
    std::size_t primitive = 0;
    int accessor = -1;
};

/**
 * Returns the JSON without the `indices` of Draco-compressed primitives (recorded in
 * `deferred`), or nothing when there are none or the JSON does not parse (tinygltf then reports
 * the error itself).
 */
std::optional<std::string>
hideDracoIndices(std::string_view text, std::vector<DeferredIndices>& deferred) {
    if (text.find("KHR_draco_mesh_compression") == std::string_view::npos)
        return std::nullopt;
    nlohmann::json doc = nlohmann::json::parse(text.begin(), text.end(), nullptr, false);
    if (doc.is_discarded() || !doc.is_object())
        return std::nullopt;
    const auto meshes = doc.find("meshes");
    if (meshes == doc.end() || !meshes->is_array())
        return std::nullopt;
    for (std::size_t m = 0; m < meshes->size(); ++m) {
        nlohmann::json& mesh = (*meshes)[m];
        if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array())
            continue;
        nlohmann::json& primitives = mesh["primitives"];
        for (std::size_t p = 0; p < primitives.size(); ++p) {
            nlohmann::json& primitive = primitives[p];
            if (!primitive.is_object() || !primitive.contains("indices") ||
                !primitive.contains("extensions") || !primitive["extensions"].is_object() ||
                !primitive["extensions"].contains("KHR_draco_mesh_compression"))
                continue;
            const nlohmann::json& indices = primitive["indices"];
            int accessor = std::numeric_limits<int>::max(); // resolves to nothing: refused later
            if (indices.is_number_integer()) {
                const auto value = indices.get<std::int64_t>();
                if (value >= 0 && value < std::numeric_limits<int>::max())
                    accessor = static_cast<int>(value);
            }
            deferred.push_back({m, p, accessor});
            primitive.erase("indices");
        }
    }
    if (deferred.empty())
        return std::nullopt;
    return doc.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

void restoreDracoIndices(tinygltf::Model& model, const std::vector<DeferredIndices>& deferred) {
    for (const DeferredIndices& d : deferred) {
        if (d.mesh < model.meshes.size() && d.primitive < model.meshes[d.mesh].primitives.size())
            model.meshes[d.mesh].primitives[d.primitive].indices = d.accessor;
    }
}

/** The GLB with its JSON chunk replaced (framing already checked by checkGlbFraming). */
std::vector<unsigned char>
replaceGlbJson(const std::vector<unsigned char>& glb, const std::string& json) {
    const std::size_t oldJsonLength = readU32(glb, kGlbHeaderSize);
    const std::size_t rest = kGlbHeaderSize + kGlbChunkHeaderSize + oldJsonLength;
    std::string padded = json;
    padded.resize((padded.size() + 3) / 4 * 4, ' ');
    std::vector<unsigned char> out(glb.begin(), glb.begin() + kGlbHeaderSize);
    auto putU32 = [&out](std::size_t at, std::size_t value) {
        const auto v = static_cast<std::uint32_t>(value);
        std::memcpy(out.data() + at, &v, sizeof v);
    };
    out.resize(kGlbHeaderSize + kGlbChunkHeaderSize);
    putU32(kGlbHeaderSize, padded.size());
    putU32(kGlbHeaderSize + 4, kGlbChunkJson);
    out.insert(out.end(), padded.begin(), padded.end());
    out.insert(out.end(), glb.begin() + static_cast<std::ptrdiff_t>(rest), glb.end());
    putU32(8, out.size());
    return out;
}

Status readWholeFile(const std::filesystem::path& path, std::vector<unsigned char>& bytes) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
        return {ErrorCode::NotFound, path.string() + ": no such file"};
    std::ifstream in(path, std::ios::binary);
    if (!in)
        return {ErrorCode::IoError, path.string() + ": cannot open"};
    in.seekg(0, std::ios::end);
    const std::streamoff size = in.tellg();
    in.seekg(0, std::ios::beg);
    if (size < 0)
        return {ErrorCode::IoError, path.string() + ": cannot read"};
    if (static_cast<std::uint64_t>(size) > std::numeric_limits<std::uint32_t>::max())
        return {ErrorCode::Unsupported, path.string() + ": files over 4 GiB are not supported"};
    bytes.resize(static_cast<std::size_t>(size));
    if (size > 0 && !in.read(reinterpret_cast<char*>(bytes.data()), size))
        return {ErrorCode::IoError, path.string() + ": short read"};
    return Status::ok();
}

bool safeFileExists(const std::string& path, void*) {
    std::error_code ec;
    return std::filesystem::is_regular_file(path, ec);
}

std::string identityPath(const std::string& path, void*) {
    return path;
}

bool safeReadWholeFile(
        std::vector<unsigned char>* out, std::string* err, const std::string& path, void*) {
    const Status status = readWholeFile(path, *out);
    if (!status.isOk() && err != nullptr)
        *err += status.message() + "\n";
    return status.isOk();
}

bool refuseWrite(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
    if (err != nullptr)
        *err += "writing is disabled\n";
    return false;
}

tinygltf::FsCallbacks safeFsCallbacks() {
    return {&safeFileExists, &identityPath, &safeReadWholeFile, &refuseWrite, nullptr};
}

} // namespace

Status loadGltfModel(
        const std::filesystem::path& path,
        tinygltf::Model& model,
        std::vector<std::string>& warnings) noexcept {
    try {
        std::vector<unsigned char> bytes;
        FF_RETURN_IF_ERROR(readWholeFile(path, bytes));

        const bool isBinary = bytes.size() >= 4 && readU32(bytes, 0) == kGlbMagic;
        const std::string baseDir = path.parent_path().string();
        tinygltf::TinyGLTF loader;
        loader.SetImageLoader(&keepEncodedImage, &model);
        loader.SetFsCallbacks(safeFsCallbacks());
        std::string err;
        std::string warn;
        bool loaded = false;
        std::vector<DeferredIndices> deferred;
        if (isBinary) {
            FF_RETURN_IF_ERROR(checkGlbFraming(bytes));
            const std::string_view json(
                    reinterpret_cast<const char*>(bytes.data()) + kGlbHeaderSize +
                            kGlbChunkHeaderSize,
                    readU32(bytes, kGlbHeaderSize));
            if (auto rewritten = hideDracoIndices(json, deferred))
                bytes = replaceGlbJson(bytes, *rewritten);
            loaded = loader.LoadBinaryFromMemory(
                    &model,
                    &err,
                    &warn,
                    bytes.data(),
                    static_cast<unsigned int>(bytes.size()),
                    baseDir);
        } else {
            if (bytes.empty())
                return {ErrorCode::InvalidInput, "JSON: empty file"};
            if (bytes.size() >= 3 && bytes[0] == 0xEF && bytes[1] == 0xBB && bytes[2] == 0xBF)
                return {ErrorCode::InvalidInput, "JSON: must not start with a byte order mark"};
            const std::string_view json(reinterpret_cast<const char*>(bytes.data()), bytes.size());
            if (auto rewritten = hideDracoIndices(json, deferred))
                bytes.assign(rewritten->begin(), rewritten->end());
            loaded = loader.LoadASCIIFromString(
                    &model,
                    &err,
                    &warn,
                    reinterpret_cast<const char*>(bytes.data()),
                    static_cast<unsigned int>(bytes.size()),
                    baseDir);
        }
        restoreDracoIndices(model, deferred);
        appendLines(warn, "tinygltf: ", warnings);
        if (!loaded)
            return {ErrorCode::InvalidInput, "tinygltf: " + joinLines(err)};
        if (!err.empty())
            appendLines(err, "tinygltf: ", warnings);
        return Status::ok();
    } catch (const std::bad_alloc&) {
        return {ErrorCode::OutOfBudget, "out of memory while parsing the glTF file"};
    } catch (const std::exception& e) {
        return {ErrorCode::InvalidInput, std::string("glTF parser failed: ") + e.what()};
    } catch (...) {
        return {ErrorCode::InvalidInput, "glTF parser failed with an unknown exception"};
    }
}

} // namespace ff::builder
