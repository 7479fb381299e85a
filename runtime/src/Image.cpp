#include <ff/runtime/Image.h>
#include <ff/storage/VertexCodec.h>

namespace ff::runtime {

Image resolveFramebuffer(const std::vector<std::uint8_t>& samples, int width, int height, int factor,
                         const glm::vec3& backgroundLinear) {
    Image image;
    image.width = width;
    image.height = height;
    image.rgba.resize(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 4);
    const int sampleWidth = width * factor;
    const float norm = 1.0f / static_cast<float>(factor * factor);
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            glm::vec4 sum(0.0f);
            for (int sy = 0; sy < factor; ++sy) {
                for (int sx = 0; sx < factor; ++sx) {
                    const auto index = (static_cast<std::size_t>(y * factor + sy) * static_cast<std::size_t>(sampleWidth) +
                                        static_cast<std::size_t>(x * factor + sx)) * 4;
                    sum += glm::vec4(storage::srgb8ToLinear(samples[index]), storage::srgb8ToLinear(samples[index + 1]),
                                     storage::srgb8ToLinear(samples[index + 2]), samples[index + 3] / 255.0f);
                }
            }
            sum *= norm;
            const glm::vec3 color = glm::vec3(sum) + (1.0f - sum.a) * backgroundLinear;
            std::uint8_t* out = image.pixel(x, height - 1 - y); // GL rows run bottom-up
            out[0] = storage::linearToSrgb8(color.r);
            out[1] = storage::linearToSrgb8(color.g);
            out[2] = storage::linearToSrgb8(color.b);
            out[3] = storage::toUnorm8(sum.a);
        }
    }
    return image;
}

} // namespace ff::runtime
