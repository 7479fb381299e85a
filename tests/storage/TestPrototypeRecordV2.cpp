// Format v2's prototype record: bounds, counts and the position grid its clusters use, round
// trip; every prefix, every bad field and random bit flips refused or harmless.

#include <ff/storage/PrototypeRecordV2.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

namespace ff::storage {
namespace {

PrototypeV2 makePrototype(bool byStep) {
    PrototypeV2 p;
    p.rootNode = 1234;
    p.bounds = {{-3.0f, 10.0f, 0.5f}, {5.0f, 12.0f, 4.5f}};
    auto grid = byStep ? PositionGrid::withStep(p.bounds.min, p.bounds.max, 0.001f)
                       : PositionGrid::covering(p.bounds.min, p.bounds.max, 20);
    EXPECT_TRUE(grid.isOk());
    p.grid = *grid;
    p.triangleCount = 5'000'000'000ull;
    p.nodeCount = 77;
    return p;
}

std::vector<std::byte> encoded(const PrototypeV2& p) {
    std::vector<std::byte> bytes(kPrototypeRecordV2Size);
    EXPECT_TRUE(encodePrototypeV2(p, bytes).isOk());
    return bytes;
}

TEST(PrototypeRecordV2Test, RoundTripsItsGridAndCounts) {
    for (const bool byStep : {false, true}) {
        const PrototypeV2 p = makePrototype(byStep);
        const auto back = decodePrototypeV2(encoded(p));
        ASSERT_TRUE(back.isOk()) << back.status().toString();
        EXPECT_EQ(back->rootNode, p.rootNode);
        EXPECT_EQ(back->bounds, p.bounds);
        EXPECT_EQ(back->grid.origin, p.grid.origin);
        EXPECT_EQ(back->grid.step, p.grid.step);
        EXPECT_EQ(back->grid.bits, p.grid.bits);
        EXPECT_EQ(back->triangleCount, p.triangleCount);
        EXPECT_EQ(back->nodeCount, p.nodeCount);
        // One coordinate, one float: the decoded grid puts a vertex where the encoder's did.
        EXPECT_EQ(back->grid.position({123, 456, 789}), p.grid.position({123, 456, 789}));
    }
}

TEST(PrototypeRecordV2Test, EveryPrefixIsRefused) {
    const std::vector<std::byte> bytes = encoded(makePrototype(false));
    for (std::size_t size = 0; size < bytes.size(); ++size) {
        const auto cut = decodePrototypeV2(std::span(bytes).first(size));
        ASSERT_FALSE(cut.isOk()) << size;
        EXPECT_EQ(cut.status().code(), ErrorCode::Corrupt);
    }
}

TEST(PrototypeRecordV2Test, EachBadFieldIsRefused) {
    const std::vector<std::byte> good = encoded(makePrototype(false));
    const auto with = [&](std::size_t offset, auto value) {
        std::vector<std::byte> bytes = good;
        std::memcpy(bytes.data() + offset, &value, sizeof(value));
        return decodePrototypeV2(bytes);
    };
    EXPECT_FALSE(with(4, std::uint8_t{0}).isOk());  // 0 grid bits
    EXPECT_FALSE(with(4, std::uint8_t{32}).isOk()); // 32 grid bits
    EXPECT_FALSE(with(5, std::uint8_t{1}).isOk());  // reserved
    EXPECT_FALSE(with(8, NAN).isOk());              // bounds
    EXPECT_FALSE(with(20, -100.0f).isOk());         // max below min
    EXPECT_FALSE(with(32, INFINITY).isOk());        // grid origin
    EXPECT_FALSE(with(32, 0.0f).isOk());            // origin above the bounds' min x (-3)
    EXPECT_FALSE(with(44, 0.0f).isOk());            // no step
    EXPECT_FALSE(with(44, -1.0f).isOk());
    EXPECT_FALSE(with(44, 1e-9f).isOk()); // a cube too small for the bounds
    const auto message = with(44, 1e-9f).status().message();
    EXPECT_NE(message.find("does not hold the bounds"), std::string::npos) << message;

    PrototypeV2 p = makePrototype(false);
    p.grid.step /= 4; // the grid no longer covers the bounds: the writer refuses it too
    std::vector<std::byte> out(kPrototypeRecordV2Size);
    EXPECT_EQ(encodePrototypeV2(p, out).code(), ErrorCode::InvalidArgument);
}

TEST(PrototypeRecordV2Test, RandomBitFlipsAreRefusedOrStillConsistent) {
    const std::vector<std::byte> good = encoded(makePrototype(true));
    std::mt19937 random(3);
    int refused = 0;
    for (int trial = 0; trial < 3000; ++trial) {
        std::vector<std::byte> bytes = good;
        for (int f = 0; f < 1 + static_cast<int>(random() % 3); ++f)
            bytes[random() % bytes.size()] ^= static_cast<std::byte>(1u << (random() % 8));
        const auto p = decodePrototypeV2(bytes);
        if (!p.isOk()) {
            ++refused;
            continue;
        }
        // Accepted: a usable grid that holds the bounds.
        ASSERT_GE(p->grid.bits, 1);
        ASSERT_LE(p->grid.bits, kMaxPositionGridBits);
        ASSERT_GT(p->grid.step, 0.0f);
        for (std::size_t a = 0; a < 3; ++a) {
            ASSERT_LE(p->bounds.min[a], p->bounds.max[a]);
            ASSERT_LE(p->grid.origin[a], p->bounds.min[a]);
        }
    }
    EXPECT_GT(refused, 0);
    EXPECT_LT(refused, 3000); // flips in the counts and the root are the caller's to check
}

} // namespace
} // namespace ff::storage
