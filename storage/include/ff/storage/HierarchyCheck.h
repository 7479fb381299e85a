#pragma once

// The deep check of a version 2 file (`farfield check`): every hierarchy walked from its root
// the way a reader walks it, so every node, representation and cluster page a reader can reach
// is known to decode. Page checksums alone cannot say that a record points where it should.

#include <ff/storage/PageSource.h>
#include <ff/storage/SceneIndex.h>
#include <ff/storage/Status.h>

#include <cstdint>
#include <functional>

namespace ff::storage {

/** What checkHierarchyV2 reached. */
struct HierarchySummary {
    std::uint64_t nodes = 0;
    std::uint64_t representations = 0;
    std::uint64_t clusters = 0;
    std::uint64_t triangles = 0;    ///< stored: each prototype's once
    std::uint64_t clusterPages = 0; ///< Geometry pages a representation names
    std::uint64_t standIns = 0;     ///< nodes with a simplified stand-in for their subtree
    std::uint64_t standInTriangles = 0; ///< theirs (not among `triangles`)
    std::uint64_t splatSets = 0;        ///< nodes with splats standing in for their subtree
    std::uint64_t splats = 0;           ///< their points
    std::uint64_t splatTriangles = 0;   ///< their triangles too large to splat
};

/**
 * Walks the instance level and every prototype of a version 2 file from their roots: each node
 * read with its parent's decoded bounds (readNodeV2), reached once (no cycles, no shared
 * children), its children inside the node slots, an Instance's index in range; each
 * representation a run of whole clusters (findClusterRun) of a Geometry page of cluster pages
 * on its own prototype's grid, every such page indexed (indexClusterPage) and decoded once;
 * the node and triangle counts of every prototype and of the header as stated. `progress`
 * gets (nodes done, node slots). Errors: Corrupt "page N: ...", InvalidArgument for a version 1
 * file, the source's errors.
 */
[[nodiscard]] Result<HierarchySummary> checkHierarchyV2(
        const SceneIndex& index,
        IPageSource& source,
        const std::function<void(std::uint64_t done, std::uint64_t total)>& progress = {});

} // namespace ff::storage
