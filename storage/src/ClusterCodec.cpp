#include <ff/storage/Assert.h>
#include <ff/storage/ClusterCodec.h>
#include <ff/storage/VertexCodec.h>

#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <mutex>
#include <string>

namespace ff::storage {

namespace {

// The header that starts every cluster (FORMAT.md, "Cluster encoding").
struct ClusterHeader {
    std::uint8_t vertexCount;
    std::uint8_t flags;
    std::uint16_t triangleCount;
    std::uint16_t vertexStreamBytes;
    std::uint16_t indexStreamBytes;
    std::array<std::uint32_t, 3> base; ///< grid coordinate the narrow deltas start from (wide: 0)
};
static_assert(sizeof(ClusterHeader) == 20);

inline constexpr std::uint8_t kClusterWidePositions = 1u << 0;
/** A point cluster (splats): no triangles and no index stream. */
inline constexpr std::uint8_t kClusterPoints = 1u << 1;
inline constexpr std::uint8_t kKnownClusterFlags = kClusterWidePositions | kClusterPoints;

// Vertices as the vertex codec sees them. Sizes are multiples of 4, as the codec requires;
// the padding is zero, which the codec stores in next to nothing.
struct NarrowVertex {
    std::array<std::uint16_t, 3> delta; ///< coordinate - header.base
    std::array<std::int16_t, 2> normal; ///< 12-bit octahedral code
    std::array<std::uint8_t, 4> color;
    std::uint16_t zero;
};
static_assert(sizeof(NarrowVertex) == 16);

struct WideVertex {
    std::array<std::uint32_t, 3> coordinate;
    std::array<std::int16_t, 2> normal;
    std::array<std::uint8_t, 4> color;
};
static_assert(sizeof(WideVertex) == 20);

// The codec versions the format pins: the first byte of each stream is 0xa0 | version (vertex)
// and 0xe0 | version (index). meshoptimizer 0.18 writes vertex version 0 and, when told, index
// version 1; a newer encoder could default to versions 0.18 cannot read, so the versions are
// set here and checked when read.
inline constexpr std::uint8_t kVertexStreamHeader = 0xa0;
inline constexpr std::uint8_t kIndexStreamHeader = 0xe1;

void pinCodecVersions() {
    static std::once_flag once;
    std::call_once(once, [] {
        meshopt_encodeVertexVersion(0);
        meshopt_encodeIndexVersion(1);
    });
}

constexpr std::int16_t kUnlitCode12 = -2048; // kUnlitNormalOct's code: outside ±2047
constexpr std::int32_t kMaxCode12 = (1 << (kClusterNormalBits - 1)) - 1;

std::int16_t toCode12(std::int16_t snorm16) noexcept {
    const double scaled =
            static_cast<double>(std::max<std::int16_t>(snorm16, -32767)) * kMaxCode12 / 32767.0;
    return static_cast<std::int16_t>(std::lround(scaled));
}

std::int16_t fromCode12(std::int16_t code) noexcept {
    // round(code · 32767 / 2047), half away from zero, in integers (the decoder's inner loop):
    // 2047 and 32767 are coprime, so no code but ±2047 lands on a half, and those are exact.
    const std::int32_t scaled = std::int32_t{code} * 32767;
    return static_cast<std::int16_t>((scaled + (scaled >= 0 ? 1023 : -1023)) / kMaxCode12);
}

std::array<std::int16_t, 2> encodeNormal12(std::array<std::int16_t, 2> oct) noexcept {
    if (isUnlitNormal(oct))
        return {kUnlitCode12, kUnlitCode12};
    return {toCode12(oct[0]), toCode12(oct[1])};
}

/** fromCode12 of every code in [-2047, 2047], for the decoder's inner loop. */
const std::array<std::int16_t, 2 * kMaxCode12 + 1>& snorm16OfCode12() {
    static const auto table = [] {
        std::array<std::int16_t, 2 * kMaxCode12 + 1> t{};
        for (std::int32_t c = -kMaxCode12; c <= kMaxCode12; ++c)
            t[static_cast<std::size_t>(c + kMaxCode12)] = fromCode12(static_cast<std::int16_t>(c));
        return t;
    }();
    return table;
}

std::array<std::int16_t, 2> decodeNormal12(std::array<std::int16_t, 2> code) noexcept {
    if (code[0] == kUnlitCode12 && code[1] == kUnlitCode12)
        return kUnlitNormalOct;
    // Codes outside [-2047, 2047] (garbage; a lone -2048) read as the nearest valid one.
    const auto& table = snorm16OfCode12();
    const auto at = [&](std::int16_t c) {
        return table[static_cast<std::size_t>(
                std::clamp<std::int32_t>(c, -kMaxCode12, kMaxCode12) + kMaxCode12)];
    };
    return {at(code[0]), at(code[1])};
}

// In double, where step · coordinate and the sum are exact to far below a float's precision,
// rounded once to float. Every reader decodes a coordinate with this function (inlined here
// into the decoder's loop, compiled once with -ffp-contract=off), so a vertex two clusters
// share decodes to one float.
inline std::array<float, 3>
dequantize(const PositionGrid& grid, std::array<std::uint32_t, 3> coordinate) noexcept {
    const double step = grid.step;
    return {static_cast<float>(grid.origin[0] + step * coordinate[0]),
            static_cast<float>(grid.origin[1] + step * coordinate[1]),
            static_cast<float>(grid.origin[2] + step * coordinate[2])};
}

/** Largest extent of finite, ordered bounds. */
Result<float> checkedExtent(std::array<float, 3> boundsMin, std::array<float, 3> boundsMax) {
    float extent = 0.0f;
    for (std::size_t a = 0; a < 3; ++a) {
        if (!std::isfinite(boundsMin[a]) || !std::isfinite(boundsMax[a]) ||
            boundsMax[a] < boundsMin[a])
            return Status(
                    ErrorCode::InvalidArgument, "position grid over empty or non-finite bounds");
        extent = std::max(extent, boundsMax[a] - boundsMin[a]);
    }
    return extent;
}

Status corrupt(const std::string& what) {
    return Status(ErrorCode::Corrupt, "cluster: " + what);
}

} // namespace

Result<PositionGrid>
PositionGrid::covering(std::array<float, 3> boundsMin, std::array<float, 3> boundsMax, int bits) {
    if (bits < 1 || bits > kMaxPositionGridBits)
        return Status(
                ErrorCode::InvalidArgument,
                "position grid bits must be 1-" + std::to_string(kMaxPositionGridBits) + ", not " +
                        std::to_string(bits));
    FF_ASSIGN_OR_RETURN(const float extent, checkedExtent(boundsMin, boundsMax));
    PositionGrid grid;
    grid.origin = boundsMin;
    grid.bits = bits;
    const double steps = static_cast<double>((std::uint32_t{1} << bits) - 1);
    // Grown by a part in 2^20 so that the far corner rounds into the grid, not past it.
    grid.step = extent > 0.0f ? static_cast<float>(extent * (1.0 + 0x1p-20) / steps) : 1.0f;
    if (!std::isfinite(grid.step) || !(grid.step > 0.0f))
        return Status(ErrorCode::InvalidArgument, "position grid step is not a positive float");
    return grid;
}

Result<PositionGrid>
PositionGrid::withStep(std::array<float, 3> boundsMin, std::array<float, 3> boundsMax, float step) {
    if (!std::isfinite(step) || !(step > 0.0f))
        return Status(ErrorCode::InvalidArgument, "position grid step must be a positive number");
    FF_ASSIGN_OR_RETURN(const float extent, checkedExtent(boundsMin, boundsMax));
    const double steps = std::ceil(static_cast<double>(extent) / step) + 1.0;
    int bits = 1;
    while (bits <= kMaxPositionGridBits && static_cast<double>(std::uint32_t{1} << bits) < steps)
        ++bits;
    if (bits > kMaxPositionGridBits)
        return Status(
                ErrorCode::InvalidArgument,
                "a position grid step of " + std::to_string(step) + " over an extent of " +
                        std::to_string(extent) + " needs more than " +
                        std::to_string(kMaxPositionGridBits) + " bits");
    PositionGrid grid;
    grid.origin = boundsMin;
    grid.step = step;
    grid.bits = bits;
    return grid;
}

std::array<std::uint32_t, 3> PositionGrid::quantize(std::array<float, 3> position) const noexcept {
    const double top = static_cast<double>((std::uint32_t{1} << bits) - 1);
    std::array<std::uint32_t, 3> coordinate{};
    for (std::size_t a = 0; a < 3; ++a) {
        const double units = (static_cast<double>(position[a]) - origin[a]) / step;
        // NaN compares false everywhere: it lands on 0.
        coordinate[a] = static_cast<std::uint32_t>(
                units > 0.0 ? std::min(std::nearbyint(units), top) : 0.0);
    }
    return coordinate;
}

std::array<float, 3>
PositionGrid::position(std::array<std::uint32_t, 3> coordinate) const noexcept {
    return dequantize(*this, coordinate);
}

float PositionGrid::maxError() const noexcept {
    // The farthest position the grid can decode, on any axis: its rounding to float is the
    // largest.
    double largest = 0.0;
    for (std::size_t a = 0; a < 3; ++a) {
        const double top = double{origin[a]} + double{step} * double(std::uint32_t{1} << bits);
        largest = std::max({largest, std::fabs(double{origin[a]}), std::fabs(top)});
    }
    // Half a step of quantization, and the one rounding of the double result to float (the
    // double arithmetic's own error is ~2^-29 of that).
    return static_cast<float>(0.5 * step + largest * 0x1p-24 * (1.0 + 0x1p-20));
}

std::array<std::int16_t, 2> roundNormalTo12Bits(std::array<std::int16_t, 2> oct) noexcept {
    return decodeNormal12(encodeNormal12(oct));
}

std::size_t encodedClusterBound(std::size_t vertexCount, std::size_t triangleCount) noexcept {
    return sizeof(ClusterHeader) +
           meshopt_encodeVertexBufferBound(vertexCount, sizeof(WideVertex)) +
           (triangleCount == 0 ? 0 : meshopt_encodeIndexBufferBound(triangleCount * 3, vertexCount));
}

namespace {

/** Either kind of cluster: triangles (`points` false, 1-512 of them) or points (no indices). */
Result<std::size_t> encodeAnyCluster(
        std::span<const ClusterVertex> vertices,
        std::span<const std::uint8_t> indices,
        bool points,
        std::span<std::byte> out) {
    if (vertices.empty() || vertices.size() > kMaxClusterVertices)
        return Status(
                ErrorCode::InvalidArgument,
                "a cluster holds 1-255 vertices, not " + std::to_string(vertices.size()));
    if (indices.size() % 3 != 0 || indices.size() / 3 > kMaxClusterTriangles || (indices.empty() && !points))
        return Status(
                ErrorCode::InvalidArgument,
                "a cluster holds 1-512 triangles, 3 indices each, not " +
                        std::to_string(indices.size()) + " indices");
    if (out.size() < encodedClusterBound(vertices.size(), indices.size() / 3))
        return Status(
                ErrorCode::InvalidArgument, "cluster output smaller than encodedClusterBound()");
    std::array<std::uint32_t, 3> lo{~0u, ~0u, ~0u};
    std::array<std::uint32_t, 3> hi{0, 0, 0};
    for (const ClusterVertex& v : vertices)
        for (std::size_t a = 0; a < 3; ++a) {
            if (v.coordinate[a] >= (1u << kMaxPositionGridBits))
                return Status(ErrorCode::InvalidArgument, "cluster coordinate beyond 2^31");
            lo[a] = std::min(lo[a], v.coordinate[a]);
            hi[a] = std::max(hi[a], v.coordinate[a]);
        }
    std::array<std::uint32_t, kMaxClusterTriangles * 3> wideIndices{};
    for (std::size_t i = 0; i < indices.size(); ++i) {
        if (indices[i] >= vertices.size())
            return Status(ErrorCode::InvalidArgument, "cluster index past its vertices");
        wideIndices[i] = indices[i];
    }
    const bool wide = hi[0] - lo[0] > 0xffff || hi[1] - lo[1] > 0xffff || hi[2] - lo[2] > 0xffff;
    pinCodecVersions();

    ClusterHeader header{};
    header.vertexCount = static_cast<std::uint8_t>(vertices.size());
    header.flags = static_cast<std::uint8_t>((wide ? kClusterWidePositions : 0) | (points ? kClusterPoints : 0));
    header.triangleCount = static_cast<std::uint16_t>(indices.size() / 3);
    header.base = wide ? std::array<std::uint32_t, 3>{0, 0, 0} : lo;

    auto* const streams = reinterpret_cast<unsigned char*>(out.data() + sizeof(ClusterHeader));
    const std::size_t room = out.size() - sizeof(ClusterHeader);
    std::size_t vertexBytes = 0;
    if (wide) {
        std::array<WideVertex, kMaxClusterVertices> packed{};
        for (std::size_t i = 0; i < vertices.size(); ++i)
            packed[i] = {
                    vertices[i].coordinate,
                    encodeNormal12(vertices[i].normalOct),
                    vertices[i].color};
        vertexBytes = meshopt_encodeVertexBuffer(
                streams, room, packed.data(), vertices.size(), sizeof(WideVertex));
    } else {
        std::array<NarrowVertex, kMaxClusterVertices> packed{};
        for (std::size_t i = 0; i < vertices.size(); ++i) {
            const auto& c = vertices[i].coordinate;
            packed[i] = {
                    {static_cast<std::uint16_t>(c[0] - lo[0]),
                     static_cast<std::uint16_t>(c[1] - lo[1]),
                     static_cast<std::uint16_t>(c[2] - lo[2])},
                    encodeNormal12(vertices[i].normalOct),
                    vertices[i].color,
                    0};
        }
        vertexBytes = meshopt_encodeVertexBuffer(
                streams, room, packed.data(), vertices.size(), sizeof(NarrowVertex));
    }
    const std::size_t indexBytes =
            points ? 0
                   : meshopt_encodeIndexBuffer(
                             streams + vertexBytes, room - vertexBytes, wideIndices.data(), indices.size());
    if (vertexBytes == 0 || (indexBytes == 0 && !points) || vertexBytes > 0xffff || indexBytes > 0xffff)
        return Status(
                ErrorCode::Internal, "meshoptimizer could not encode a cluster within its bound");
    FF_ASSERT(streams[0] == kVertexStreamHeader && (points || streams[vertexBytes] == kIndexStreamHeader));
    header.vertexStreamBytes = static_cast<std::uint16_t>(vertexBytes);
    header.indexStreamBytes = static_cast<std::uint16_t>(indexBytes);
    std::memcpy(out.data(), &header, sizeof header);
    return sizeof(ClusterHeader) + vertexBytes + indexBytes;
}

} // namespace

Result<std::size_t> encodeCluster(
        std::span<const ClusterVertex> vertices,
        std::span<const std::uint8_t> indices,
        std::span<std::byte> out) {
    return encodeAnyCluster(vertices, indices, false, out);
}

Result<std::size_t> encodePointCluster(std::span<const ClusterVertex> vertices, std::span<std::byte> out) {
    return encodeAnyCluster(vertices, {}, true, out);
}

namespace {

Result<ClusterHeader> readHeader(std::span<const std::byte> bytes) {
    if (bytes.size() < sizeof(ClusterHeader))
        return corrupt("truncated header (" + std::to_string(bytes.size()) + " bytes)");
    ClusterHeader h;
    std::memcpy(&h, bytes.data(), sizeof h);
    if (h.vertexCount == 0)
        return corrupt("no vertices");
    if ((h.flags & ~kKnownClusterFlags) != 0)
        return corrupt("unknown flags " + std::to_string(h.flags));
    const bool points = (h.flags & kClusterPoints) != 0;
    if (points ? h.triangleCount != 0 || h.indexStreamBytes != 0
               : h.triangleCount == 0 || h.triangleCount > kMaxClusterTriangles)
        return corrupt(
                std::to_string(h.triangleCount) + " triangles (" +
                (points ? "a point cluster has none and no index stream)" : "1-512)"));
    const std::size_t total =
            sizeof(ClusterHeader) + std::size_t{h.vertexStreamBytes} + h.indexStreamBytes;
    if (h.vertexStreamBytes == 0 || (h.indexStreamBytes == 0 && !points) || total > bytes.size())
        return corrupt(
                "streams of " + std::to_string(h.vertexStreamBytes) + " + " +
                std::to_string(h.indexStreamBytes) + " bytes past the " +
                std::to_string(bytes.size()) + " there are");
    const auto* streams =
            reinterpret_cast<const unsigned char*>(bytes.data() + sizeof(ClusterHeader));
    if (streams[0] != kVertexStreamHeader || (!points && streams[h.vertexStreamBytes] != kIndexStreamHeader))
        return corrupt("codec versions other than vertex 0 and index 1");
    for (std::size_t a = 0; a < 3; ++a)
        if (h.base[a] >= (1u << kMaxPositionGridBits))
            return corrupt("base coordinate beyond 2^31");
    return h;
}

std::array<std::uint32_t, 3>
coordinateOf(const NarrowVertex& v, const std::array<std::uint32_t, 3>& base) noexcept {
    return {base[0] + v.delta[0], base[1] + v.delta[1], base[2] + v.delta[2]};
}

std::array<std::uint32_t, 3>
coordinateOf(const WideVertex& v, const std::array<std::uint32_t, 3>&) noexcept {
    return v.coordinate;
}

template <typename Vertex>
Status decodeVertices(
        const ClusterHeader& h,
        const unsigned char* stream,
        const PositionGrid& grid,
        std::span<PackedVertex> out) {
    std::array<Vertex, kMaxClusterVertices> packed;
    if (meshopt_decodeVertexBuffer(
                packed.data(), h.vertexCount, sizeof(Vertex), stream, h.vertexStreamBytes) != 0)
        return corrupt("vertex stream does not decode");
    const std::uint32_t limit = 1u << std::min(grid.bits, kMaxPositionGridBits);
    // Checked once for the cluster after the loop, so the loop itself does not branch.
    std::uint32_t largest = 0;
    for (std::size_t i = 0; i < h.vertexCount; ++i) {
        const std::array<std::uint32_t, 3> c = coordinateOf(packed[i], h.base);
        largest = std::max({largest, c[0], c[1], c[2]});
        out[i] = {dequantize(grid, c), decodeNormal12(packed[i].normal), packed[i].color};
    }
    if (largest >= limit)
        return corrupt("vertex outside the position grid");
    return Status::ok();
}

} // namespace

Result<ClusterInfo> readClusterInfo(std::span<const std::byte> bytes) {
    FF_ASSIGN_OR_RETURN(const ClusterHeader h, readHeader(bytes));
    return ClusterInfo{
            h.vertexCount,
            h.triangleCount,
            static_cast<std::uint32_t>(
                    sizeof(ClusterHeader) + h.vertexStreamBytes + h.indexStreamBytes),
            (h.flags & kClusterWidePositions) != 0};
}

Status decodeCluster(
        std::span<const std::byte> bytes,
        const PositionGrid& grid,
        std::span<PackedVertex> vertices,
        std::span<std::uint8_t> indices) {
    FF_ASSIGN_OR_RETURN(const ClusterHeader h, readHeader(bytes));
    // The room given comes from a table kept apart from the cluster (a page's index, a cache's
    // copy of it): one that disagrees with the cluster's own header is corrupt, not a bug here.
    if (vertices.size() < h.vertexCount || indices.size() < std::size_t{h.triangleCount} * 3)
        return corrupt(
                "cluster of " + std::to_string(h.vertexCount) + " vertices and " +
                std::to_string(h.triangleCount) + " triangles, room for " +
                std::to_string(vertices.size()) + " and " + std::to_string(indices.size() / 3));
    const auto* streams =
            reinterpret_cast<const unsigned char*>(bytes.data() + sizeof(ClusterHeader));
    const Status decodedVertices =
            (h.flags & kClusterWidePositions) != 0
                    ? decodeVertices<WideVertex>(h, streams, grid, vertices)
                    : decodeVertices<NarrowVertex>(h, streams, grid, vertices);
    FF_RETURN_IF_ERROR(decodedVertices);
    if (h.triangleCount == 0)
        return Status::ok(); // a point cluster: vertices only
    std::array<std::uint16_t, kMaxClusterTriangles * 3> decoded;
    const std::size_t indexCount = std::size_t{h.triangleCount} * 3;
    if (meshopt_decodeIndexBuffer(
                decoded.data(),
                indexCount,
                sizeof(std::uint16_t),
                streams + h.vertexStreamBytes,
                h.indexStreamBytes) != 0)
        return corrupt("index stream does not decode");
    std::uint16_t largest = 0;
    for (std::size_t i = 0; i < indexCount; ++i) {
        largest = std::max(largest, decoded[i]);
        indices[i] = static_cast<std::uint8_t>(decoded[i]);
    }
    if (largest >= h.vertexCount)
        return corrupt(
                "index " + std::to_string(largest) + " past its " + std::to_string(h.vertexCount) +
                " vertices");
    return Status::ok();
}

} // namespace ff::storage
