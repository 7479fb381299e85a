// glTF 2.0 importer: load (GltfLoader) -> validate (GltfValidation) -> walk the scene's node
// tree collecting instance transforms and cameras -> per used mesh, one prototype whose
// triangles are streamed to the sink in batches, then its instances.
//
// Meshes whose triangles would come out identical (same primitives: mode, index and attribute
// accessors, Draco payload, and the same base colour inputs) share one prototype. Exporters
// often write one mesh per node that differ only in material properties we do not keep
// (MetalRoughSpheresNoTextures: 98 meshes over one sphere's accessors, two base colours).
//
// Vertex colour (linear RGBA) = material baseColorFactor x COLOR_0 x baseColorTexture sampled
// bilinearly at the vertex's TEXCOORD_<texCoord> (moved by KHR_texture_transform, whose texCoord
// overrides the reference's), with the texture's sampler wrap modes and its sRGB texels decoded
// to linear before filtering. KHR_materials_unlit vertices are stored unlit (GltfMaterial.h).
// A primitive without material, or a material without base colour, is white (glTF's default
// factor is 1). Normals are passed through in the
// mesh's own frame (zero when absent, so packTriangle uses the face normal). Skins and morph
// targets are ignored: meshes are taken in their rest pose, with a warning.

#include "GltfAccessors.h"
#include "GltfDraco.h"
#include "GltfLoader.h"
#include "GltfMaterial.h"
#include "GltfValidation.h"
#include "TextureSampler.h"

#include <ff/builder/GltfImporter.h>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include <cmath>
#include <exception>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace ff::builder {

namespace {

constexpr std::size_t kTriangleBatch = 4096;

bool isTriangleMode(int mode) noexcept {
    return mode == TINYGLTF_MODE_TRIANGLES || mode == TINYGLTF_MODE_TRIANGLE_STRIP ||
           mode == TINYGLTF_MODE_TRIANGLE_FAN;
}

const char* modeName(int mode) noexcept {
    switch (mode) {
    case TINYGLTF_MODE_POINTS:
        return "POINTS";
    case TINYGLTF_MODE_LINE:
        return "LINES";
    case TINYGLTF_MODE_LINE_LOOP:
        return "LINE_LOOP";
    case TINYGLTF_MODE_LINE_STRIP:
        return "LINE_STRIP";
    case TINYGLTF_MODE_TRIANGLES:
        return "TRIANGLES";
    case TINYGLTF_MODE_TRIANGLE_STRIP:
        return "TRIANGLE_STRIP";
    case TINYGLTF_MODE_TRIANGLE_FAN:
        return "TRIANGLE_FAN";
    default:
        return "unknown";
    }
}

/** Triangles a primitive declares: from the index count, else the POSITION count. */
std::uint64_t
declaredTriangles(const tinygltf::Model& model, const tinygltf::Primitive& primitive) {
    if (!isTriangleMode(primitive.mode))
        return 0;
    std::size_t n = 0;
    if (primitive.indices >= 0) {
        n = model.accessors[static_cast<std::size_t>(primitive.indices)].count;
    } else {
        const auto position = primitive.attributes.find("POSITION");
        if (position == primitive.attributes.end())
            return 0;
        n = model.accessors[static_cast<std::size_t>(position->second)].count;
    }
    if (primitive.mode == TINYGLTF_MODE_TRIANGLES)
        return n / 3;
    return n >= 3 ? n - 2 : 0;
}

bool isFinite(const glm::dmat4& m) noexcept {
    for (int c = 0; c < 4; ++c) {
        for (int r = 0; r < 4; ++r) {
            if (!std::isfinite(m[c][r]))
                return false;
        }
    }
    return true;
}

glm::dmat4 trs(const glm::dvec3& t, const glm::dquat& r, const glm::dvec3& s) {
    return glm::translate(glm::dmat4(1.0), t) * glm::mat4_cast(r) * glm::scale(glm::dmat4(1.0), s);
}

glm::dmat4 localTransform(const tinygltf::Node& node) {
    if (node.matrix.size() == 16) {
        glm::dmat4 m(1.0);
        for (int i = 0; i < 16; ++i)
            m[i / 4][i % 4] = node.matrix[static_cast<std::size_t>(i)]; // glTF is column-major
        return m;
    }
    glm::dvec3 t(0.0);
    glm::dquat r(1.0, 0.0, 0.0, 0.0);
    glm::dvec3 s(1.0);
    if (node.translation.size() == 3)
        t = {node.translation[0], node.translation[1], node.translation[2]};
    if (node.rotation.size() == 4) // glTF stores x, y, z, w
        r = glm::normalize(
                glm::dquat(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]));
    if (node.scale.size() == 3)
        s = {node.scale[0], node.scale[1], node.scale[2]};
    return trs(t, r, s);
}

