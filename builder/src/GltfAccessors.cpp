#include "GltfAccessors.h"

#include <algorithm>
#include <cstring>
#include <limits>
#include <span>
#include <string>

namespace ff::builder {

namespace {

/** An accessor without bufferView is all zeros (plus sparse values); its count is not bounded
 *  by any buffer, so cap it before allocating. */
constexpr std::size_t kMaxElementsWithoutView = std::size_t{1} << 26;

Status accessorError(int index, const std::string& what) {
    return {ErrorCode::InvalidInput, "accessor " + std::to_string(index) + ": " + what};
}

/** Byte size of one element, with the column padding glTF requires for small matrices. */
std::size_t elementSizeOf(int componentType, int type) noexcept {
    const std::size_t componentSize = componentSizeOf(componentType);
    const int components = componentCountOf(type);
    if (componentSize == 0 || components == 0)
        return 0;
    if (type == TINYGLTF_TYPE_MAT2 && componentSize == 1)
        return 8; // two columns of 2 bytes, each padded to 4
    if (type == TINYGLTF_TYPE_MAT3 && componentSize == 1)
        return 12; // three columns of 3 bytes, each padded to 4
    if (type == TINYGLTF_TYPE_MAT3 && componentSize == 2)
        return 24; // three columns of 6 bytes, each padded to 8
    return componentSize * static_cast<std::size_t>(components);
}

/** `offset + length <= limit` without overflow. */
bool fits(std::uint64_t offset, std::uint64_t length, std::uint64_t limit) noexcept {
    return offset <= limit && length <= limit - offset;
}

/** Resolves bufferView `viewIndex` to its bytes, checking the view against its buffer. */
Result<std::span<const unsigned char>>
viewBytes(const tinygltf::Model& model, int viewIndex, int accessorIndex, const char* role) {
    if (viewIndex < 0 || static_cast<std::size_t>(viewIndex) >= model.bufferViews.size()) {
        return accessorError(
                accessorIndex,
                std::string(role) + "bufferView " + std::to_string(viewIndex) + " does not exist");
    }
    const tinygltf::BufferView& view = model.bufferViews[static_cast<std::size_t>(viewIndex)];
    if (view.buffer < 0 || static_cast<std::size_t>(view.buffer) >= model.buffers.size()) {
        return Status{
                ErrorCode::InvalidInput,
                "bufferView " + std::to_string(viewIndex) + ": buffer " +
                        std::to_string(view.buffer) + " does not exist"};
    }
    const std::vector<unsigned char>& data =
            model.buffers[static_cast<std::size_t>(view.buffer)].data;
    if (!fits(view.byteOffset, view.byteLength, data.size())) {
        return Status{
                ErrorCode::InvalidInput,
                "bufferView " + std::to_string(viewIndex) + ": range past the end of buffer " +
                        std::to_string(view.buffer)};
    }
    return std::span<const unsigned char>(data.data() + view.byteOffset, view.byteLength);
}

/** Where an accessor's dense elements live: bytes of its view, the stride between elements. */
struct DenseSource {
    std::span<const unsigned char> bytes; ///< empty when the accessor has no bufferView (zeros)
    std::size_t offset = 0;
    std::size_t stride = 0;
};

struct SparseSource {
    std::span<const unsigned char> indices;
    std::span<const unsigned char> values;
    std::size_t count = 0;
    int indexComponentType = 0;
};

struct CheckedAccessor {
    const tinygltf::Accessor* accessor = nullptr;
    std::size_t elementSize = 0;
    DenseSource dense;
    bool sparse = false;
    SparseSource sparseSource;
};

Result<CheckedAccessor> checkAndResolve(const tinygltf::Model& model, int index) {
    if (index < 0 || static_cast<std::size_t>(index) >= model.accessors.size())
        return accessorError(index, "does not exist");
    const tinygltf::Accessor& accessor = model.accessors[static_cast<std::size_t>(index)];
    CheckedAccessor out;
    out.accessor = &accessor;
    out.elementSize = elementSizeOf(accessor.componentType, accessor.type);
    if (out.elementSize == 0)
        return accessorError(index, "unknown componentType or type");
    const std::size_t componentSize = componentSizeOf(accessor.componentType);
    if (accessor.count == 0)
        return accessorError(index, "count must be at least 1");
    if (accessor.bufferView < 0 && accessor.count > kMaxElementsWithoutView)
        return accessorError(index, "count too large for an accessor without bufferView");

    if (accessor.bufferView >= 0) {
        FF_ASSIGN_OR_RETURN(auto bytes, viewBytes(model, accessor.bufferView, index, ""));
        const tinygltf::BufferView& view =
                model.bufferViews[static_cast<std::size_t>(accessor.bufferView)];
        std::size_t stride = out.elementSize;
        if (view.byteStride != 0) {
            if (view.byteStride < out.elementSize) {
                return accessorError(
                        index,
                        "byteStride " + std::to_string(view.byteStride) +
                                " is smaller than an element (" + std::to_string(out.elementSize) +
                                " bytes)");
            }
            stride = view.byteStride;
        }
        if (accessor.byteOffset % componentSize != 0 ||
            (view.byteOffset + accessor.byteOffset) % componentSize != 0)
            return accessorError(index, "byteOffset is not aligned to its component size");
        // Last element ends at byteOffset + (count - 1) * stride + elementSize; bounded by the
        // view, so check count against the view first to keep the product from overflowing.
        if (accessor.count - 1 > bytes.size() / stride ||
            !fits(accessor.byteOffset,
                  static_cast<std::uint64_t>(accessor.count - 1) * stride + out.elementSize,
                  bytes.size())) {
            return accessorError(
                    index,
                    "range past the end of bufferView " + std::to_string(accessor.bufferView));
        }
        out.dense = {bytes, accessor.byteOffset, stride};
    }

    if (accessor.sparse.isSparse) {
        const auto& sparse = accessor.sparse;
        if (sparse.count <= 0 || static_cast<std::size_t>(sparse.count) > accessor.count)
            return accessorError(index, "sparse count out of range");
        const std::size_t count = static_cast<std::size_t>(sparse.count);
        const std::size_t indexSize = componentSizeOf(sparse.indices.componentType);
        if (sparse.indices.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
            sparse.indices.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
            sparse.indices.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
            return accessorError(index, "sparse indices must be unsigned integers");
        FF_ASSIGN_OR_RETURN(
                auto indexBytes,
                viewBytes(model, sparse.indices.bufferView, index, "sparse indices "));
        FF_ASSIGN_OR_RETURN(
                auto valueBytes,
                viewBytes(model, sparse.values.bufferView, index, "sparse values "));
        for (int viewIndex : {sparse.indices.bufferView, sparse.values.bufferView}) {
            if (model.bufferViews[static_cast<std::size_t>(viewIndex)].byteStride != 0)
                return accessorError(index, "sparse bufferViews must not have a byteStride");
        }
        if (sparse.indices.byteOffset < 0 || sparse.values.byteOffset < 0)
            return accessorError(index, "negative sparse byteOffset");
        if (count > indexBytes.size() / indexSize ||
            !fits(static_cast<std::uint64_t>(sparse.indices.byteOffset),
                  static_cast<std::uint64_t>(count) * indexSize,
                  indexBytes.size()))
            return accessorError(index, "sparse indices run past their bufferView");
        if (count > valueBytes.size() / out.elementSize ||
            !fits(static_cast<std::uint64_t>(sparse.values.byteOffset),
                  static_cast<std::uint64_t>(count) * out.elementSize,
                  valueBytes.size()))
            return accessorError(index, "sparse values run past their bufferView");
        out.sparse = true;
        out.sparseSource = {
                indexBytes.subspan(
                        static_cast<std::size_t>(sparse.indices.byteOffset), count * indexSize),
                valueBytes.subspan(
                        static_cast<std::size_t>(sparse.values.byteOffset),
                        count * out.elementSize),
                count,
                sparse.indices.componentType};
    }
    return out;
}

std::uint32_t readUnsigned(const unsigned char* p, int componentType) noexcept {
    switch (componentType) {
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return *p;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        std::uint16_t v = 0;
        std::memcpy(&v, p, sizeof v);
        return v;
    }
    default: {
        std::uint32_t v = 0;
        std::memcpy(&v, p, sizeof v);
        return v;
    }
    }
}

float readComponent(const unsigned char* p, int componentType, bool normalized) noexcept {
    switch (componentType) {
    case TINYGLTF_COMPONENT_TYPE_FLOAT: {
        float v = 0.0f;
        std::memcpy(&v, p, sizeof v);
        return v;
    }
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
        std::int8_t v = 0;
        std::memcpy(&v, p, sizeof v);
        return normalized ? std::max(static_cast<float>(v) / 127.0f, -1.0f) : static_cast<float>(v);
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return normalized ? static_cast<float>(*p) / 255.0f : static_cast<float>(*p);
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
        std::int16_t v = 0;
        std::memcpy(&v, p, sizeof v);
        return normalized ? std::max(static_cast<float>(v) / 32767.0f, -1.0f)
                          : static_cast<float>(v);
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        std::uint16_t v = 0;
        std::memcpy(&v, p, sizeof v);
        return normalized ? static_cast<float>(v) / 65535.0f : static_cast<float>(v);
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
        std::uint32_t v = 0;
        std::memcpy(&v, p, sizeof v);
        return normalized ? static_cast<float>(static_cast<double>(v) / 4294967295.0)
                          : static_cast<float>(v);
    }
    default:
        return 0.0f;
    }
}

/** The accessor's elements tightly packed (count x elementSize), sparse substitution applied.
 *  Everything was range-checked by checkAndResolve(). */
Result<std::vector<unsigned char>> gatherElements(const CheckedAccessor& checked, int index) {
    const tinygltf::Accessor& accessor = *checked.accessor;
    const std::size_t elementSize = checked.elementSize;
    std::vector<unsigned char> packed(accessor.count * elementSize, 0);
    if (!checked.dense.bytes.empty()) {
        const unsigned char* base = checked.dense.bytes.data() + checked.dense.offset;
        for (std::size_t i = 0; i < accessor.count; ++i)
            std::memcpy(
                    packed.data() + i * elementSize, base + i * checked.dense.stride, elementSize);
    }
    if (checked.sparse) {
        const SparseSource& sparse = checked.sparseSource;
        const std::size_t indexSize = componentSizeOf(sparse.indexComponentType);
        for (std::size_t i = 0; i < sparse.count; ++i) {
            const std::uint32_t target =
                    readUnsigned(sparse.indices.data() + i * indexSize, sparse.indexComponentType);
            if (target >= accessor.count) {
                return accessorError(
                        index,
                        "sparse index " + std::to_string(target) + " >= count " +
                                std::to_string(accessor.count));
            }
            std::memcpy(
                    packed.data() + static_cast<std::size_t>(target) * elementSize,
                    sparse.values.data() + i * elementSize,
                    elementSize);
        }
    }
    return packed;
}

} // namespace

