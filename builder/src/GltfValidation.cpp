#include "GltfValidation.h"

#include "GltfAccessors.h"
#include "GltfDraco.h"
#include "GltfMaterial.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace ff::builder {

namespace {

constexpr std::array<std::string_view, 5> kSupportedRequired = {
        "KHR_draco_mesh_compression", "KHR_mesh_quantization", kInstancingExtension,
        kTextureTransformExtension, kUnlitExtension};

template <typename T> bool inRange(int index, const std::vector<T>& items) noexcept {
    return index >= 0 && static_cast<std::size_t>(index) < items.size();
}

Status invalid(const std::string& object, int index, const std::string& what) {
    return {ErrorCode::InvalidInput, object + " " + std::to_string(index) + ": " + what};
}

bool allFinite(const std::vector<double>& values) noexcept {
    for (double v : values) {
        if (!std::isfinite(v))
            return false;
    }
    return true;
}

Status checkBufferViews(const tinygltf::Model& model) {
    for (std::size_t i = 0; i < model.bufferViews.size(); ++i) {
        const tinygltf::BufferView& view = model.bufferViews[i];
        const int index = static_cast<int>(i);
        if (!inRange(view.buffer, model.buffers))
            return invalid(
                    "bufferView",
                    index,
                    "buffer " + std::to_string(view.buffer) + " does not exist");
        const std::size_t size = model.buffers[static_cast<std::size_t>(view.buffer)].data.size();
        if (view.byteLength == 0)
            return invalid("bufferView", index, "byteLength must be at least 1");
        if (view.byteOffset > size || view.byteLength > size - view.byteOffset) {
            return invalid(
                    "bufferView",
                    index,
                    "range [" + std::to_string(view.byteOffset) + ", +" +
                            std::to_string(view.byteLength) + ") past the end of buffer " +
                            std::to_string(view.buffer) + " (" + std::to_string(size) + " bytes)");
        }
        if (view.byteStride > view.byteLength)
            return invalid(
                    "bufferView",
                    index,
                    "byteStride " + std::to_string(view.byteStride) +
                            " is larger than byteLength " + std::to_string(view.byteLength));
        if (view.byteStride != 0 &&
            (view.byteStride < 4 || view.byteStride > 252 || view.byteStride % 4 != 0))
            return invalid(
                    "bufferView",
                    index,
                    "byteStride " + std::to_string(view.byteStride) +
                            " must be a multiple of 4 in [4, 252]");
    }
    return Status::ok();
}

/** Node graph: references, single parent, no loops, finite transforms. */
Status checkNodes(const tinygltf::Model& model, std::vector<int>& parents) {
    const std::size_t count = model.nodes.size();
    parents.assign(count, -1);
    for (std::size_t i = 0; i < count; ++i) {
        const tinygltf::Node& node = model.nodes[i];
        const int index = static_cast<int>(i);
        for (int child : node.children) {
            if (!inRange(child, model.nodes))
                return invalid("node", index, "child " + std::to_string(child) + " does not exist");
            if (child == index)
                return invalid("node", index, "loop through its children (it is its own child)");
            int& parent = parents[static_cast<std::size_t>(child)];
            if (parent != -1) {
                return invalid(
                        "node",
                        child,
                        "has two parents (nodes " + std::to_string(parent) + " and " +
                                std::to_string(index) + ")");
            }
            parent = index;
        }
        if (node.mesh != -1 && !inRange(node.mesh, model.meshes))
            return invalid("node", index, "mesh " + std::to_string(node.mesh) + " does not exist");
        if (node.camera != -1 && !inRange(node.camera, model.cameras))
            return invalid(
                    "node", index, "camera " + std::to_string(node.camera) + " does not exist");
        if (!node.matrix.empty() && node.matrix.size() != 16)
            return invalid("node", index, "matrix must have 16 values");
        if (!node.translation.empty() && node.translation.size() != 3)
            return invalid("node", index, "translation must have 3 values");
        if (!node.rotation.empty() && node.rotation.size() != 4)
            return invalid("node", index, "rotation must have 4 values");
        if (!node.scale.empty() && node.scale.size() != 3)
            return invalid("node", index, "scale must have 3 values");
        if (!allFinite(node.matrix) || !allFinite(node.translation) || !allFinite(node.rotation) ||
            !allFinite(node.scale))
            return invalid("node", index, "transform is not finite");
        if (node.rotation.size() == 4) {
            double len2 = 0.0;
            for (double q : node.rotation)
                len2 += q * q;
            if (len2 < 1e-12)
                return invalid("node", index, "rotation is not a unit quaternion");
        }
    }
    // With at most one parent per node, a loop is a cycle of parent links with no root; walk up
    // from every node, marking nodes already known to reach a root.
    std::vector<std::uint8_t> state(count, 0); // 0 unknown, 1 on the current walk, 2 reaches a root
    std::vector<std::size_t> walk;
    for (std::size_t start = 0; start < count; ++start) {
        walk.clear();
        std::size_t at = start;
        while (true) {
            if (state[at] == 2)
                break;
            if (state[at] == 1)
                return invalid("node", static_cast<int>(at), "loop through its children");
            state[at] = 1;
            walk.push_back(at);
            if (parents[at] == -1)
                break;
            at = static_cast<std::size_t>(parents[at]);
        }
        for (std::size_t n : walk)
            state[n] = 2;
    }
    return Status::ok();
}

/** Every accessor's bufferView references resolve (ranges are checked only for the accessors
 *  the importer reads, in checkPrimitive/checkInstancing). */
Status checkAccessorReferences(const tinygltf::Model& model) {
    for (std::size_t i = 0; i < model.accessors.size(); ++i) {
        const tinygltf::Accessor& accessor = model.accessors[i];
        const int index = static_cast<int>(i);
        if (accessor.bufferView != -1 && !inRange(accessor.bufferView, model.bufferViews))
            return invalid(
                    "accessor",
                    index,
                    "bufferView " + std::to_string(accessor.bufferView) + " does not exist");
        if (accessor.sparse.isSparse) {
            for (int view :
                 {accessor.sparse.indices.bufferView, accessor.sparse.values.bufferView}) {
                if (!inRange(view, model.bufferViews))
                    return invalid(
                            "accessor",
                            index,
                            "sparse bufferView " + std::to_string(view) + " does not exist");
            }
        }
    }
    return Status::ok();
}

Status checkInstancing(const tinygltf::Model& model) {
    for (std::size_t i = 0; i < model.nodes.size(); ++i) {
        const tinygltf::Node& node = model.nodes[i];
        const auto ext = node.extensions.find(std::string(kInstancingExtension));
        if (ext == node.extensions.end())
            continue;
        const int index = static_cast<int>(i);
        const std::string prefix = std::string(kInstancingExtension) + ": ";
        const tinygltf::Value& attributes = ext->second.Get("attributes");
        if (!attributes.IsObject())
            return invalid("node", index, prefix + "attributes must be an object");
        std::size_t count = 0;
        for (const auto& [name, value] : attributes.Get<tinygltf::Value::Object>()) {
            if (!value.IsInt())
                return invalid("node", index, prefix + name + " must be an accessor index");
            const int accessor = value.Get<int>();
            FF_RETURN_IF_ERROR(
                    checkAccessor(model, accessor).withContext("node " + std::to_string(index)));
            const tinygltf::Accessor& a = model.accessors[static_cast<std::size_t>(accessor)];
            const int expectedType = name == "ROTATION" ? TINYGLTF_TYPE_VEC4 : TINYGLTF_TYPE_VEC3;
            if ((name == "TRANSLATION" || name == "ROTATION" || name == "SCALE") &&
                a.type != expectedType)
                return invalid("node", index, prefix + name + " has the wrong accessor type");
            if (count != 0 && a.count != count)
                return invalid("node", index, prefix + "attributes have different counts");
            count = a.count;
        }
    }
    return Status::ok();
}

Status checkAttributeType(
        const std::string& where, const std::string& name, const tinygltf::Accessor& accessor) {
    auto fail = [&](const char* what) {
        return Status{ErrorCode::InvalidInput, where + ": " + name + " " + what};
    };
    if (name == "POSITION" || name == "NORMAL") {
        if (accessor.type != TINYGLTF_TYPE_VEC3)
            return fail("must be VEC3");
    } else if (name == "COLOR_0") {
        if (accessor.type != TINYGLTF_TYPE_VEC3 && accessor.type != TINYGLTF_TYPE_VEC4)
            return fail("must be VEC3 or VEC4");
    } else if (name.rfind("TEXCOORD_", 0) == 0) {
        if (accessor.type != TINYGLTF_TYPE_VEC2)
            return fail("must be VEC2");
    }
    return Status::ok();
}

Status checkPrimitive(
        const tinygltf::Model& model,
        const tinygltf::Primitive& primitive,
        const std::string& where) {
    if (primitive.mode < TINYGLTF_MODE_POINTS || primitive.mode > TINYGLTF_MODE_TRIANGLE_FAN)
        return {ErrorCode::InvalidInput,
                where + ": mode " + std::to_string(primitive.mode) +
                        " is not a glTF primitive mode"};
    if (primitive.material != -1 && !inRange(primitive.material, model.materials))
        return {ErrorCode::InvalidInput,
                where + ": material " + std::to_string(primitive.material) + " does not exist"};
    const bool draco = primitive.extensions.count(kDracoExtension) != 0;
    std::size_t vertexCount = 0;
    std::string firstName;
    for (const auto& [name, accessor] : primitive.attributes) {
        if (!inRange(accessor, model.accessors))
            return {ErrorCode::InvalidInput,
                    where + ": attribute " + name + ": accessor " + std::to_string(accessor) +
                            " does not exist"};
        FF_RETURN_IF_ERROR(
                checkAccessor(model, accessor).withContext(where + ": attribute " + name));
        const tinygltf::Accessor& a = model.accessors[static_cast<std::size_t>(accessor)];
        FF_RETURN_IF_ERROR(checkAttributeType(where, name, a));
        if (firstName.empty()) {
            firstName = name;
            vertexCount = a.count;
        } else if (a.count != vertexCount) {
            return {ErrorCode::InvalidInput,
                    where + ": attribute " + name + " has " + std::to_string(a.count) +
                            " elements but " + firstName + " has " + std::to_string(vertexCount)};
        }
    }
    if (primitive.indices != -1) {
        if (!inRange(primitive.indices, model.accessors))
            return {ErrorCode::InvalidInput,
                    where + ": indices accessor " + std::to_string(primitive.indices) +
                            " does not exist"};
        const tinygltf::Accessor& a = model.accessors[static_cast<std::size_t>(primitive.indices)];
        if (a.type != TINYGLTF_TYPE_SCALAR ||
            (a.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
             a.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
             a.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT))
            return {ErrorCode::InvalidInput,
                    where + ": indices must be SCALAR uint8, uint16 or uint32"};
        if (!draco) {
            // Index values are data, but an index past the vertices would make us read out of
            // range later: check them all now, before anything reaches the sink.
            FF_ASSIGN_OR_RETURN(auto indices, readIndexAccessor(model, primitive.indices));
            for (std::size_t i = 0; i < indices.size(); ++i) {
                if (indices[i] >= vertexCount) {
                    return {ErrorCode::InvalidInput,
                            where + ": index " + std::to_string(indices[i]) + " at position " +
                                    std::to_string(i) + " >= vertex count " +
                                    std::to_string(vertexCount)};
                }
            }
        } else {
            FF_RETURN_IF_ERROR(
                    checkAccessor(model, primitive.indices).withContext(where + ": indices"));
        }
    }
    if (draco) {
        const tinygltf::Value& ext = primitive.extensions.at(kDracoExtension);
        const tinygltf::Value& view = ext.Get("bufferView");
        const tinygltf::Value& attributes = ext.Get("attributes");
        if (!view.IsInt() || !inRange(view.Get<int>(), model.bufferViews))
            return {ErrorCode::InvalidInput,
                    where + ": " + kDracoExtension + ": bufferView does not exist"};
        if (!attributes.IsObject())
            return {ErrorCode::InvalidInput,
                    where + ": " + kDracoExtension + ": attributes must be an object"};
        for (const auto& [name, id] : attributes.Get<tinygltf::Value::Object>()) {
            if (primitive.attributes.count(name) == 0)
                return {ErrorCode::InvalidInput,
                        where + ": " + kDracoExtension + ": attribute " + name +
                                " is not an attribute of the primitive"};
            if (!id.IsInt())
                return {ErrorCode::InvalidInput,
                        where + ": " + kDracoExtension + ": attribute " + name +
                                " id must be an integer"};
        }
    }
    return Status::ok();
}

Status checkMaterials(const tinygltf::Model& model) {
    for (std::size_t i = 0; i < model.materials.size(); ++i) {
        const auto& pbr = model.materials[i].pbrMetallicRoughness;
        const int index = static_cast<int>(i);
        if (pbr.baseColorFactor.size() != 4 || !allFinite(pbr.baseColorFactor))
            return invalid("material", index, "baseColorFactor must be 4 finite numbers");
        const int texture = pbr.baseColorTexture.index;
        if (texture != -1 && !inRange(texture, model.textures))
            return invalid(
                    "material",
                    index,
                    "baseColorTexture " + std::to_string(texture) + " does not exist");
        if (pbr.baseColorTexture.texCoord < 0)
            return invalid("material", index, "negative texCoord");
        FF_RETURN_IF_ERROR(baseColorInput(model, index).status());
    }
    for (std::size_t i = 0; i < model.textures.size(); ++i) {
        const tinygltf::Texture& texture = model.textures[i];
        const int index = static_cast<int>(i);
        if (texture.source != -1 && !inRange(texture.source, model.images))
            return invalid(
                    "texture",
                    index,
                    "image " + std::to_string(texture.source) + " does not exist");
        if (texture.sampler != -1 && !inRange(texture.sampler, model.samplers))
            return invalid(
                    "texture",
                    index,
                    "sampler " + std::to_string(texture.sampler) + " does not exist");
    }
    for (std::size_t i = 0; i < model.images.size(); ++i) {
        const tinygltf::Image& image = model.images[i];
        if (image.bufferView != -1 && !inRange(image.bufferView, model.bufferViews))
            return invalid(
                    "image",
                    static_cast<int>(i),
                    "bufferView " + std::to_string(image.bufferView) + " does not exist");
    }
    return Status::ok();
}

Status checkScenes(const tinygltf::Model& model, const std::vector<int>& parents) {
    if (model.defaultScene != -1 && !inRange(model.defaultScene, model.scenes))
        return {ErrorCode::InvalidInput,
                "default scene " + std::to_string(model.defaultScene) + " does not exist"};
    for (std::size_t i = 0; i < model.scenes.size(); ++i) {
        const int index = static_cast<int>(i);
        std::vector<bool> seen(model.nodes.size(), false);
        for (int node : model.scenes[i].nodes) {
            if (!inRange(node, model.nodes))
                return invalid("scene", index, "node " + std::to_string(node) + " does not exist");
            if (parents[static_cast<std::size_t>(node)] != -1)
                return invalid(
                        "scene", index, "node " + std::to_string(node) + " is not a root node");
            if (seen[static_cast<std::size_t>(node)])
                return invalid("scene", index, "node " + std::to_string(node) + " listed twice");
            seen[static_cast<std::size_t>(node)] = true;
        }
    }
    return Status::ok();
}

} // namespace

