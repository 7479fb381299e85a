#include "GltfDraco.h"

#include <draco/compression/decode.h>
#include <draco/core/decoder_buffer.h>

#include <exception>
#include <limits>

namespace ff::builder {

namespace {

Status dracoError(const std::string& where, const std::string& what) {
    return {ErrorCode::InvalidInput, where + ": " + kDracoExtension + ": " + what};
}

bool isIntegerType(draco::DataType type) {
    switch (type) {
    case draco::DT_INT8:
    case draco::DT_UINT8:
    case draco::DT_INT16:
    case draco::DT_UINT16:
    case draco::DT_INT32:
    case draco::DT_UINT32:
        return true;
    default:
        return false;
    }
}

float normalizationScale(draco::DataType type) {
    switch (type) {
    case draco::DT_INT8:
        return 1.0f / 127.0f;
    case draco::DT_UINT8:
        return 1.0f / 255.0f;
    case draco::DT_INT16:
        return 1.0f / 32767.0f;
    case draco::DT_UINT16:
        return 1.0f / 65535.0f;
    default:
        return 1.0f;
    }
}

Result<DracoPrimitive>
decode(const tinygltf::Model& model,
       const tinygltf::Primitive& primitive,
       const std::string& where) {
    const auto ext = primitive.extensions.find(kDracoExtension);
    if (ext == primitive.extensions.end() || !ext->second.IsObject())
        return dracoError(where, "extension object missing");
    const tinygltf::Value& bufferViewValue = ext->second.Get("bufferView");
    const tinygltf::Value& attributesValue = ext->second.Get("attributes");
    if (!bufferViewValue.IsInt() || !attributesValue.IsObject())
        return dracoError(where, "needs an integer bufferView and an attributes object");
    const int viewIndex = bufferViewValue.Get<int>();
    if (viewIndex < 0 || static_cast<std::size_t>(viewIndex) >= model.bufferViews.size())
        return dracoError(where, "bufferView " + std::to_string(viewIndex) + " does not exist");
    const tinygltf::BufferView& view = model.bufferViews[static_cast<std::size_t>(viewIndex)];
    if (view.buffer < 0 || static_cast<std::size_t>(view.buffer) >= model.buffers.size())
        return dracoError(where, "bufferView " + std::to_string(viewIndex) + " has no buffer");
    const std::vector<unsigned char>& data =
            model.buffers[static_cast<std::size_t>(view.buffer)].data;
    if (view.byteOffset > data.size() || view.byteLength > data.size() - view.byteOffset)
        return dracoError(where, "bufferView " + std::to_string(viewIndex) + " past its buffer");

    draco::DecoderBuffer buffer;
    buffer.Init(reinterpret_cast<const char*>(data.data() + view.byteOffset), view.byteLength);
    draco::Decoder decoder;
    auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
    if (!decoded.ok())
        return dracoError(where, "decode failed: " + decoded.status().error_msg_string());
    const std::unique_ptr<draco::Mesh>& mesh = decoded.value();
    if (!mesh)
        return dracoError(where, "decode produced no mesh");

    DracoPrimitive out;
    out.vertexCount = mesh->num_points();
    out.indices.reserve(static_cast<std::size_t>(mesh->num_faces()) * 3);
    for (draco::FaceIndex f(0); f < mesh->num_faces(); ++f) {
        const draco::Mesh::Face& face = mesh->face(f);
        for (const draco::PointIndex& corner : face)
            out.indices.push_back(corner.value());
    }

    for (const auto& [name, idValue] : attributesValue.Get<tinygltf::Value::Object>()) {
        if (!idValue.IsInt() || idValue.Get<int>() < 0)
            return dracoError(where, "attribute " + name + " has no valid Draco id");
        const auto id = static_cast<std::uint32_t>(idValue.Get<int>());
        const draco::PointAttribute* attribute = mesh->GetAttributeByUniqueId(id);
        if (attribute == nullptr)
            return dracoError(
                    where,
                    "attribute " + name + ": Draco id " + std::to_string(id) +
                            " not in the stream");
        const int components = attribute->num_components();
        if (components < 1 || components > 4)
            continue; // not an attribute we read (e.g. a matrix); only 1..4 components matter here
        // glTF says how to interpret the decoded integers; Draco only normalizes when its own
        // flag is set, so apply the accessor's `normalized` for plain integer attributes.
        float scale = 1.0f;
        const auto accessorIt = primitive.attributes.find(name);
        if (accessorIt != primitive.attributes.end() && accessorIt->second >= 0 &&
            static_cast<std::size_t>(accessorIt->second) < model.accessors.size() &&
            model.accessors[static_cast<std::size_t>(accessorIt->second)].normalized &&
            isIntegerType(attribute->data_type()) && !attribute->normalized())
            scale = normalizationScale(attribute->data_type());

        FloatArray array;
        array.count = mesh->num_points();
        array.components = components;
        array.values.resize(array.count * static_cast<std::size_t>(components));
        float value[4] = {0.0f, 0.0f, 0.0f, 0.0f};
        for (draco::PointIndex p(0); p < mesh->num_points(); ++p) {
            const draco::AttributeValueIndex valueIndex = attribute->mapped_index(p);
            if (valueIndex.value() >= attribute->size() ||
                !attribute->ConvertValue<float>(
                        valueIndex, static_cast<std::int8_t>(components), value))
                return dracoError(where, "attribute " + name + ": value out of range");
            for (int c = 0; c < components; ++c) {
                array
                        .values[static_cast<std::size_t>(p.value()) *
                                        static_cast<std::size_t>(components) +
                                static_cast<std::size_t>(c)] = value[c] * scale;
            }
        }
        out.attributes.emplace(name, std::move(array));
    }
    return out;
}

} // namespace

Result<DracoPrimitive> decodeDracoPrimitive(
        const tinygltf::Model& model,
        const tinygltf::Primitive& primitive,
        const std::string& where) noexcept {
    try {
        return decode(model, primitive, where);
    } catch (const std::bad_alloc&) {
        return Status{ErrorCode::OutOfBudget, where + ": out of memory decoding Draco"};
    } catch (const std::exception& e) {
        return dracoError(where, std::string("decoder threw: ") + e.what());
    } catch (...) {
        return dracoError(where, "decoder threw");
    }
}

} // namespace ff::builder