glm::vec4 FloatArray::get(std::size_t i, glm::vec4 fill) const noexcept {
    glm::vec4 out = fill;
    const std::size_t n = static_cast<std::size_t>(components);
    for (std::size_t c = 0; c < n && c < 4; ++c)
        out[static_cast<glm::length_t>(c)] = values[i * n + c];
    return out;
}

std::size_t componentSizeOf(int componentType) noexcept {
    switch (componentType) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
        return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT:
        return 4;
    default:
        return 0; // INT and DOUBLE are not glTF 2.0 accessor component types
    }
}

int componentCountOf(int type) noexcept {
    switch (type) {
    case TINYGLTF_TYPE_SCALAR:
        return 1;
    case TINYGLTF_TYPE_VEC2:
        return 2;
    case TINYGLTF_TYPE_VEC3:
        return 3;
    case TINYGLTF_TYPE_VEC4:
    case TINYGLTF_TYPE_MAT2:
        return 4;
    case TINYGLTF_TYPE_MAT3:
        return 9;
    case TINYGLTF_TYPE_MAT4:
        return 16;
    default:
        return 0;
    }
}

Status checkAccessor(const tinygltf::Model& model, int index) {
    FF_ASSIGN_OR_RETURN(auto checked, checkAndResolve(model, index));
    (void)checked;
    return Status::ok();
}

