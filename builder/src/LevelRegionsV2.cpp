#include "LevelRegionsV2.h"

#include <ff/storage/Assert.h>
#include <ff/storage/NodePageV2.h>

#include <algorithm>
#include <string>

namespace ff::builder {

namespace {

// Small appends (a chunk's shallow levels) are gathered; a chunk's deep levels write through.
constexpr std::size_t kSpillBufferBytes = 64u << 10;

Result<EncodedRun> encodeRun(
        ClusterEncoder& encoder,
        std::span<const storage::PackedTriangle> run,
        const storage::PositionGrid& grid,
        std::vector<std::byte>& bytes,
        ClusterBuildStats& total) {
    EncodedRun out;
    out.offset = bytes.size();
    if (run.empty())
        return out;
    FF_ASSIGN_OR_RETURN(const ClusterBuildStats stats, encoder.encode(run, grid, bytes));
    total += stats;
    out.bytes = bytes.size() - out.offset;
    out.clusters = static_cast<std::uint32_t>(stats.clusters);
    out.kept = stats.trianglesKept;
    out.unlit = stats.trianglesUnlit;
    return out;
}

} // namespace

Result<ChunkClustersV2>
encodeChunkClusters(LevelledSubtree& chunk, const storage::PositionGrid& grid) {
    ChunkClustersV2 out;
    FF_ASSERT(chunk.levels.size() > 0);
    out.levels.resize(chunk.levels.size());
    ClusterEncoder encoder;
    for (std::size_t d = 0; d < chunk.levels.size(); ++d) {
        const LevelledSubtree::Level& level = chunk.levels[d];
        ChunkClustersV2::Level& encoded = out.levels[d];
        const auto triangles = std::span<const storage::PackedTriangle>(chunk.triangles)
                                       .subspan(level.triangleBegin, level.triangleCount);
        if (d == 0 && chunk.root.placedTriangles) {
            const auto run =
                    triangles.subspan(chunk.root.placedTriangles->slot, chunk.root.triangleCount);
            FF_ASSIGN_OR_RETURN(out.root, encodeRun(encoder, run, grid, encoded.bytes, out.stats));
        }
        encoded.runs.reserve(level.records.size());
        for (const storage::NodeRecord& record : level.records) {
            const auto run = triangles.subspan(record.geometryFirst, record.geometryCount);
            FF_ASSIGN_OR_RETURN(
                    const EncodedRun r, encodeRun(encoder, run, grid, encoded.bytes, out.stats));
            encoded.runs.push_back(r);
        }
        // A level's stand-ins after its own runs, in its bytes.
        const auto encodeLevelStandIn = [&](const std::optional<StandIn>& standIn) -> Result<EncodedRun> {
            EncodedRun r;
            r.offset = encoded.bytes.size();
            if (!standIn)
                return r;
            FF_ASSIGN_OR_RETURN(
                    const ClusterBuildStats stats, encodeStandIn(encoder, *standIn, grid, encoded.bytes));
            out.standInStats += stats;
            r.bytes = encoded.bytes.size() - r.offset;
            r.clusters = static_cast<std::uint32_t>(stats.clusters);
            r.kept = stats.trianglesKept;
            r.unlit = stats.trianglesUnlit;
            r.error = standIn->error;
            r.kind = representationKindOf(standIn->kind);
            out.standIns += r.clusters > 0 ? 1 : 0;
            return r;
        };
        if (d == 0) {
            FF_ASSIGN_OR_RETURN(out.rootStandIn, encodeLevelStandIn(chunk.rootStandIn));
        }
        if (!level.standIns.empty()) {
            encoded.standIns.reserve(level.standIns.size());
            for (const std::optional<StandIn>& standIn : level.standIns) {
                FF_ASSIGN_OR_RETURN(const EncodedRun r, encodeLevelStandIn(standIn));
                encoded.standIns.push_back(r);
            }
        }
        chunk.levels[d].standIns = std::vector<std::optional<StandIn>>();
    }
    chunk.triangles = std::vector<storage::PackedTriangle>(); // its memory, not just its elements
    chunk.rootStandIn.reset();
    return out;
}

struct LevelRegionsV2::Region {
    Region(const std::filesystem::path& path,
           SpillCodec codec,
           storage::SceneWriter& writer,
           std::uint32_t prototype)
        : records(path, codec)
        , packer(writer, prototype) {
        records.setBufferLimit(kSpillBufferBytes);
    }

