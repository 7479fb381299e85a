#pragma once

#include "OctreeBuilder.h"
#include "RunFile.h"
#include "SubtreeEncoder.h"

#include <ff/storage/SceneFormat.h>
#include <ff/storage/SceneWriter.h>
#include <ff/storage/Status.h>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace ff::builder {

/**
 * The chunks of a partitioned prototype, below their crowns, laid out level by level across all
 * chunks: one region of node pages and one of geometry pages per octree level, each holding
 * that level of every chunk in the order the chunks come (Morton order). So a level's records
 * and triangles fill pages across chunk boundaries, as in a prototype built in one piece, and a
 * frame that needs a few records of many chunks loads them from shared pages instead of one
 * page per chunk (docs/results/paging.md, "Chunks").
 *
 * Chunks are placed as they are appended and spilled to one record file and one triangle file
 * per level; writeTo() copies the regions into the scene file and makes the page numbers final.
 * Not thread-safe.
 */
class LevelRegions {
public:
    /** Spill files go to `directory`, named after `prefix`. */
    LevelRegions(std::filesystem::path directory, std::string prefix, std::uint32_t pageSize);

    /**
     * Places the chunk after the chunks appended before it, level by level, writes its records
     * and triangles out and frees them. The crown's placedChildren and placedTriangles become
     * pages of their level's region (final after writeTo()).
     */
    [[nodiscard]] Status append(LevelledSubtree& chunk);

    /**
     * Appends every level's geometry pages, then every level's node pages, to `writer`, and
     * removes the spill files. Once it returns, absoluteChildren() and absoluteTriangles() map
     * crown references to pages of the scene file.
     */
    [[nodiscard]] Status writeTo(storage::SceneWriter& writer);

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
        Region(const std::filesystem::path& records, const std::filesystem::path& triangles);
        RecordFile records;
        RunFile triangles;
        std::vector<std::uint32_t> pageFill; ///< records per node page; the last one is open
        std::uint64_t triangleCount = 0;
        std::uint64_t firstNodePage = 0;     ///< in the scene file, set by writeTo()
        std::uint64_t firstGeometryPage = 0; ///< in the scene file, set by writeTo()
    };

    Region& region(std::uint32_t level);
    /** Places a sibling block of `count` records; it never straddles a page end. */
    storage::NodeRef placeBlock(Region& region, std::uint32_t count);
    TriangleSlot triangleSlot(std::uint64_t index) const;
    [[nodiscard]] Status copyNodePages(Region& region, const Region* below, storage::SceneWriter& writer);

    std::filesystem::path mDirectory;
    std::string mPrefix;
    std::uint32_t mPageSize;
    std::vector<std::unique_ptr<Region>> mRegions; ///< by octree level
};

} // namespace ff::builder