Result<FloatArray> readFloatAccessor(const tinygltf::Model& model, int index) {
    FF_ASSIGN_OR_RETURN(auto checked, checkAndResolve(model, index));
    const tinygltf::Accessor& accessor = *checked.accessor;
    const int components = componentCountOf(accessor.type);
    if (components < 1 || components > 4)
        return accessorError(index, "expected SCALAR, VEC2, VEC3 or VEC4");
    FF_ASSIGN_OR_RETURN(auto packed, gatherElements(checked, index));
    const std::size_t componentSize = componentSizeOf(accessor.componentType);
    FloatArray out;
    out.count = accessor.count;
    out.components = components;
    out.values.resize(accessor.count * static_cast<std::size_t>(components));
    for (std::size_t i = 0; i < out.values.size(); ++i) {
        out.values[i] = readComponent(
                packed.data() + i * componentSize, accessor.componentType, accessor.normalized);
    }
    return out;
}

Result<std::vector<std::uint32_t>> readIndexAccessor(const tinygltf::Model& model, int index) {
    FF_ASSIGN_OR_RETURN(auto checked, checkAndResolve(model, index));
    const tinygltf::Accessor& accessor = *checked.accessor;
    if (accessor.type != TINYGLTF_TYPE_SCALAR ||
        (accessor.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
         accessor.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
         accessor.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT))
        return accessorError(index, "indices must be SCALAR uint8, uint16 or uint32");
    FF_ASSIGN_OR_RETURN(auto packed, gatherElements(checked, index));
    const std::size_t componentSize = componentSizeOf(accessor.componentType);
    std::vector<std::uint32_t> out(accessor.count);
    for (std::size_t i = 0; i < out.size(); ++i)
        out[i] = readUnsigned(packed.data() + i * componentSize, accessor.componentType);
    return out;
}

} // namespace ff::builder
