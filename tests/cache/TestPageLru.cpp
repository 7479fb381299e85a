#include <ff/cache/PageLru.h>

#include <gtest/gtest.h>

#include <cstdint>

namespace ff::cache {
namespace {

TEST(PageLruTest, EmptyHasNoOldest) {
    PageLru lru;
    EXPECT_EQ(lru.size(), 0u);
    EXPECT_FALSE(lru.oldest().has_value());
    EXPECT_FALSE(lru.oldestWhereNot([](std::uint64_t) { return false; }).has_value());
}

TEST(PageLruTest, OldestIsTheLeastRecentlyTouched) {
    PageLru lru;
    lru.touch(1);
    lru.touch(2);
    lru.touch(3);
    EXPECT_EQ(lru.size(), 3u);
    EXPECT_EQ(lru.oldest(), 1u);
    lru.touch(1); // now most recent
    EXPECT_EQ(lru.size(), 3u);
    EXPECT_EQ(lru.oldest(), 2u);
    EXPECT_TRUE(lru.contains(1));
    EXPECT_FALSE(lru.contains(4));
}

TEST(PageLruTest, EraseRemovesAndIgnoresAbsentPages) {
    PageLru lru;
    lru.touch(7);
    lru.touch(8);
    lru.erase(7);
    lru.erase(42);
    EXPECT_FALSE(lru.contains(7));
    EXPECT_EQ(lru.size(), 1u);
    EXPECT_EQ(lru.oldest(), 8u);
    lru.erase(8);
    EXPECT_FALSE(lru.oldest().has_value());
    lru.touch(7); // re-inserting after erase works
    EXPECT_EQ(lru.oldest(), 7u);
}

TEST(PageLruTest, OldestWhereNotSkipsFromTheOldestEnd) {
    PageLru lru;
    for (std::uint64_t page = 0; page < 5; ++page)
        lru.touch(page);
    EXPECT_EQ(lru.oldestWhereNot([](std::uint64_t p) { return p < 2; }), 2u);
    EXPECT_EQ(lru.oldestWhereNot([](std::uint64_t p) { return p % 2 == 0; }), 1u);
    EXPECT_FALSE(lru.oldestWhereNot([](std::uint64_t) { return true; }).has_value());
}

TEST(PageLruTest, ClearEmptiesEverything) {
    PageLru lru;
    lru.touch(1);
    lru.touch(2);
    lru.clear();
    EXPECT_EQ(lru.size(), 0u);
    EXPECT_FALSE(lru.contains(1));
    EXPECT_FALSE(lru.oldest().has_value());
}

} // namespace
} // namespace ff::cache
