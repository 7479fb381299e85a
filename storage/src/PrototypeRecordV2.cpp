#include <ff/storage/PrototypeRecordV2.h>

#include <cmath>
#include <cstring>
#include <string>

namespace ff::storage {

namespace {

// The record's layout (FORMAT.md §4.4).
struct PackedPrototypeV2 {
    std::uint32_t rootNode;               // 0
    std::uint8_t gridBits;                // 4
    std::array<std::uint8_t, 3> reserved; // 5
    std::array<float, 3> boundsMin;       // 8
    std::array<float, 3> boundsMax;       // 20
    std::array<float, 3> gridOrigin;      // 32
    float gridStep;                       // 44
    std::uint64_t triangleCount;          // 48
    std::uint64_t nodeCount;              // 56
};
static_assert(sizeof(PackedPrototypeV2) == kPrototypeRecordV2Size);

Status corrupt(const std::string& what) {
    return {ErrorCode::Corrupt, "prototype: " + what};
}

bool finite3(const std::array<float, 3>& v) noexcept {
    return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
}

/** Why the record's fields do not make a prototype a reader can use, or empty. */
std::string problemOf(const PackedPrototypeV2& r) {
    if (r.reserved != std::array<std::uint8_t, 3>{0, 0, 0})
        return "reserved bytes not 0";
    if (!finite3(r.boundsMin) || !finite3(r.boundsMax))
        return "non-finite bounds";
    for (std::size_t a = 0; a < 3; ++a)
        if (r.boundsMin[a] > r.boundsMax[a])
            return "bounds with min > max";
    if (r.gridBits < 1 || r.gridBits > kMaxPositionGridBits)
        return "grid of " + std::to_string(r.gridBits) + " bits (1-31)";
    if (!finite3(r.gridOrigin) || !std::isfinite(r.gridStep) || !(r.gridStep > 0.0f))
        return "a grid that is not finite or has no positive step";
    // The grid's cube must hold the bounds, or some vertex would be clamped.
    const double extent =
            double{r.gridStep} * static_cast<double>((std::uint64_t{1} << r.gridBits) - 1);
    for (std::size_t a = 0; a < 3; ++a)
        if (r.gridOrigin[a] > r.boundsMin[a] || double{r.gridOrigin[a]} + extent < r.boundsMax[a])
            return "a grid that does not hold the bounds";
    return {};
}

} // namespace

Status encodePrototypeV2(const PrototypeV2& p, std::span<std::byte> out) {
    if (out.size() < kPrototypeRecordV2Size)
        return {ErrorCode::InvalidArgument, "prototype record needs 64 bytes"};
    PackedPrototypeV2 r{};
    r.rootNode = p.rootNode;
    r.gridBits = static_cast<std::uint8_t>(p.grid.bits);
    r.boundsMin = p.bounds.min;
    r.boundsMax = p.bounds.max;
    r.gridOrigin = p.grid.origin;
    r.gridStep = p.grid.step;
    r.triangleCount = p.triangleCount;
    r.nodeCount = p.nodeCount;
    if (p.grid.bits < 1 || p.grid.bits > kMaxPositionGridBits)
        return {ErrorCode::InvalidArgument,
                "prototype: grid of " + std::to_string(p.grid.bits) + " bits (1-31)"};
    if (const std::string problem = problemOf(r); !problem.empty())
        return {ErrorCode::InvalidArgument, "prototype: " + problem};
    std::memcpy(out.data(), &r, sizeof(r));
    return Status::ok();
}

Result<PrototypeV2> decodePrototypeV2(std::span<const std::byte> bytes) {
    if (bytes.size() < kPrototypeRecordV2Size)
        return corrupt("truncated record (" + std::to_string(bytes.size()) + " bytes)");
    PackedPrototypeV2 r{};
    std::memcpy(&r, bytes.data(), sizeof(r));
    if (const std::string problem = problemOf(r); !problem.empty())
        return corrupt(problem);
    PrototypeV2 p;
    p.rootNode = r.rootNode;
    p.bounds = {r.boundsMin, r.boundsMax};
    p.grid.origin = r.gridOrigin;
    p.grid.step = r.gridStep;
    p.grid.bits = r.gridBits;
    p.triangleCount = r.triangleCount;
    p.nodeCount = r.nodeCount;
    return p;
}

} // namespace ff::storage