glm::vec3 unitOr(const glm::dvec3& v, const glm::vec3& fallback) {
    const double len = glm::length(v);
    if (!std::isfinite(len) || len < 1e-12)
        return fallback;
    return glm::vec3(v / len);
}

GltfCamera
makeCamera(const tinygltf::Model& model, const tinygltf::Node& node, const glm::dmat4& world) {
    const tinygltf::Camera& source = model.cameras[static_cast<std::size_t>(node.camera)];
    GltfCamera camera;
    camera.name = !source.name.empty() ? source.name : node.name;
    camera.eye = glm::dvec3(world[3]);
    const glm::dmat3 basis(world);
    camera.forward = unitOr(basis * glm::dvec3(0.0, 0.0, -1.0), {0.0f, 0.0f, -1.0f});
    camera.up = unitOr(basis * glm::dvec3(0.0, 1.0, 0.0), {0.0f, 1.0f, 0.0f});
    if (source.type == "orthographic") {
        camera.perspective = false;
        camera.xmag = static_cast<float>(source.orthographic.xmag);
        camera.ymag = static_cast<float>(source.orthographic.ymag);
        camera.znear = static_cast<float>(source.orthographic.znear);
        camera.zfar = static_cast<float>(source.orthographic.zfar);
    } else {
        camera.perspective = true;
        camera.yfovRadians = static_cast<float>(source.perspective.yfov);
        camera.aspectRatio = static_cast<float>(source.perspective.aspectRatio);
        camera.znear = static_cast<float>(source.perspective.znear);
        camera.zfar = static_cast<float>(source.perspective.zfar);
    }
    return camera;
}

/**
 * A string equal for two meshes exactly when their emitted triangles are equal: every input of
 * emitPrimitive() for every primitive. Over-inclusive on purpose (all attributes, the whole
 * Draco extension object), so a collision can only cost sharing, never correctness.
 */
std::string geometryKey(const tinygltf::Model& model, const tinygltf::Mesh& mesh) {
    std::ostringstream key;
    key.precision(17);
    for (const tinygltf::Primitive& primitive : mesh.primitives) {
        key << "p" << primitive.mode << "i" << primitive.indices;
        for (const auto& [name, accessor] : primitive.attributes)
            key << ' ' << name << '=' << accessor;
        const auto draco = primitive.extensions.find(kDracoExtension);
        if (draco != primitive.extensions.end()) {
            const tinygltf::Value& ext = draco->second;
            key << " draco"
                << (ext.Get("bufferView").IsInt() ? ext.Get("bufferView").Get<int>() : -1);
            if (ext.Get("attributes").IsObject()) {
                for (const auto& [name, id] : ext.Get("attributes").Get<tinygltf::Value::Object>())
                    key << ' ' << name << '#' << (id.IsInt() ? id.Get<int>() : -1);
            }
        }
        // Validation has read every material's inputs already (validateGltfModel).
        if (const auto input = baseColorInput(model, primitive.material))
            key << ' ' << baseColorKey(*input);
        key << ';';
    }
    return key.str();
}

/** Where a mesh is drawn: its instance transforms, in order of discovery. */
struct MeshUse {
    std::vector<glm::dmat4> transforms;
    bool skinned = false;
};

/** The vertex streams of one primitive, decoded from accessors or from Draco. */
struct PrimitiveStreams {
    std::size_t vertexCount = 0;
    FloatArray positions;
    std::optional<FloatArray> normals;
    std::optional<FloatArray> colors;
    std::optional<FloatArray> texcoords; ///< the set the base colour texture asks for
    std::optional<std::vector<std::uint32_t>> indices;
};

class Importer {
public:
    Importer(const tinygltf::Model& model, ISceneSink& sink, GltfImportReport& report)
        : mModel(model)
        , mSink(sink)
        , mReport(report) {}

    Status run(const GltfImportOptions& options) {
        FF_ASSIGN_OR_RETURN(const std::vector<int> roots, sceneRoots(options));
        FF_RETURN_IF_ERROR(collect(roots));
        for (int mesh : mMeshOrder)
            FF_RETURN_IF_ERROR(importMesh(mesh, mUses.at(mesh)));
        return Status::ok();
    }

private:
    void warn(std::string message) { mReport.warnings.push_back(std::move(message)); }