bool isSupportedRequiredExtension(std::string_view name) noexcept {
    for (std::string_view supported : kSupportedRequired) {
        if (name == supported)
            return true;
    }
    return false;
}

Status validateGltfModel(const tinygltf::Model& model) {
    for (const std::string& name : model.extensionsRequired) {
        if (!isSupportedRequiredExtension(name))
            return {ErrorCode::Unsupported, "required extension " + name + " is not supported"};
    }
    FF_RETURN_IF_ERROR(checkBufferViews(model));
    FF_RETURN_IF_ERROR(checkAccessorReferences(model));
    std::vector<int> parents;
    FF_RETURN_IF_ERROR(checkNodes(model, parents));
    FF_RETURN_IF_ERROR(checkScenes(model, parents));
    FF_RETURN_IF_ERROR(checkMaterials(model));
    for (std::size_t m = 0; m < model.meshes.size(); ++m) {
        const tinygltf::Mesh& mesh = model.meshes[m];
        for (std::size_t p = 0; p < mesh.primitives.size(); ++p) {
            const std::string where =
                    "mesh " + std::to_string(m) + " primitive " + std::to_string(p);
            FF_RETURN_IF_ERROR(checkPrimitive(model, mesh.primitives[p], where));
        }
    }
    FF_RETURN_IF_ERROR(checkInstancing(model));
    return Status::ok();
}

} // namespace ff::builder
