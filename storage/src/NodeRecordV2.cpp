#include <ff/storage/NodeRecordV2.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <string>

namespace ff::storage {

namespace {

// The record's layout (FORMAT.md §5.3).
struct PackedNodeV2 {
    std::array<std::array<std::uint8_t, 4>, 6> cube; // 0
    std::uint64_t bounds;                            // 24: 6 x 10 bits, min xyz then max xyz; octant
    std::uint32_t firstChild;                        // 32
    float subtreeTriangles;                          // 36
    std::uint32_t firstRepresentation;               // 40
    std::uint8_t childCount;                         // 44
    std::uint8_t representationCount;                // 45
    std::uint8_t kind;                               // 46
    std::uint8_t flags;                              // 47
};
static_assert(sizeof(PackedNodeV2) == kNodeRecordV2Size);
static_assert(offsetof(PackedNodeV2, bounds) == 24 && offsetof(PackedNodeV2, firstChild) == 32);
/** Bits 60-62 of `bounds`: the node's octant of its parent's cell (kNodeV2OctantCell). */
constexpr unsigned kOctantShift = 60;

struct PackedRepresentation {
    std::uint8_t kind;
    std::uint8_t flags;
    std::uint16_t count;
    std::uint32_t page;
    std::uint32_t offset;
    std::uint32_t length;
    float parameter;
};
static_assert(sizeof(PackedRepresentation) == kRepresentationRecordSize);

/** Step q of [lo, hi]: computed in double, rounded once, the same in encoder and decoder. */
float boundAt(float lo, float hi, std::uint32_t q) noexcept {
    if (q == 0)
        return lo;
    if (q == kNodeBoundsSteps)
        return hi;
    return static_cast<float>(lo + (double{hi} - lo) * q / kNodeBoundsSteps);
}

/** Where `value` lies in steps of [lo, hi], rounded by `round` into [0, 1023]: the search's start.
 */
std::uint32_t firstGuess(float lo, float hi, float value, double (*round)(double)) noexcept {
    const double extent = double{hi} - lo;
    if (!(extent > 0.0))
        return 0;
    return static_cast<std::uint32_t>(std::clamp(
            round((value - lo) / extent * kNodeBoundsSteps), 0.0, double{kNodeBoundsSteps}));
}

/** The largest step at or below `value` (the box's min), the first of its float. */
std::uint32_t stepBelow(float lo, float hi, float value) noexcept {
    std::uint32_t q = firstGuess(lo, hi, value, std::floor);
    while (q > 0 && boundAt(lo, hi, q) > value)
        --q;
    while (q < kNodeBoundsSteps && boundAt(lo, hi, q + 1) <= value)
        ++q;
    // Where steps round to one float (a parent far from the origin), the first step of that
    // float: a box's min step then never passes its max step.
    while (q > 0 && boundAt(lo, hi, q - 1) == boundAt(lo, hi, q))
        --q;
    return q;
}

/** The smallest step at or above `value` (the box's max). */
std::uint32_t stepAbove(float lo, float hi, float value) noexcept {
    std::uint32_t q = firstGuess(lo, hi, value, std::ceil);
    while (q < kNodeBoundsSteps && boundAt(lo, hi, q) < value)
        ++q;
    while (q > 0 && boundAt(lo, hi, q - 1) >= value)
        --q;
    return q;
}

bool finiteBox(const NodeBox& b) noexcept {
    for (std::size_t a = 0; a < 3; ++a)
        if (!std::isfinite(b.min[a]) || !std::isfinite(b.max[a]) || b.min[a] > b.max[a])
            return false;
    return true;
}

Status corrupt(const std::string& what) {
    return Status(ErrorCode::Corrupt, "node record v2: " + what);
}

} // namespace

Result<NodeBox> quantizeBoundsOutward(const NodeBox& box, const NodeBox& parent) {
    if (!finiteBox(box) || !finiteBox(parent))
        return Status(ErrorCode::InvalidArgument, "node bounds must be finite, ordered boxes");
    NodeBox out;
    for (std::size_t a = 0; a < 3; ++a) {
        if (box.min[a] < parent.min[a] || box.max[a] > parent.max[a])
            return Status(ErrorCode::InvalidArgument, "a node's bounds reach outside its parent's");
        out.min[a] = boundAt(
                parent.min[a], parent.max[a], stepBelow(parent.min[a], parent.max[a], box.min[a]));
        out.max[a] = boundAt(
                parent.min[a], parent.max[a], stepAbove(parent.min[a], parent.max[a], box.max[a]));
    }
    return out;
}

Status encodeNodeV2(const NodeV2& node, const NodeBox& parent, std::span<std::byte> out) {
    if (out.size() < kNodeRecordV2Size)
        return Status(ErrorCode::InvalidArgument, "node record v2 needs 48 bytes");
    if (!finiteBox(node.bounds) || !finiteBox(parent))
        return Status(ErrorCode::InvalidArgument, "node bounds must be finite, ordered boxes");
    if ((node.flags & ~kKnownNodeV2Flags) != 0 || node.kind > NodeKindV2::Instance)
        return Status(ErrorCode::InvalidArgument, "unknown node kind or flags");
    if (node.octant > 7 || (node.octant != 0 && (node.flags & kNodeV2OctantCell) == 0))
        return Status(ErrorCode::InvalidArgument, "an octant is 0-7, and 0 on a node without an octant cell");
    if (!std::isfinite(node.subtreeTriangles) || node.subtreeTriangles < 0.0f)
        return Status(ErrorCode::InvalidArgument, "subtree triangles must be a finite count");
    PackedNodeV2 p{};
    p.cube = node.cube;
    for (std::size_t a = 0; a < 3; ++a) {
        if (node.bounds.min[a] < parent.min[a] || node.bounds.max[a] > parent.max[a])
            return Status(ErrorCode::InvalidArgument, "a node's bounds reach outside its parent's");
        const std::uint64_t lo = stepBelow(parent.min[a], parent.max[a], node.bounds.min[a]);
        const std::uint64_t hi = stepAbove(parent.min[a], parent.max[a], node.bounds.max[a]);
        p.bounds |= lo << (10 * a) | hi << (10 * (a + 3));
    }
    p.bounds |= std::uint64_t{node.octant} << kOctantShift;
    p.firstChild = node.firstChild;
    p.subtreeTriangles = node.subtreeTriangles;
    p.firstRepresentation = node.firstRepresentation;
    p.childCount = node.childCount;
    p.representationCount = node.representationCount;
    p.kind = static_cast<std::uint8_t>(node.kind);
    p.flags = node.flags;
    std::memcpy(out.data(), &p, sizeof p);
    return Status::ok();
}

Result<NodeV2> decodeNodeV2(std::span<const std::byte> bytes, const NodeBox& parent) {
    if (bytes.size() < kNodeRecordV2Size)
        return corrupt("truncated (" + std::to_string(bytes.size()) + " of 48 bytes)");
    if (!finiteBox(parent))
        return Status(
                ErrorCode::InvalidArgument, "the parent's bounds must be a finite, ordered box");
    PackedNodeV2 p;
    std::memcpy(&p, bytes.data(), sizeof p);
    if (p.kind > static_cast<std::uint8_t>(NodeKindV2::Instance))
        return corrupt("unknown kind " + std::to_string(p.kind));
    if ((p.flags & ~kKnownNodeV2Flags) != 0)
        return corrupt("unknown flags " + std::to_string(p.flags));
    if ((p.bounds >> 63) != 0)
        return corrupt("reserved bound bit set");
    const auto octant = static_cast<std::uint8_t>(p.bounds >> kOctantShift & 7u);
    if (octant != 0 && (p.flags & kNodeV2OctantCell) == 0)
        return corrupt("an octant on a node without an octant cell");
    if (!std::isfinite(p.subtreeTriangles) || p.subtreeTriangles < 0.0f)
        return corrupt("subtree triangle count is not a finite count");
    NodeV2 node;
    for (std::size_t a = 0; a < 3; ++a) {
        const auto lo = static_cast<std::uint32_t>(p.bounds >> (10 * a) & 0x3ff);
        const auto hi = static_cast<std::uint32_t>(p.bounds >> (10 * (a + 3)) & 0x3ff);
        if (lo > hi || hi > kNodeBoundsSteps)
            return corrupt("empty bounds on axis " + std::to_string(a));
        node.bounds.min[a] = boundAt(parent.min[a], parent.max[a], lo);
        node.bounds.max[a] = boundAt(parent.min[a], parent.max[a], hi);
    }
    node.cube = p.cube;
    node.firstChild = p.firstChild;
    node.subtreeTriangles = p.subtreeTriangles;
    node.firstRepresentation = p.firstRepresentation;
    node.childCount = p.childCount;
    node.representationCount = p.representationCount;
    node.kind = static_cast<NodeKindV2>(p.kind);
    node.flags = p.flags;
    node.octant = octant;
    return node;
}

namespace {

/** A stand-in is clusters (simplified) or splats, with an error >= 0; splats are only ever a
 *  subtree's stand-in (a kind's other uses are not defined yet). */
bool standInRuleHolds(RepresentationKind kind, std::uint8_t flags, float parameter) noexcept {
    const bool standIn = (flags & kRepresentationStandIn) != 0;
    if (kind == RepresentationKind::Splats)
        return standIn && parameter >= 0.0f;
    return !standIn || (kind == RepresentationKind::Clusters && parameter >= 0.0f);
}

} // namespace

Status encodeRepresentation(const RepresentationRecord& r, std::span<std::byte> out) {
    if (out.size() < kRepresentationRecordSize)
        return Status(ErrorCode::InvalidArgument, "a representation record needs 20 bytes");
    if (r.kind < RepresentationKind::Clusters || r.kind > RepresentationKind::VisibleSet ||
        (r.flags & ~kKnownRepresentationFlags) != 0 || !std::isfinite(r.parameter))
        return Status(
                ErrorCode::InvalidArgument,
                "unknown representation kind or flags, or a non-finite parameter");
    if (!standInRuleHolds(r.kind, r.flags, r.parameter))
        return Status(
                ErrorCode::InvalidArgument,
                "a stand-in is clusters or splats with an error of at least 0, and splats are "
                "always a stand-in");
    const PackedRepresentation p{
            static_cast<std::uint8_t>(r.kind),
            r.flags,
            r.count,
            r.page,
            r.offset,
            r.length,
            r.parameter};
    std::memcpy(out.data(), &p, sizeof p);
    return Status::ok();
}

Result<RepresentationRecord> decodeRepresentation(std::span<const std::byte> bytes) {
    if (bytes.size() < kRepresentationRecordSize)
        return Status(
                ErrorCode::Corrupt,
                "representation record: truncated (" + std::to_string(bytes.size()) +
                        " of 20 bytes)");
    PackedRepresentation p;
    std::memcpy(&p, bytes.data(), sizeof p);
    if (p.kind < static_cast<std::uint8_t>(RepresentationKind::Clusters) ||
        p.kind > static_cast<std::uint8_t>(RepresentationKind::VisibleSet))
        return Status(
                ErrorCode::Corrupt,
                "representation record: unknown kind " + std::to_string(p.kind));
    if ((p.flags & ~kKnownRepresentationFlags) != 0)
        return Status(
                ErrorCode::Corrupt,
                "representation record: unknown flags " + std::to_string(p.flags));
    if (!std::isfinite(p.parameter))
        return Status(ErrorCode::Corrupt, "representation record: non-finite parameter");
    if (!standInRuleHolds(static_cast<RepresentationKind>(p.kind), p.flags, p.parameter))
        return Status(
                ErrorCode::Corrupt,
                "representation record: a stand-in that is not clusters or splats or has a "
                "negative error, or splats that are not a stand-in");
    return RepresentationRecord{
            static_cast<RepresentationKind>(p.kind),
            p.flags,
            p.count,
            p.page,
            p.offset,
            p.length,
            p.parameter};
}

} // namespace ff::storage