    Result<std::vector<int>> sceneRoots(const GltfImportOptions& options) {
        const auto sceneCount = static_cast<int>(mModel.scenes.size());
        int scene = options.scene;
        if (scene >= 0) {
            if (scene >= sceneCount) {
                return Status{
                        ErrorCode::InvalidArgument,
                        "scene " + std::to_string(scene) + " does not exist (the file has " +
                                std::to_string(sceneCount) + ")"};
            }
        } else if (mModel.defaultScene >= 0) {
            scene = mModel.defaultScene;
        } else if (sceneCount > 0) {
            scene = 0;
        }
        if (scene >= 0)
            return mModel.scenes[static_cast<std::size_t>(scene)].nodes;
        // No scene at all: the spec leaves it to the application; draw every root node.
        warn("file has no scene; importing every root node");
        std::vector<bool> isChild(mModel.nodes.size(), false);
        for (const tinygltf::Node& node : mModel.nodes) {
            for (int child : node.children)
                isChild[static_cast<std::size_t>(child)] = true;
        }
        std::vector<int> roots;
        for (std::size_t i = 0; i < isChild.size(); ++i) {
            if (!isChild[i])
                roots.push_back(static_cast<int>(i));
        }
        return roots;
    }

    /** Walks the node trees (validated: no loops, one parent each) without recursion. */
    Status collect(const std::vector<int>& roots) {
        std::vector<std::pair<int, glm::dmat4>> stack;
        for (auto it = roots.rbegin(); it != roots.rend(); ++it)
            stack.emplace_back(*it, glm::dmat4(1.0));
        while (!stack.empty()) {
            const auto [index, parentWorld] = stack.back();
            stack.pop_back();
            const tinygltf::Node& node = mModel.nodes[static_cast<std::size_t>(index)];
            const glm::dmat4 world = parentWorld * localTransform(node);
            if (!isFinite(world))
                return invalidNode(index, "world transform is not finite");
            if (node.camera >= 0)
                mReport.cameras.push_back(makeCamera(mModel, node, world));
            if (node.mesh >= 0)
                FF_RETURN_IF_ERROR(addMeshUse(index, node, world));
            for (auto child = node.children.rbegin(); child != node.children.rend(); ++child)
                stack.emplace_back(*child, world);
        }
        return Status::ok();
    }

    static Status invalidNode(int index, const std::string& what) {
        return {ErrorCode::InvalidInput, "node " + std::to_string(index) + ": " + what};
    }

    Status addMeshUse(int index, const tinygltf::Node& node, const glm::dmat4& world) {
        auto [it, inserted] = mUses.try_emplace(node.mesh);
        if (inserted)
            mMeshOrder.push_back(node.mesh);
        MeshUse& use = it->second;
        use.skinned = use.skinned || node.skin >= 0;
        const auto ext = node.extensions.find(std::string(kInstancingExtension));
        if (ext == node.extensions.end()) {
            use.transforms.emplace_back(world);
            return Status::ok();
        }
        // EXT_mesh_gpu_instancing: the node draws its mesh once per instance, at
        // world x T x R x S of that instance, and not at its own transform.
        const tinygltf::Value& attributes = ext->second.Get("attributes");
        std::optional<FloatArray> translation;
        std::optional<FloatArray> rotation;
        std::optional<FloatArray> scale;
        std::size_t count = 0;
        for (auto [name, target] :
             {std::pair{"TRANSLATION", &translation},
              std::pair{"ROTATION", &rotation},
              std::pair{"SCALE", &scale}}) {
            const tinygltf::Value& accessor = attributes.Get(name);
            if (!accessor.IsInt())
                continue;
            FF_ASSIGN_OR_RETURN(FloatArray values, readFloatAccessor(mModel, accessor.Get<int>()));
            count = values.count;
            *target = std::move(values);
        }
        for (std::size_t i = 0; i < count; ++i) {
            const glm::dvec3 t = translation ? glm::dvec3(translation->get(i)) : glm::dvec3(0.0);
            glm::dquat r(1.0, 0.0, 0.0, 0.0);
            if (rotation) {
                const glm::dvec4 q(rotation->get(i));
                if (glm::dot(q, q) > 1e-12)
                    r = glm::normalize(glm::dquat(q.w, q.x, q.y, q.z));
            }
            const glm::dvec3 s = scale ? glm::dvec3(scale->get(i)) : glm::dvec3(1.0);
            const glm::dmat4 instance = world * trs(t, r, s);
            if (!isFinite(instance))
                return invalidNode(
                        index,
                        std::string(kInstancingExtension) + ": instance " + std::to_string(i) +
                                " transform is not finite");
            use.transforms.emplace_back(instance);
        }
        return Status::ok();
    }

