#include <ff/storage/NodeRecordV2.h>

#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <vector>

namespace ff::storage {
namespace {

NodeBox randomBoxInside(const NodeBox& parent, std::mt19937& rng) {
    NodeBox b;
    for (std::size_t a = 0; a < 3; ++a) {
        std::uniform_real_distribution<float> at(parent.min[a], parent.max[a]);
        float x = at(rng);
        float y = at(rng);
        if (x > y)
            std::swap(x, y);
        b.min[a] = x;
        b.max[a] = y;
    }
    return b;
}

bool contains(const NodeBox& outer, const NodeBox& inner) {
    for (std::size_t a = 0; a < 3; ++a)
        if (inner.min[a] < outer.min[a] || inner.max[a] > outer.max[a])
            return false;
    return true;
}

NodeV2 sampleNode(const NodeBox& bounds) {
    NodeV2 n;
    n.bounds = bounds;
    for (std::size_t f = 0; f < 6; ++f)
        n.cube[f] = {static_cast<std::uint8_t>(10 * f), 20, 30, 255};
    n.firstChild = 123456789;
    n.subtreeTriangles = 1.4e10f;
    n.firstRepresentation = 4000000000u;
    n.childCount = 8;
    n.representationCount = 3;
    n.kind = NodeKindV2::Cell;
    n.flags = kNodeV2HasCube | kNodeV2Unlit;
    return n;
}

// Bounds decode outward: along a chain of 24 levels, each decoded relative to its parent's
// decoded box, every decoded box holds the true one, lies inside its decoded parent, and is
// at most a step (1/1023 of the parent's extent) larger per side. The z axis lies 10^6 from the
// origin, where deep levels' neighbouring steps round to one float.
TEST(NodeRecordV2Test, BoundsDecodeOutwardDownAChainOfLevels) {
    std::mt19937 rng(1);
    for (int chain = 0; chain < 200; ++chain) {
        NodeBox trueParent{{-1000.0f, 5.0f, 1e6f}, {3000.0f, 5.5f, 1e6f + 64.0f}};
        NodeBox decodedParent = trueParent;
        for (int level = 0; level < 24; ++level) {
            const NodeBox child = randomBoxInside(trueParent, rng);
            std::array<std::byte, kNodeRecordV2Size> bytes{};
            ASSERT_TRUE(encodeNodeV2(sampleNode(child), decodedParent, bytes).isOk());
            const auto decoded = decodeNodeV2(bytes, decodedParent);
            ASSERT_TRUE(decoded.isOk()) << decoded.status().toString();
            ASSERT_TRUE(contains(decoded->bounds, child)) << "level " << level;
            ASSERT_TRUE(contains(decodedParent, decoded->bounds)) << "level " << level;
            const auto quantized = quantizeBoundsOutward(child, decodedParent);
            ASSERT_TRUE(quantized.isOk());
            EXPECT_EQ(*quantized, decoded->bounds);
            for (std::size_t a = 0; a < 3; ++a) {
                const float step = (decodedParent.max[a] - decodedParent.min[a]) / kNodeBoundsSteps;
                EXPECT_LE(child.min[a] - decoded->bounds.min[a], step * 1.001f + 1e-3f);
                EXPECT_LE(decoded->bounds.max[a] - child.max[a], step * 1.001f + 1e-3f);
            }
            trueParent = child;
            decodedParent = decoded->bounds;
        }
    }
}

TEST(NodeRecordV2Test, EveryOtherFieldRoundTrips) {
    const NodeBox parent{{0, 0, 0}, {1, 1, 1}};
    NodeV2 n = sampleNode({{0.25f, 0.5f, 0.0f}, {0.75f, 0.5f, 1.0f}});
    n.kind = NodeKindV2::Instance;
    n.flags = static_cast<std::uint8_t>(n.flags | kNodeV2OctantCell);
    n.octant = 5;
    std::array<std::byte, kNodeRecordV2Size> bytes{};
    ASSERT_TRUE(encodeNodeV2(n, parent, bytes).isOk());
    const auto d = decodeNodeV2(bytes, parent);
    ASSERT_TRUE(d.isOk());
    EXPECT_EQ(d->octant, 5);
    EXPECT_EQ(d->cube, n.cube);
    EXPECT_EQ(d->firstChild, n.firstChild);
    EXPECT_EQ(d->subtreeTriangles, n.subtreeTriangles);
    EXPECT_EQ(d->firstRepresentation, n.firstRepresentation);
    EXPECT_EQ(d->childCount, n.childCount);
    EXPECT_EQ(d->representationCount, n.representationCount);
    EXPECT_EQ(d->kind, NodeKindV2::Instance);
    EXPECT_EQ(d->flags, n.flags);
    EXPECT_TRUE(contains(d->bounds, n.bounds));
    EXPECT_EQ(d->bounds.min[2], 0.0f); // the parent's own faces are steps: exact
    EXPECT_EQ(d->bounds.max[2], 1.0f);
}

TEST(NodeRecordV2Test, TheEncoderRefusesWhatCannotBeStoredConservatively) {
    const NodeBox parent{{0, 0, 0}, {1, 1, 1}};
    std::array<std::byte, kNodeRecordV2Size> bytes{};
    EXPECT_FALSE(encodeNodeV2(sampleNode({{-0.1f, 0, 0}, {0.5f, 1, 1}}), parent, bytes).isOk());
    EXPECT_FALSE(encodeNodeV2(sampleNode({{0, 0, 0}, {0.5f, NAN, 1}}), parent, bytes).isOk());
    NodeV2 badFlags = sampleNode(parent);
    badFlags.flags = 0x80;
    EXPECT_FALSE(encodeNodeV2(badFlags, parent, bytes).isOk());
    NodeV2 octantWithoutFlag = sampleNode(parent);
    octantWithoutFlag.octant = 3;
    EXPECT_FALSE(encodeNodeV2(octantWithoutFlag, parent, bytes).isOk());
    NodeV2 ninthOctant = sampleNode(parent);
    ninthOctant.flags = static_cast<std::uint8_t>(ninthOctant.flags | kNodeV2OctantCell);
    ninthOctant.octant = 8;
    EXPECT_FALSE(encodeNodeV2(ninthOctant, parent, bytes).isOk());
    NodeV2 badCount = sampleNode(parent);
    badCount.subtreeTriangles = INFINITY;
    EXPECT_FALSE(encodeNodeV2(badCount, parent, bytes).isOk());
    std::array<std::byte, 47> small{};
    EXPECT_FALSE(encodeNodeV2(sampleNode(parent), parent, small).isOk());
}

// A record's octant means something only with kNodeV2OctantCell: a reader refuses one without
// the flag, and the last bit of the bounds word, which nothing uses.
TEST(NodeRecordV2Test, TheReaderRefusesAnOctantWithoutItsFlagAndTheReservedBit) {
    const NodeBox parent{{0, 0, 0}, {1, 1, 1}};
    NodeV2 n = sampleNode({{0.5f, 0.5f, 0.5f}, {1, 1, 1}});
    n.flags = static_cast<std::uint8_t>(n.flags | kNodeV2OctantCell);
    n.octant = 7;
    std::array<std::byte, kNodeRecordV2Size> bytes{};
    ASSERT_TRUE(encodeNodeV2(n, parent, bytes).isOk());
    ASSERT_TRUE(decodeNodeV2(bytes, parent).isOk());
    auto withoutFlag = bytes;
    withoutFlag[47] = static_cast<std::byte>(
            std::to_integer<std::uint8_t>(withoutFlag[47]) & ~kNodeV2OctantCell);
    EXPECT_FALSE(decodeNodeV2(withoutFlag, parent).isOk());
    auto reservedBit = bytes;
    reservedBit[31] |= std::byte{0x80}; // bit 63 of the little-endian bounds word at 24
    EXPECT_FALSE(decodeNodeV2(reservedBit, parent).isOk());
}

// Every reader is memory-safe: every truncation is refused, and random bytes decode either to
// a node whose bounds lie inside the parent's or to an error.
TEST(NodeRecordV2Test, TruncationAndGarbageAreRefusedOrStayInsideTheParent) {
    const NodeBox parent{{-2, -2, -2}, {2, 2, 2}};
    std::array<std::byte, kNodeRecordV2Size> bytes{};
    ASSERT_TRUE(encodeNodeV2(sampleNode({{-1, -1, -1}, {1, 1, 1}}), parent, bytes).isOk());
    for (std::size_t n = 0; n < bytes.size(); ++n)
        EXPECT_FALSE(decodeNodeV2(std::span(bytes).first(n), parent).isOk()) << n;
    std::mt19937 rng(2);
    int refused = 0;
    for (int trial = 0; trial < 5000; ++trial) {
        for (auto& b : bytes)
            b = static_cast<std::byte>(rng());
        const auto d = decodeNodeV2(bytes, parent);
        if (!d.isOk()) {
            ++refused;
            continue;
        }
        EXPECT_TRUE(contains(parent, d->bounds));
    }
    EXPECT_GT(refused, 4000); // reserved bits, kinds and flags catch most garbage
}

TEST(NodeRecordV2Test, RepresentationRecordsRoundTripAndRefuseUnknownKinds) {
    const RepresentationRecord r{RepresentationKind::ImageLevel, 0, 17, 99, 4096, 777, 0.125f};
    std::array<std::byte, kRepresentationRecordSize> bytes{};
    ASSERT_TRUE(encodeRepresentation(r, bytes).isOk());
    const auto d = decodeRepresentation(bytes);
    ASSERT_TRUE(d.isOk());
    EXPECT_EQ(*d, r);
    for (std::size_t n = 0; n < bytes.size(); ++n)
        EXPECT_FALSE(decodeRepresentation(std::span(bytes).first(n)).isOk());
    bytes[0] = std::byte{9};
    EXPECT_FALSE(decodeRepresentation(bytes).isOk());
    bytes[0] = std::byte{1};
    bytes[1] = std::byte{2}; // an unknown flag
    EXPECT_FALSE(decodeRepresentation(bytes).isOk());
    bytes[1] = std::byte{kRepresentationStandIn};
    EXPECT_TRUE(decodeRepresentation(bytes).isOk()) << "a stand-in of clusters, error 0.125";
    bytes[0] = std::byte{2};
    EXPECT_TRUE(decodeRepresentation(bytes).isOk()) << "splats standing in, error 0.125";
    bytes[0] = std::byte{4};
    EXPECT_FALSE(decodeRepresentation(bytes).isOk()) << "only clusters and splats stand in";
    bytes[0] = std::byte{2};
    bytes[1] = std::byte{0};
    EXPECT_FALSE(decodeRepresentation(bytes).isOk()) << "splats are always a stand-in";
    RepresentationRecord splats{RepresentationKind::Splats, 0, 3, 5, 16, 200, 0.5f};
    EXPECT_FALSE(encodeRepresentation(splats, bytes).isOk());
    splats.flags = kRepresentationStandIn;
    ASSERT_TRUE(encodeRepresentation(splats, bytes).isOk());
    EXPECT_EQ(decodeRepresentation(bytes).value(), splats);
    RepresentationRecord standIn{RepresentationKind::Clusters, kRepresentationStandIn, 3, 5, 16, 200, 0.5f};
    ASSERT_TRUE(encodeRepresentation(standIn, bytes).isOk());
    EXPECT_EQ(decodeRepresentation(bytes).value(), standIn);
    EXPECT_TRUE(isStandIn(standIn));
    standIn.parameter = -0.5f; // an error below 0
    EXPECT_FALSE(encodeRepresentation(standIn, bytes).isOk());
    const float negative = -0.5f;
    std::memcpy(bytes.data() + 16, &negative, sizeof negative);
    EXPECT_FALSE(decodeRepresentation(bytes).isOk());
    RepresentationRecord nan = r;
    nan.parameter = NAN;
    EXPECT_FALSE(encodeRepresentation(nan, bytes).isOk());
}

} // namespace
} // namespace ff::storage
