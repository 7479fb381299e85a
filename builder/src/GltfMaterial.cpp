#include "GltfMaterial.h"

#include <cmath>
#include <sstream>

namespace ff::builder {

namespace {

Status invalidTransform(int material, const std::string& what) {
    return {ErrorCode::InvalidInput,
            "material " + std::to_string(material) + ": " + kTextureTransformExtension + " " +
                    what};
}

/** The extension's `key`: absent leaves `out` as it is; else it must be `size` finite numbers. */
Status readNumbers(
        const tinygltf::Value& extension,
        const char* key,
        std::size_t size,
        double* out,
        int material) {
    if (!extension.Has(key))
        return Status::ok();
    const tinygltf::Value& value = extension.Get(key);
    const auto finiteNumber = [](const tinygltf::Value& v) {
        return v.IsNumber() && std::isfinite(v.GetNumberAsDouble());
    };
    if (size == 1) {
        if (!finiteNumber(value))
            return invalidTransform(material, std::string(key) + " must be a finite number");
        out[0] = value.GetNumberAsDouble();
        return Status::ok();
    }
    if (!value.IsArray() || value.ArrayLen() != size)
        return invalidTransform(
                material, std::string(key) + " must be " + std::to_string(size) + " numbers");
    for (std::size_t i = 0; i < size; ++i) {
        if (!finiteNumber(value.Get(static_cast<int>(i))))
            return invalidTransform(material, std::string(key) + " must be finite numbers");
        out[i] = value.Get(static_cast<int>(i)).GetNumberAsDouble();
    }
    return Status::ok();
}

} // namespace

glm::vec2 UvTransform::apply(glm::vec2 uv) const noexcept {
    const double c = std::cos(rotation);
    const double s = std::sin(rotation);
    const double u = scale.x * static_cast<double>(uv.x);
    const double v = scale.y * static_cast<double>(uv.y);
    return {static_cast<float>(c * u + s * v + offset.x),
            static_cast<float>(-s * u + c * v + offset.y)};
}

bool UvTransform::isIdentity() const noexcept {
    return offset == glm::dvec2(0.0) && rotation == 0.0 && scale == glm::dvec2(1.0);
}

Result<BaseColorInput> baseColorInput(const tinygltf::Model& model, int material) {
    BaseColorInput input;
    if (material < 0)
        return input;
    const tinygltf::Material& m = model.materials[static_cast<std::size_t>(material)];
    const auto& pbr = m.pbrMetallicRoughness;
    for (int c = 0; c < 4; ++c)
        input.factor[c] = static_cast<float>(pbr.baseColorFactor[static_cast<std::size_t>(c)]);
    input.unlit = m.extensions.count(kUnlitExtension) != 0;
    input.texture = pbr.baseColorTexture.index;
    input.texCoord = pbr.baseColorTexture.texCoord;
    const auto transform = pbr.baseColorTexture.extensions.find(kTextureTransformExtension);
    if (input.texture < 0 || transform == pbr.baseColorTexture.extensions.end())
        return input;
    const tinygltf::Value& extension = transform->second;
    if (!extension.IsObject())
        return invalidTransform(material, "must be an object");
    double offset[2] = {0.0, 0.0};
    double scale[2] = {1.0, 1.0};
    FF_RETURN_IF_ERROR(readNumbers(extension, "offset", 2, offset, material));
    FF_RETURN_IF_ERROR(
            readNumbers(extension, "rotation", 1, &input.uvTransform.rotation, material));
    FF_RETURN_IF_ERROR(readNumbers(extension, "scale", 2, scale, material));
    input.uvTransform.offset = {offset[0], offset[1]};
    input.uvTransform.scale = {scale[0], scale[1]};
    if (extension.Has("texCoord")) {
        const tinygltf::Value& texCoord = extension.Get("texCoord");
        if (!texCoord.IsInt() || texCoord.Get<int>() < 0)
            return invalidTransform(material, "texCoord must be a non-negative integer");
        input.texCoord = texCoord.Get<int>();
    }
    return input;
}

std::string baseColorKey(const BaseColorInput& input) {
    std::ostringstream key;
    key.precision(17);
    key << "c";
    for (int c = 0; c < 4; ++c)
        key << ' ' << input.factor[c];
    key << " t" << input.texture << ',' << input.texCoord;
    if (input.texture >= 0 && !input.uvTransform.isIdentity()) {
        const UvTransform& t = input.uvTransform;
        key << " uv" << t.offset.x << ',' << t.offset.y << ',' << t.rotation << ',' << t.scale.x
            << ',' << t.scale.y;
    }
    if (input.unlit)
        key << " unlit";
    return key.str();
}

} // namespace ff::builder