    Status importMesh(int meshIndex, const MeshUse& use) {
        const tinygltf::Mesh& mesh = mModel.meshes[static_cast<std::size_t>(meshIndex)];
        const std::string meshName = "mesh " + std::to_string(meshIndex);
        bool drawable = false;
        bool morphed = false;
        for (const tinygltf::Primitive& primitive : mesh.primitives) {
            const std::uint64_t declared = declaredTriangles(mModel, primitive);
            mReport.declaredTriangles += declared * use.transforms.size();
            drawable = drawable || declared > 0;
            morphed = morphed || !primitive.targets.empty();
        }
        if (use.skinned)
            warn(meshName + ": skinned, taken in rest pose");
        if (morphed)
            warn(meshName + ": morph targets ignored, taken in rest pose");

        if (!drawable || use.transforms.empty())
            return countSkipped(mesh, meshName);
        const std::string key = geometryKey(mModel, mesh);
        if (const auto shared = mPrototypeByKey.find(key); shared != mPrototypeByKey.end())
            return addInstances(shared->second, use);

        FF_ASSIGN_OR_RETURN(
                const PrototypeId prototype,
                mSink.addPrototype(mesh.name.empty() ? meshName : mesh.name));
        mPrototypeByKey.emplace(key, prototype);
        ++mReport.prototypes;
        mBatch.clear();
        for (std::size_t p = 0; p < mesh.primitives.size(); ++p) {
            const tinygltf::Primitive& primitive = mesh.primitives[p];
            const std::string where = meshName + " primitive " + std::to_string(p);
            if (!isTriangleMode(primitive.mode)) {
                ++mReport.skippedPrimitives;
                warn(where + ": mode " + modeName(primitive.mode) + " skipped");
                continue;
            }
            if (declaredTriangles(mModel, primitive) > 0)
                FF_RETURN_IF_ERROR(emitPrimitive(prototype, primitive, where));
        }
        FF_RETURN_IF_ERROR(flush(prototype));
        return addInstances(prototype, use);
    }

    Status addInstances(PrototypeId prototype, const MeshUse& use) {
        for (const glm::dmat4& transform : use.transforms) {
            FF_RETURN_IF_ERROR(mSink.addInstance(prototype, transform));
            ++mReport.instances;
        }
        return Status::ok();
    }

    /** A mesh with nothing to draw: only its point/line primitives are reported. */
    Status countSkipped(const tinygltf::Mesh& mesh, const std::string& meshName) {
        for (std::size_t p = 0; p < mesh.primitives.size(); ++p) {
            const int mode = mesh.primitives[p].mode;
            if (!isTriangleMode(mode)) {
                ++mReport.skippedPrimitives;
                warn(meshName + " primitive " + std::to_string(p) + ": mode " + modeName(mode) +
                     " skipped");
            }
        }
        return Status::ok();
    }

    Status flush(PrototypeId prototype) {
        if (mBatch.empty())
            return Status::ok();
        FF_RETURN_IF_ERROR(mSink.addTriangles(prototype, mBatch));
        mReport.emittedTriangles += mBatch.size();
        mBatch.clear();
        return Status::ok();
    }

