#pragma once

#include "OctreeBuilder.h"
#include "RunFile.h"
#include "SubtreeEncoder.h"

#include <ff/storage/SceneFormat.h>
#include <ff/storage/SceneWriter.h>
#include <ff/storage/Status.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace ff::builder {

/**
 * The chunks of a partitioned prototype, below their roots, laid out level by level across all
 * chunks: each octree level's records of every chunk in one region of node pages, and their
 * triangles in that level's geometry pages, in the order the chunks come (Morton order). So a
 * level's records and triangles fill pages across chunk boundaries, as in a prototype built in
 * one piece, and a frame that needs a few records of many chunks loads them from shared pages
 * instead of one page per chunk (docs/results/paging.md, "Chunks").
 *
 * Triangles go straight to the scene file: each level gathers its runs in an extent of up to
 * `extentBytes` and appends it to the writer when the next run would not fit, so a run never
 * crosses an extent end (pages of one extent are consecutive in the file). Records wait in
 * one spill file per level, because a record names its children's page, which is known only
 * once the level below is complete; finish() copies them into the scene file.
 * Not thread-safe; the writer must not be used by anyone else until finish() returns.
 */
class LevelRegions {
public:
    /** Record spill files go to `directory`, coded with `codec`, named after `prefix`. */
    LevelRegions(
            storage::SceneWriter& writer,
            std::filesystem::path directory,
            SpillCodec codec,
            std::string prefix,
            std::uint64_t extentBytes);

    /**
     * Places the chunk after the chunks appended before it, level by level: spills its records,
     * hands its triangles to their levels' extents (appending the full ones to the writer) and
     * frees both. The root's placedChildren and placedTriangles become region references (final
     * after finish()).
     */
    [[nodiscard]] Status append(LevelledSubtree& chunk);

    /**
     * Appends the open extents, then every level's node pages, to the writer, and removes the
     * spill files. `pagesCopied` (if set) is called after each node page with the pages written
     * so far and the total. Once it returns, absoluteChildren() and absoluteTriangles() map the
     * roots' references to pages of the scene file.
     */
    [[nodiscard]] Status finish(const std::function<void(std::uint64_t done, std::uint64_t total)>& pagesCopied = {});

    /** `ref` of a block at octree level `level`, as a page of the scene file. */
    storage::NodeRef absoluteChildren(std::uint32_t level, storage::NodeRef ref) const;
    /** `start` of a run of level `level`, as a page of the scene file. */
    TriangleSlot absoluteTriangles(std::uint32_t level, TriangleSlot start) const;

    std::uint64_t nodePages() const noexcept;
    std::uint64_t geometryPages() const noexcept;
    /** Bytes written to the spill files so far. */
    std::uint64_t spillBytes() const noexcept;

private:
    struct Region {
        Region(const std::filesystem::path& records, SpillCodec codec);
        RecordFile records;
        std::vector<std::uint32_t> pageFill; ///< records per node page; the last one is open
        std::uint64_t firstNodePage = 0;     ///< in the scene file, set by finish()
        /** The open extent: runs placed from local geometry page extentFirstPage on. */
        std::vector<storage::PackedTriangle> extent;
        std::uint32_t extentFirstPage = 0;
        /** Scene-file page of each local geometry page written so far. */
        std::vector<std::uint32_t> geometryPage;
    };

    Region& region(std::uint32_t level);
    /** Places a sibling block of `count` records; it never straddles a page end. */
    storage::NodeRef placeBlock(Region& region, std::uint32_t count);
    /** Copies a run into the level's extent, first appending the extent if the run does not
     *  fit what is left of it; returns where the run starts (local page, slot). */
    [[nodiscard]] Result<TriangleSlot> placeRun(Region& region, std::span<const storage::PackedTriangle> run);
    [[nodiscard]] Status writeExtent(Region& region);
    [[nodiscard]] Status copyNodePages(Region& region, const Region* below, const std::function<void()>& pageWritten);

    storage::SceneWriter& mWriter;
    std::filesystem::path mDirectory;
    SpillCodec mCodec;
    std::string mPrefix;
    std::uint32_t mPageSize;
    std::uint64_t mExtentTriangles; ///< capacity of an extent, whole pages
    std::vector<std::unique_ptr<Region>> mRegions; ///< by octree level
};

} // namespace ff::builder
