// The names users type and read: --method, --cube-draw, bench scenarios, the HUD.

#include <ff/runtime/FrameContext.h>
#include <ff/runtime/Selection.h>

#include <array>
#include <utility>

namespace ff::runtime {

namespace {

constexpr std::array<std::pair<Method, const char*>, 2> kMethods = {{
        {Method::Hierarchical, "hierarchical"},
        {Method::Full, "full"},
}};
constexpr std::array<std::pair<CubeStyle, const char*>, 3> kCubeStyles = {{
        {CubeStyle::Auto, "auto"},
        {CubeStyle::Faces, "faces"},
        {CubeStyle::AreaWeightedPoints, "points"},
}};
constexpr std::array<std::pair<Representation, const char*>, 4> kRepresentations = {{
        {Representation::Auto, "auto"},
        {Representation::Cube, "cube"},
        {Representation::Simplified, "simplified"},
        {Representation::Splats, "splats"},
}};
constexpr std::array<std::pair<OcclusionBackend, const char*>, 2> kOcclusionBackends = {{
        {OcclusionBackend::Queries, "queries"},
        {OcclusionBackend::Hzb, "hzb"},
}};

template <typename Enum, std::size_t N>
const char* nameIn(const std::array<std::pair<Enum, const char*>, N>& table, Enum value) noexcept {
    for (const auto& [entry, name] : table) {
        if (entry == value)
            return name;
    }
    return "?";
}

template <typename Enum, std::size_t N>
std::optional<Enum>
parseIn(const std::array<std::pair<Enum, const char*>, N>& table, std::string_view text) noexcept {
    for (const auto& [entry, name] : table) {
        if (text == name)
            return entry;
    }
    return std::nullopt;
}

} // namespace

const char* methodName(Method method) noexcept {
    return nameIn(kMethods, method);
}
std::optional<Method> parseMethod(std::string_view name) noexcept {
    return parseIn(kMethods, name);
}
const char* cubeStyleName(CubeStyle style) noexcept {
    return nameIn(kCubeStyles, style);
}
std::optional<CubeStyle> parseCubeStyle(std::string_view name) noexcept {
    return parseIn(kCubeStyles, name);
}
const char* representationName(Representation representation) noexcept {
    return nameIn(kRepresentations, representation);
}
std::optional<Representation> parseRepresentation(std::string_view name) noexcept {
    return parseIn(kRepresentations, name);
}
const char* occlusionBackendName(OcclusionBackend backend) noexcept {
    return nameIn(kOcclusionBackends, backend);
}
std::optional<OcclusionBackend> parseOcclusionBackend(std::string_view name) noexcept {
    return parseIn(kOcclusionBackends, name);
}

std::vector<std::string> cubeStyleNames() {
    std::vector<std::string> names;
    for (const auto& entry : kCubeStyles)
        names.emplace_back(entry.second);
    return names;
}

} // namespace ff::runtime