    /** The base colour texture of `material`, decoded on first use; null if none or broken. */
    const TextureSampler* baseColorTexture(int material, const std::string& where) {
        if (material < 0)
            return nullptr;
        const tinygltf::Material& m = mModel.materials[static_cast<std::size_t>(material)];
        const tinygltf::TextureInfo& info = m.pbrMetallicRoughness.baseColorTexture;
        if (info.index < 0)
            return nullptr;
        auto [it, inserted] = mTextures.try_emplace(info.index);
        if (!inserted)
            return it->second ? &*it->second : nullptr;
        const tinygltf::Texture& texture = mModel.textures[static_cast<std::size_t>(info.index)];
        if (texture.source < 0) {
            warn(where + ": texture " + std::to_string(info.index) +
                 " has no image; base colour texture ignored");
            return nullptr;
        }
        const tinygltf::Image& image = mModel.images[static_cast<std::size_t>(texture.source)];
        auto decoded = TextureSampler::decode(image.image);
        if (!decoded) {
            warn("texture " + std::to_string(info.index) + ": image " +
                 std::to_string(texture.source) + " not usable (" + decoded.status().message() +
                 "); base colour texture ignored");
            return nullptr;
        }
        if (texture.sampler >= 0) {
            const tinygltf::Sampler& sampler =
                    mModel.samplers[static_cast<std::size_t>(texture.sampler)];
            decoded->setWrap(wrapModeFromGltf(sampler.wrapS), wrapModeFromGltf(sampler.wrapT));
        }
        it->second = std::move(decoded).value();
        return &*it->second;
    }

    Result<std::optional<FloatArray>> readAttribute(
            const tinygltf::Primitive& primitive,
            const std::optional<DracoPrimitive>& draco,
            const std::string& name,
            std::size_t vertexCount,
            const std::string& where) {
        if (draco) {
            const auto decoded = draco->attributes.find(name);
            if (decoded != draco->attributes.end())
                return std::optional<FloatArray>(decoded->second);
        }
        const auto it = primitive.attributes.find(name);
        if (it == primitive.attributes.end())
            return std::optional<FloatArray>();
        FF_ASSIGN_OR_RETURN(FloatArray values, readFloatAccessor(mModel, it->second));
        if (values.count < vertexCount) {
            return Status{
                    ErrorCode::InvalidInput,
                    where + ": attribute " + name + " has fewer elements than the vertices"};
        }
        return std::optional<FloatArray>(std::move(values));
    }

    Result<PrimitiveStreams>
    readStreams(const tinygltf::Primitive& primitive, int texCoordSet, const std::string& where) {
        PrimitiveStreams streams;
        std::optional<DracoPrimitive> draco;
        if (primitive.extensions.count(kDracoExtension) != 0) {
            FF_ASSIGN_OR_RETURN(
                    DracoPrimitive decoded, decodeDracoPrimitive(mModel, primitive, where));
            draco = std::move(decoded);
            streams.vertexCount = draco->vertexCount;
            streams.indices = std::move(draco->indices);
        } else {
            const auto position = primitive.attributes.find("POSITION");
            streams.vertexCount =
                    mModel.accessors[static_cast<std::size_t>(position->second)].count;
            if (primitive.indices >= 0) {
                FF_ASSIGN_OR_RETURN(auto indices, readIndexAccessor(mModel, primitive.indices));
                streams.indices = std::move(indices);
            }
        }
        FF_ASSIGN_OR_RETURN(
                auto positions,
                readAttribute(primitive, draco, "POSITION", streams.vertexCount, where));
        if (!positions || positions->components != 3)
            return Status{ErrorCode::InvalidInput, where + ": POSITION missing or not VEC3"};
        streams.positions = std::move(*positions);
        FF_ASSIGN_OR_RETURN(
                streams.normals,
                readAttribute(primitive, draco, "NORMAL", streams.vertexCount, where));
        FF_ASSIGN_OR_RETURN(
                streams.colors,
                readAttribute(primitive, draco, "COLOR_0", streams.vertexCount, where));
        if (texCoordSet >= 0) {
            FF_ASSIGN_OR_RETURN(
                    streams.texcoords,
                    readAttribute(
                            primitive,
                            draco,
                            "TEXCOORD_" + std::to_string(texCoordSet),
                            streams.vertexCount,
                            where));
        }
        if (streams.indices) {
            for (std::uint32_t index : *streams.indices) {
                if (index >= streams.vertexCount) {
                    return Status{
                            ErrorCode::InvalidInput,
                            where + ": index " + std::to_string(index) + " >= vertex count " +
                                    std::to_string(streams.vertexCount)};
                }
            }
        }
        return streams;
    }