    RecordFileV2 records;
    ClusterPagePacker packer;
    std::vector<storage::RepresentationRecord> representations; ///< pages local to `packer`
    std::vector<std::uint32_t> pageFill; ///< records per node page; the last one is open
    std::vector<std::uint32_t> pageReps; ///< representations per node page
    std::uint32_t count = 0;             ///< records appended: the next position
    // Set by finish():
    std::vector<std::uint32_t> pageStart;      ///< position of each page's first record
    std::uint64_t firstOrdinal = 0;            ///< of its first node page in the NodePages table
    std::vector<storage::DecodedNodeV2> parents; ///< per position, what the record is read against
};

LevelRegionsV2::LevelRegionsV2(
        storage::SceneWriter& writer,
        NodePageTable& table,
        std::filesystem::path directory,
        SpillCodec codec,
        std::string prefix,
        std::uint32_t storedPrototype)
    : mWriter(writer)
    , mTable(table)
    , mDirectory(std::move(directory))
    , mCodec(codec)
    , mPrefix(std::move(prefix))
    , mPrototype(storedPrototype) {}

LevelRegionsV2::~LevelRegionsV2() = default;

LevelRegionsV2::Region& LevelRegionsV2::region(std::uint32_t level) {
    while (mRegions.size() <= level) {
        const std::string name = mPrefix + "-level" + std::to_string(mRegions.size()) + ".nodes2";
        mRegions.push_back(
                std::make_unique<Region>(mDirectory / name, mCodec, mWriter, mPrototype));
    }
    return *mRegions[level];
}

Status LevelRegionsV2::append(LevelledSubtree& chunk, ChunkClustersV2& clusters) {
    const std::size_t depths = chunk.levels.size();
    FF_ASSERT(clusters.levels.size() == depths);
    // Where each level of this chunk starts in its region's stream of records.
    std::vector<std::uint32_t> base(depths + 1, 0);
    for (std::size_t d = 0; d <= depths; ++d)
        base[d] = region(chunk.rootLevel + static_cast<std::uint32_t>(d)).count;

    // Triangles drawn at and below each record, as stored, and how many of them are unlit:
    // from the deepest level up.
    std::vector<std::vector<double>> drawn(depths);
    std::vector<std::vector<double>> unlit(depths);
    for (std::size_t d = depths; d-- > 0;) {
        const auto& records = chunk.levels[d].records;
        drawn[d].resize(records.size());
        unlit[d].resize(records.size());
        for (std::size_t i = 0; i < records.size(); ++i) {
            drawn[d][i] = static_cast<double>(clusters.levels[d].runs[i].kept);
            unlit[d][i] = static_cast<double>(clusters.levels[d].runs[i].unlit);
            for (std::uint32_t c = 0; c < records[i].childCount; ++c) {
                drawn[d][i] += drawn.at(d + 1).at(records[i].firstChild.slot + c);
                unlit[d][i] += unlit.at(d + 1).at(records[i].firstChild.slot + c);
            }
        }
    }

    Root root;
    root.level = chunk.rootLevel;
    root.storedTriangles = clusters.root.kept;
    root.drawnTriangles = static_cast<double>(clusters.root.kept);
    root.unlitTriangles = static_cast<double>(clusters.root.unlit);
    if (chunk.root.placedChildren) {
        root.firstChild = base[1] + chunk.root.placedChildren->slot;
        root.childCount = chunk.root.childCount;
        for (std::uint32_t c = 0; c < root.childCount; ++c) {
            root.drawnTriangles += drawn.at(1).at(chunk.root.placedChildren->slot + c);
            root.unlitTriangles += unlit.at(1).at(chunk.root.placedChildren->slot + c);
        }
    }
    if (clusters.root.clusters > 0) {
        Region& r = region(chunk.rootLevel);
        const auto bytes = std::span(clusters.levels[0].bytes)
                                   .subspan(clusters.root.offset, clusters.root.bytes);
        FF_RETURN_IF_ERROR(r.packer.place(bytes, clusters.root.clusters, root.representations));
    }
    if (const EncodedRun& standIn = clusters.rootStandIn; standIn.clusters > 0) {
        Region& r = region(chunk.rootLevel);
        FF_RETURN_IF_ERROR(r.packer.placeStandIn(
                std::span(clusters.levels[0].bytes).subspan(standIn.offset, standIn.bytes),
                standIn.clusters,
                standIn.error,
                standIn.kind,
                root.representations));
    }
    root.standInSource = std::move(chunk.rootSource);
    mStandIns += clusters.standIns;
    mStandInStats += clusters.standInStats;
    {
        if (root.representations.size() > 255)
            return Status(
                    ErrorCode::Unsupported,
                    "a node needs more than 255 representations; use a larger --page-size");
    }
    // The root's own triangles are counted with the tree above, whose record the root is.

    const std::uint64_t payloadBytes = storage::pagePayloadBytes(mWriter.pageSize());
    std::vector<PendingNodeV2> pending;
    std::vector<std::uint32_t> repCount;
    for (std::size_t d = 1; d < depths; ++d) {
        const std::uint32_t levelIndex = chunk.rootLevel + static_cast<std::uint32_t>(d);
        Region& r = region(levelIndex);
        const LevelledSubtree::Level& level = chunk.levels[d];
        const ChunkClustersV2::Level& encoded = clusters.levels[d];
        pending.assign(level.records.size(), PendingNodeV2{});
        repCount.assign(level.records.size(), 0);
        // Payloads first: a block is placed with its representations.
        for (std::size_t i = 0; i < level.records.size(); ++i) {
            const EncodedRun& run = encoded.runs[i];
            const auto first = static_cast<std::uint32_t>(r.representations.size());
            if (run.clusters > 0)
                FF_RETURN_IF_ERROR(r.packer.place(
                        std::span(encoded.bytes).subspan(run.offset, run.bytes),
                        run.clusters,
                        r.representations));
            if (!encoded.standIns.empty() && encoded.standIns[i].clusters > 0) {
                const EncodedRun& standIn = encoded.standIns[i];
                FF_RETURN_IF_ERROR(r.packer.placeStandIn(
                        std::span(encoded.bytes).subspan(standIn.offset, standIn.bytes),
                        standIn.clusters,
                        standIn.error,
                        standIn.kind,
                        r.representations));
            }
            repCount[i] = static_cast<std::uint32_t>(r.representations.size()) - first;
            if (repCount[i] > 255)
                return Status(
                        ErrorCode::Unsupported,
                        "a node needs more than 255 representations; use a larger --page-size");
            const storage::NodeRecord& record = level.records[i];
            PendingNodeV2& p = pending[i];
            p.boundsMin = record.boundsMin;
            p.boundsMax = record.boundsMax;
            p.cellMin = record.cellMin;
            p.cellMax = record.cellMax;
            p.cube = record.cube;
            p.firstChild = record.childCount > 0 ? base[d + 1] + record.firstChild.slot : 0;
            p.firstRepresentation = first;
            p.drawnTriangles = static_cast<float>(drawn[d][i]);
            p.childCount = record.childCount;
            p.representationCount = static_cast<std::uint8_t>(repCount[i]);
            p.flags = static_cast<std::uint8_t>(
                    storage::kNodeV2HasCube | unlitFlag(drawn[d][i], unlit[d][i]));
            if ((record.flags & storage::kNodeOctreeChildren) != 0)
                p.flags = static_cast<std::uint8_t>(p.flags | storage::kNodeV2OctreeChildren);
            ++mNodes;
            mLeafNodes += record.childCount == 0 ? 1 : 0;
            mStoredTriangles += run.kept;
            mMaxLevel = std::max(mMaxLevel, levelIndex);
        }
        // Sibling blocks never straddle a page, and a page holds its records' representations.
        std::size_t i = 0;
        for (const std::uint8_t block : level.blocks) {
            std::uint64_t blockReps = 0;
            for (std::uint32_t k = 0; k < block; ++k)
                blockReps += repCount[i + k];
            const auto fits = [&](std::uint64_t nodes, std::uint64_t reps) {
                return storage::kNodeRecordV2Size * (nodes + block) +
                               storage::kRepresentationRecordSize * (reps + blockReps) <=
                       payloadBytes;
            };
            if (!fits(0, 0))
                return Status(
                        ErrorCode::Unsupported,
                        "a sibling block of " + std::to_string(block) + " nodes and " +
                                std::to_string(blockReps) +
                                " representations does not fit one page; use a larger --page-size");
            if (r.pageFill.empty() || !fits(r.pageFill.back(), r.pageReps.back())) {
                r.pageFill.push_back(0);
                r.pageReps.push_back(0);
            }
            r.pageFill.back() += block;
            r.pageReps.back() += static_cast<std::uint32_t>(blockReps);
            i += block;
        }
        FF_ASSERT(i == level.records.size());
        FF_RETURN_IF_ERROR(r.records.append(pending));
        r.count += static_cast<std::uint32_t>(pending.size());
    }
    mRoots.push_back(std::move(root));
    // Free the memory, not just the elements (see commitSubtree).
    chunk.levels = std::vector<LevelledSubtree::Level>();
    clusters = ChunkClustersV2{};
    return Status::ok();
}

Status LevelRegionsV2::finish(
        std::span<const storage::DecodedNodeV2> rootBoxes,
        const std::function<void(std::uint64_t done, std::uint64_t total)>& pagesWritten) {
    if (rootBoxes.size() != mRoots.size())
        return Status(ErrorCode::Internal, "a decoded box per chunk root is needed");
    for (const auto& r : mRegions)
        FF_RETURN_IF_ERROR(r->packer.finish());
    // The regions' node pages follow one another from a fresh page of the table.
    FF_RETURN_IF_ERROR(mTable.writeOpen(mWriter));
    std::uint64_t ordinal = mTable.openOrdinal();
    for (const auto& r : mRegions) {
        r->firstOrdinal = ordinal;
        ordinal += r->pageFill.size();
        r->pageStart.assign(r->pageFill.size(), 0);
        for (std::size_t p = 1; p < r->pageFill.size(); ++p)
            r->pageStart[p] = r->pageStart[p - 1] + r->pageFill[p - 1];
    }
    const std::uint64_t slotsPerPage = storage::nodesPerPageV2(mWriter.pageSize());
    if (ordinal * slotsPerPage >= 0xFFFFFFFFull)
        return Status(ErrorCode::Unsupported, "scene needs more than 2^32 node slots");

    for (std::size_t c = 0; c < mRoots.size(); ++c) {
        Root& root = mRoots[c];
        for (auto& r : root.representations)
            r = mRegions[root.level]->packer.relocated(r);
        if (root.childCount == 0)
            continue;
        Region& below = *mRegions.at(root.level + 1);
        below.parents.resize(below.count);
        for (std::uint32_t k = 0; k < root.childCount; ++k)
            below.parents[root.firstChild + k] = rootBoxes[c];
        const auto page = static_cast<std::size_t>(
                std::upper_bound(below.pageStart.begin(), below.pageStart.end(), root.firstChild) -
                below.pageStart.begin() - 1);
        root.absoluteFirstChild = static_cast<std::uint32_t>(
                (below.firstOrdinal + page) * slotsPerPage +
                (root.firstChild - below.pageStart[page]));
    }

    const std::uint64_t totalPages = nodePages();
    std::uint64_t written = 0;
    const auto pageWritten = [&] {
        if (pagesWritten)
            pagesWritten(++written, totalPages);
    };
    for (std::size_t level = 0; level < mRegions.size(); ++level)
        FF_RETURN_IF_ERROR(writeRegion(level, pageWritten));
    return Status::ok();
}

Status LevelRegionsV2::writeRegion(std::size_t level, const std::function<void()>& pageWritten) {
    Region& r = *mRegions[level];
    if (r.pageFill.empty())
        return Status::ok();
    Region* below = level + 1 < mRegions.size() ? mRegions[level + 1].get() : nullptr;
    if (below != nullptr)
        below->parents.resize(below->count);
    const std::uint64_t slotsPerPage = storage::nodesPerPageV2(mWriter.pageSize());
    const auto indexBelow = [&](std::uint32_t position) {
        const auto page = static_cast<std::size_t>(
                std::upper_bound(below->pageStart.begin(), below->pageStart.end(), position) -
                below->pageStart.begin() - 1);
        return static_cast<std::uint32_t>(
                (below->firstOrdinal + page) * slotsPerPage + (position - below->pageStart[page]));
    };

    std::vector<PendingNodeV2> pending; // read but not yet written, < 2 pages
    std::vector<storage::RepresentationRecord> reps;
    std::size_t page = 0;
    std::uint32_t position = 0;
    FF_RETURN_IF_ERROR(r.records.forEachBatch(
            slotsPerPage, [&](std::span<const PendingNodeV2> batch) -> Status {
                pending.insert(pending.end(), batch.begin(), batch.end());
                std::size_t used = 0;
                while (page < r.pageFill.size() && pending.size() - used >= r.pageFill[page]) {
                    FF_ASSERT(
                            mTable.open().empty() && mTable.openOrdinal() == r.firstOrdinal + page);
                    storage::NodePageV2Writer& out = mTable.open();
                    for (std::uint32_t i = 0; i < r.pageFill[page]; ++i, ++position) {
                        const PendingNodeV2& p = pending[used + i];
                        const storage::DecodedNodeV2& parent = r.parents.at(position);
                        storage::NodeV2 node;
                        node.cube = p.cube;
                        node.subtreeTriangles = p.drawnTriangles;
                        node.flags = p.flags;
                        FF_ASSIGN_OR_RETURN(
                                const storage::DecodedNodeV2 decoded,
                                placeUnder(
                                        node,
                                        {p.boundsMin, p.boundsMax},
                                        {p.cellMin, p.cellMax},
                                        parent));
                        if (p.childCount > 0) {
                            FF_ASSERT(below != nullptr);
                            node.firstChild = indexBelow(p.firstChild);
                            node.childCount = p.childCount;
                            for (std::uint32_t k = 0; k < p.childCount; ++k)
                                below->parents.at(p.firstChild + k) = decoded;
                        }
                        reps.clear();
                        for (std::uint32_t k = 0; k < p.representationCount; ++k)
                            reps.push_back(r.packer.relocated(
                                    r.representations.at(p.firstRepresentation + k)));
                        FF_ASSIGN_OR_RETURN(
                                const std::uint32_t slot, out.append(node, parent.bounds, reps));
                        FF_ASSERT(slot == i);
                    }
                    FF_RETURN_IF_ERROR(mTable.writeOpen(mWriter));
                    pageWritten();
                    used += r.pageFill[page];
                    ++page;
                }
                pending.erase(pending.begin(), pending.begin() + static_cast<std::ptrdiff_t>(used));
                return Status::ok();
            }));
    FF_ASSERT(page == r.pageFill.size() && pending.empty());
    r.records.remove();
    r.parents = std::vector<storage::DecodedNodeV2>();
    r.representations = std::vector<storage::RepresentationRecord>();
    return Status::ok();
}

PlacedNodeV2 LevelRegionsV2::placedRoot(std::size_t chunk, std::uint32_t node) const {
    const Root& root = mRoots.at(chunk);
    PlacedNodeV2 placed;
    placed.node = node;
    placed.firstChild = root.absoluteFirstChild;
    placed.representations = root.representations;
    placed.storedTriangles = root.storedTriangles;
    placed.drawnTriangles = root.drawnTriangles;
    placed.unlitTriangles = root.unlitTriangles;
    placed.standInSource = root.standInSource;
    return placed;
}

std::uint64_t LevelRegionsV2::nodePages() const noexcept {
    std::uint64_t pages = 0;
    for (const auto& r : mRegions)
        pages += r->pageFill.size();
    return pages;
}

std::uint64_t LevelRegionsV2::geometryPages() const noexcept {
    std::uint64_t pages = 0;
    for (const auto& r : mRegions)
        pages += r->packer.pages();
    return pages;
}

std::uint64_t LevelRegionsV2::spillBytes() const noexcept {
    std::uint64_t bytes = 0;
    for (const auto& r : mRegions)
        bytes += r->records.bytesWritten();
    return bytes;
}

} // namespace ff::builder