    Status emitPrimitive(
            PrototypeId prototype, const tinygltf::Primitive& primitive, const std::string& where) {
        if (primitive.attributes.count("POSITION") == 0)
            return Status::ok(); // declaredTriangles() is 0 then; kept for clarity
        FF_ASSIGN_OR_RETURN(const BaseColorInput material, baseColorInput(mModel, primitive.material));
        const TextureSampler* texture = baseColorTexture(primitive.material, where);
        const int texCoordSet = texture != nullptr ? material.texCoord : -1;
        FF_ASSIGN_OR_RETURN(PrimitiveStreams streams, readStreams(primitive, texCoordSet, where));
        if (texture != nullptr && !streams.texcoords) {
            warn(where + ": base colour texture needs TEXCOORD_" + std::to_string(texCoordSet) +
                 ", which is missing; texture ignored");
            texture = nullptr;
        }

        std::vector<SourceVertex> vertices(streams.vertexCount);
        for (std::size_t i = 0; i < vertices.size(); ++i) {
            SourceVertex& v = vertices[i];
            v.position = glm::vec3(streams.positions.get(i));
            if (streams.normals)
                v.normal = glm::vec3(streams.normals->get(i));
            glm::vec4 color = material.factor;
            if (streams.colors)
                color *= streams.colors->get(i, glm::vec4(1.0f));
            if (texture != nullptr)
                color *= texture->sample(material.uvTransform.apply(glm::vec2(streams.texcoords->get(i))));
            v.color = color;
            v.unlit = material.unlit;
        }

        // Element k of the primitive is vertex `at(k)`: through the indices, or k itself.
        const std::size_t elements =
                streams.indices ? streams.indices->size() : streams.vertexCount;
        auto at = [&](std::size_t k) -> const SourceVertex& {
            return vertices[streams.indices ? (*streams.indices)[k] : k];
        };
        // Draco always decodes to a triangle list, whatever the primitive's mode says.
        const int mode = streams.indices && primitive.extensions.count(kDracoExtension) != 0
                                 ? TINYGLTF_MODE_TRIANGLES
                                 : primitive.mode;
        auto push =
                [&](const SourceVertex& a, const SourceVertex& b, const SourceVertex& c) -> Status {
            mBatch.push_back(packTriangle(a, b, c));
            return mBatch.size() >= kTriangleBatch ? flush(prototype) : Status::ok();
        };
        if (mode == TINYGLTF_MODE_TRIANGLES) {
            for (std::size_t k = 0; k + 2 < elements; k += 3)
                FF_RETURN_IF_ERROR(push(at(k), at(k + 1), at(k + 2)));
        } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
            // glTF: triangle i = {v_i, v_{i+(1+i%2)}, v_{i+(2-i%2)}}, keeping the winding.
            for (std::size_t k = 0; k + 2 < elements; ++k) {
                const std::size_t odd = k % 2;
                FF_RETURN_IF_ERROR(push(at(k), at(k + 1 + odd), at(k + 2 - odd)));
            }
        } else {
            // TRIANGLE_FAN: triangle i = {v_{i+1}, v_{i+2}, v_0}.
            for (std::size_t k = 0; k + 2 < elements; ++k)
                FF_RETURN_IF_ERROR(push(at(k + 1), at(k + 2), at(0)));
        }
        return Status::ok();
    }

    const tinygltf::Model& mModel;
    ISceneSink& mSink;
    GltfImportReport& mReport;
    std::map<int, MeshUse> mUses;
    std::vector<int> mMeshOrder;
    std::map<int, std::optional<TextureSampler>> mTextures;
    std::map<std::string, PrototypeId> mPrototypeByKey;
    std::vector<storage::PackedTriangle> mBatch;
};

Result<GltfImportReport>
importImpl(const std::filesystem::path& path, ISceneSink& sink, const GltfImportOptions& options) {
    GltfImportReport report;
    tinygltf::Model model;
    FF_RETURN_IF_ERROR(loadGltfModel(path, model, report.warnings));
    FF_RETURN_IF_ERROR(validateGltfModel(model));
    Importer importer(model, sink, report);
    FF_RETURN_IF_ERROR(importer.run(options));
    return report;
}

} // namespace

Result<GltfImportReport>
importGltf(const std::filesystem::path& path, ISceneSink& sink, const GltfImportOptions& options) {
    // Nothing may escape: tinygltf, Draco, stb and the sink are all behind this boundary.
    try {
        auto result = importImpl(path, sink, options);
        if (!result)
            return result.status().withContext(path.filename().string());
        return result;
    } catch (const std::bad_alloc&) {
        return Status{ErrorCode::OutOfBudget, path.filename().string() + ": out of memory"};
    } catch (const std::exception& e) {
        return Status{ErrorCode::Internal, path.filename().string() + ": " + e.what()};
    } catch (...) {
        return Status{ErrorCode::Internal, path.filename().string() + ": unknown exception"};
    }
}

} // namespace ff::builder
