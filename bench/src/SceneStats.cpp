#include <ff/bench/SceneStats.h>

#include <ff/builder/Generators.h>
#include <ff/builder/SceneSink.h>
#include <ff/runtime/BackToFrontTraversal.h>
#include <ff/runtime/CameraOptions.h>
#include <ff/runtime/CameraPathGenerators.h>
#include <ff/runtime/FrameStats.h>
#include <ff/runtime/PageAccess.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <string_view>
#include <unordered_map>
#include <unordered_set>

namespace ff::bench {

namespace {

using storage::NodeRecord;
using storage::NodeRef;

std::uint64_t nodeKey(NodeRef ref) {
    return (std::uint64_t{ref.page} << 32) | ref.slot;
}

bool isCell(const NodeRecord& node) {
    return node.kind == static_cast<std::uint8_t>(storage::NodeKind::Cell);
}

/** One reachable node as the walk meets it. */
struct WalkedNode {
    NodeRef ref;
    NodeRecord record;
    std::optional<NodeRef> parent; ///< the cell or instance-level node above it, if any
    bool instanceLevel = false;
};

// Every distinct node reachable from the header root (the instance level) and from each
// prototype root, depth first, each once. Instance nodes are not followed into their prototype:
// the prototype roots are walked on their own, so shared prototypes count once.
Status
walkNodes(const storage::SceneFile& scene, const std::function<Status(const WalkedNode&)>& visit) {
    std::unordered_set<std::uint64_t> seen;
    std::vector<WalkedNode> stack;
    auto push = [&](NodeRef ref, std::optional<NodeRef> parent, bool instanceLevel) -> Status {
        if (!seen.insert(nodeKey(ref)).second)
            return Status::ok();
        FF_ASSIGN_OR_RETURN(const NodeRecord record, scene.node(ref));
        stack.push_back({ref, record, parent, instanceLevel});
        return Status::ok();
    };
    auto drain = [&]() -> Status {
        while (!stack.empty()) {
            const WalkedNode node = stack.back();
            stack.pop_back();
            FF_RETURN_IF_ERROR(visit(node));
            for (std::uint32_t c = 0; c < node.record.childCount; ++c)
                FF_RETURN_IF_ERROR(
                        push(storage::SceneFile::childRef(node.record, c),
                             node.ref,
                             node.instanceLevel));
        }
        return Status::ok();
    };
    if (!(scene.header().root == storage::kNullNodeRef)) {
        FF_RETURN_IF_ERROR(push(scene.header().root, std::nullopt, true));
        FF_RETURN_IF_ERROR(drain());
    }
    for (const storage::PrototypeRecord& prototype : scene.prototypes()) {
        FF_RETURN_IF_ERROR(push(prototype.root, std::nullopt, false));
        FF_RETURN_IF_ERROR(drain());
    }
    return Status::ok();
}

LevelStats& levelOf(std::vector<LevelStats>& levels, std::uint8_t level) {
    if (levels.size() <= level)
        levels.resize(level + 1u);
    return levels[level];
}

Result<std::uint64_t> fileSize(const std::filesystem::path& file) {
    std::error_code error;
    const std::uintmax_t size = std::filesystem::file_size(file, error);
    if (error)
        return Status(ErrorCode::NotFound, file.string() + ": " + error.message());
    return static_cast<std::uint64_t>(size);
}

Result<std::string> readText(const std::filesystem::path& file, std::uint64_t maxBytes) {
    std::ifstream in(file, std::ios::binary);
    if (!in)
        return Status(ErrorCode::NotFound, file.string() + ": cannot open");
    std::string text(static_cast<std::size_t>(maxBytes), '\0');
    in.read(text.data(), static_cast<std::streamsize>(maxBytes));
    text.resize(static_cast<std::size_t>(in.gcount()));
    return text;
}

std::uint32_t readU32(const std::string& bytes, std::size_t offset) {
    std::uint32_t v = 0;
    std::memcpy(&v, bytes.data() + offset, sizeof(v));
    return v;
}

/** Byte length of bufferView `index`, or 0 if the JSON does not have it. */
std::uint64_t bufferViewBytes(const nlohmann::json& gltf, std::uint64_t index) {
    const auto views = gltf.find("bufferViews");
    if (views == gltf.end() || !views->is_array() || index >= views->size())
        return 0;
    const auto length = (*views)[index].find("byteLength");
    return length != (*views)[index].end() && length->is_number_unsigned()
                   ? length->get<std::uint64_t>()
                   : 0;
}

bool isDataUri(const std::string& uri) {
    return uri.rfind("data:", 0) == 0;
}

/** Counts what a generator passes to its sink, as an indexed mesh. */
class IndexedMeshSink final : public builder::ISceneSink {
public:
    Result<builder::PrototypeId> addPrototype(std::string_view) override {
        mVertices.emplace_back();
        return static_cast<builder::PrototypeId>(mVertices.size() - 1);
    }
    Status addTriangles(
            builder::PrototypeId prototype,
            std::span<const storage::PackedTriangle> triangles) override {
        if (prototype >= mVertices.size())
            return Status(ErrorCode::InvalidArgument, "unknown prototype");
        for (const storage::PackedTriangle& t : triangles) {
            for (const storage::PackedVertex& v : t.vertices) {
                std::string key(sizeof(v), '\0');
                std::memcpy(key.data(), &v, sizeof(v));
                mVertices[prototype].insert(std::move(key));
            }
        }
        mTriangles += triangles.size();
        return Status::ok();
    }
    Status addInstance(builder::PrototypeId, const glm::dmat4&) override {
        ++mInstances;
        return Status::ok();
    }

    std::uint64_t bytes() const {
        std::uint64_t vertices = 0;
        for (const auto& set : mVertices)
            vertices += set.size();
        return vertices * sizeof(storage::PackedVertex) + mTriangles * 3 * sizeof(std::uint32_t) +
               mInstances * 12 * sizeof(float);
    }

private:
    std::vector<std::unordered_set<std::string>> mVertices;
    std::uint64_t mTriangles = 0;
    std::uint64_t mInstances = 0;
};

class CubeRecorder final : public runtime::ISelectionObserver {
public:
    void cubeDrawn(NodeRef ref, const NodeRecord&) override {
        ++draws;
        drawn.insert(nodeKey(ref));
    }
    std::unordered_set<std::uint64_t> drawn;
    std::uint64_t draws = 0;
};

nlohmann::json levelsJson(const std::vector<LevelStats>& levels, bool withDrawn) {
    nlohmann::json out = nlohmann::json::array();
    for (const LevelStats& l : levels) {
        nlohmann::json row = {{"nodes", l.nodes}, {"with_cube", l.withCube}};
        if (withDrawn)
            row["cubes_drawn"] = l.cubesDrawn;
        out.push_back(row);
    }
    return out;
}

double ratio(std::uint64_t a, std::uint64_t b) {
    return b == 0 ? 0.0 : static_cast<double>(a) / static_cast<double>(b);
}

} // namespace

std::uint64_t SceneStats::representedBytes() const noexcept {
    return headerBytes + nodeRecordBytes + triangleBytes + prototypeRecordBytes +
           instanceRecordBytes + metadataBytes + trailerBytes + headerSlack + nodeSlack +
           geometrySlack + tableSlack + unreferencedBytes;
}

Result<SceneStats> collectSceneStats(const storage::SceneFile& scene) {
    if (scene.formatVersion() != storage::kFormatVersion)
        return Status(ErrorCode::Unsupported, "stats reads format version 1 files; `farfield check` reports a version 2 file's contents");
    FF_RETURN_IF_ERROR(scene.verifyAll());
    SceneStats s;
    const storage::FileHeader& header = scene.header();
    const std::uint32_t pageSize = scene.pageSize();
    const std::uint64_t payload = storage::pagePayloadBytes(pageSize);
    s.path = scene.path().string();
    FF_ASSIGN_OR_RETURN(s.fileBytes, fileSize(scene.path()));
    s.pageSize = pageSize;
    s.pageCount = scene.pageCount();
    s.headerNodeCount = header.nodeCount;
    s.instancedTriangles = header.instancedTriangles;
    s.prototypes = scene.prototypes().size();
    s.instances = scene.instances().size();
    const nlohmann::json metadata = nlohmann::json::parse(scene.metadataJson(), nullptr, false);
    if (metadata.is_object() && metadata.contains("source") && metadata["source"].is_string())
        s.source = metadata["source"].get<std::string>();

    // Nodes and the slots they occupy.
    std::map<std::uint64_t, std::uint64_t> nodeSlots;     // Nodes page -> used slots
    std::map<std::uint64_t, std::uint64_t> triangleSlots; // Geometry page -> used slots
    std::vector<storage::GeometrySegment> segments;
    FF_RETURN_IF_ERROR(walkNodes(scene, [&](const WalkedNode& n) -> Status {
        const NodeRecord& r = n.record;
        ++s.nodes;
        ++nodeSlots[n.ref.page];
        (n.instanceLevel ? s.instanceLevelNodes : s.prototypeNodes) += 1;
        LevelStats& level =
                levelOf(n.instanceLevel ? s.instanceLevels : s.prototypeLevels, r.level);
        ++level.nodes;
        if (r.flags & storage::kNodeHasCube) {
            ++s.nodesWithCube;
            ++level.withCube;
        }
        s.maxChildren = std::max<std::uint64_t>(s.maxChildren, r.childCount);
        if (!isCell(r)) {
            ++s.instanceNodes;
            return Status::ok();
        }
        if (r.childCount > 0) {
            ++s.innerCells;
            s.innerCellsWithTriangles += r.geometryCount > 0 ? 1 : 0;
            s.singleChildCells += r.childCount == 1 && r.geometryCount == 0 ? 1 : 0;
        } else {
            ++s.leafCells;
            s.emptyLeaves += r.geometryCount == 0 ? 1 : 0;
            s.smallLeaves += r.geometryCount > 0 && r.geometryCount < 8 ? 1 : 0;
        }
        s.storedTriangles += r.geometryCount;
        segments.clear();
        FF_RETURN_IF_ERROR(scene.geometrySegments(r, segments));
        for (const storage::GeometrySegment& segment : segments)
            triangleSlots[segment.page] += segment.count;
        return Status::ok();
    }));

    // Pages: table sections by the section table, the rest by what the nodes use.
    std::vector<bool> isTable(s.pageCount, false);
    for (const storage::SectionEntry& section : scene.sections()) {
        const auto type = static_cast<storage::SectionType>(section.type);
        if (type == storage::SectionType::Hierarchy)
            continue;
        s.tablePages += section.pageCount;
        s.tableSlack += section.pageCount * payload - section.byteLength;
        for (std::uint64_t p = section.firstPage; p < section.firstPage + section.pageCount; ++p)
            isTable[p] = true;
        if (type == storage::SectionType::Prototypes)
            s.prototypeRecordBytes = section.byteLength;
        else if (type == storage::SectionType::Instances)
            s.instanceRecordBytes = section.byteLength;
        else if (type == storage::SectionType::Metadata)
            s.metadataBytes = section.byteLength;
    }
    const std::uint64_t nodesPerPage = storage::nodesPerPage(pageSize);
    const std::uint64_t trianglesPerPage = storage::trianglesPerPage(pageSize);
    for (const auto& [page, used] : nodeSlots) {
        if (triangleSlots.contains(page) || isTable[page])
            return Status(
                    ErrorCode::Corrupt,
                    "page " + std::to_string(page) + ": used both for nodes and for other data");
        s.sparseNodePages += 4 * used < nodesPerPage ? 1 : 0;
    }
    for (const auto& [page, used] : triangleSlots) {
        if (used > trianglesPerPage || isTable[page])
            return Status(
                    ErrorCode::Corrupt, "page " + std::to_string(page) + ": triangle runs overlap");
        s.sparseGeometryPages += 4 * used < trianglesPerPage ? 1 : 0;
    }
    s.nodePages = nodeSlots.size();
    s.geometryPages = triangleSlots.size();
    s.unreferencedPages = s.pageCount - 1 - s.tablePages - s.nodePages - s.geometryPages;

    // Bytes by representation.
    s.headerBytes =
            sizeof(storage::FileHeader) + scene.sections().size() * sizeof(storage::SectionEntry);
    s.headerSlack = payload - s.headerBytes;
    s.nodeRecordBytes = s.nodes * sizeof(NodeRecord);
    s.cubeBytes = s.nodesWithCube * sizeof(NodeRecord::cube);
    s.nodeSlack = s.nodePages * payload - s.nodeRecordBytes;
    s.triangleBytes = s.storedTriangles * sizeof(storage::PackedTriangle);
    s.geometrySlack = s.geometryPages * payload - s.triangleBytes;
    s.trailerBytes = s.pageCount * sizeof(storage::PageTrailer);
    s.unreferencedBytes = s.unreferencedPages * payload;
    return s;
}

Status measureCubeUsage(
        const storage::SceneFile& scene, const CubeUsageOptions& options, SceneStats& stats) {
    const runtime::Bounds bounds = runtime::sceneBounds(scene);
    runtime::MappedPageAccess pages(scene);
    runtime::BackToFrontTraversal traversal(scene, pages);
    CubeRecorder recorder;
    runtime::FrameContext frame;
    frame.width = options.width;
    frame.height = options.height;
    frame.selection.epsilonPixels = options.epsilonPixels;
    frame.selection.observer = &recorder;
    // Only what the traversal chooses is recorded: nothing is drawn.
    runtime::DiscardingSink discard;
    runtime::NoVisibility visibility;
    runtime::AdmitAll admitAll;
    runtime::PathGeneratorOptions generator;
    generator.frames = options.framesPerPath;
    for (const std::string& kind : options.paths) {
        Result<runtime::CameraPath> path =
                Status(ErrorCode::InvalidArgument,
                       "unknown path kind " + kind + " (orbit, flythrough, teleports)");
        if (kind == "orbit")
            path = runtime::makeOrbitPath(bounds, generator);
        else if (kind == "flythrough")
            path = runtime::makeFlythroughPath(bounds, generator);
        else if (kind == "teleports")
            path = runtime::makeTeleportPath(bounds, generator);
        if (!path)
            return path.status().withContext(kind + " path");
        for (std::int64_t f = 0; f < path->frameCount(); ++f) {
            frame.camera = path->sample(path->frameTime(f));
            frame.camera.fitClipPlanes(bounds);
            runtime::FrameStats frameStats;
            FF_RETURN_IF_ERROR(traversal.traverse(frame, {discard, visibility, admitAll}, frameStats));
            if (!traversal.newFailures().empty())
                return traversal.newFailures().front();
        }
    }

    CubeUsage usage;
    usage.paths = options.paths;
    usage.framesPerPath = options.framesPerPath;
    usage.epsilonPixels = options.epsilonPixels;
    usage.width = options.width;
    usage.height = options.height;
    usage.cubeDraws = recorder.draws;
    for (LevelStats& l : stats.prototypeLevels)
        l.cubesDrawn = 0;
    for (LevelStats& l : stats.instanceLevels)
        l.cubesDrawn = 0;
    FF_RETURN_IF_ERROR(walkNodes(scene, [&](const WalkedNode& n) -> Status {
        const NodeRecord& r = n.record;
        if (!(r.flags & storage::kNodeHasCube))
            return Status::ok();
        ++usage.nodesWithCube;
        if (recorder.drawn.contains(nodeKey(n.ref))) {
            ++usage.nodesDrawn;
            ++levelOf(n.instanceLevel ? stats.instanceLevels : stats.prototypeLevels, r.level)
                      .cubesDrawn;
            return Status::ok();
        }
        ++usage.neverDrawn;
        if (!isCell(r)) {
            ++usage.neverDrawnInstance;
        } else if (r.childCount > 0) {
            ++usage.neverDrawnInner;
        } else {
            ++usage.neverDrawnLeaf;
            if (n.parent && !recorder.drawn.contains(nodeKey(*n.parent)))
                ++usage.neverDrawnLeafWithNeverDrawnParent;
        }
        return Status::ok();
    }));
    usage.neverDrawnBytes = usage.neverDrawn * sizeof(NodeRecord::cube);
    stats.cubes = usage;
    return Status::ok();
}

Result<InputSize> measureGltfInput(const std::filesystem::path& file) {
    FF_ASSIGN_OR_RETURN(const std::uint64_t size, fileSize(file));
    InputSize input;
    const bool binary = file.extension() == ".glb";
    nlohmann::json gltf;
    if (binary) {
        // GLB: 12-byte header, then the JSON chunk (length, type, bytes).
        FF_ASSIGN_OR_RETURN(const std::string head, readText(file, 20));
        if (head.size() < 20 || head.compare(0, 4, "glTF") != 0)
            return Status(ErrorCode::InvalidArgument, file.string() + ": not a GLB file");
        const std::uint32_t jsonLength = readU32(head, 12);
        if (jsonLength > size - 20)
            return Status(
                    ErrorCode::InvalidArgument,
                    file.string() + ": GLB JSON chunk runs past the file");
        FF_ASSIGN_OR_RETURN(const std::string all, readText(file, 20 + std::uint64_t{jsonLength}));
        gltf = nlohmann::json::parse(all.substr(20), nullptr, false);
    } else {
        FF_ASSIGN_OR_RETURN(const std::string all, readText(file, size));
        gltf = nlohmann::json::parse(all, nullptr, false);
    }
    if (!gltf.is_object())
        return Status(ErrorCode::InvalidArgument, file.string() + ": the glTF JSON does not parse");
    input.bytes = size;
    std::uint64_t embeddedImages = 0;
    const std::filesystem::path dir = file.parent_path();
    if (const auto buffers = gltf.find("buffers"); buffers != gltf.end() && buffers->is_array()) {
        for (const nlohmann::json& buffer : *buffers) {
            const auto uri = buffer.find("uri");
            if (uri == buffer.end() || !uri->is_string() || isDataUri(uri->get<std::string>()))
                continue;
            FF_ASSIGN_OR_RETURN(const std::uint64_t bytes, fileSize(dir / uri->get<std::string>()));
            input.bytes += bytes;
        }
    }
    if (const auto images = gltf.find("images"); images != gltf.end() && images->is_array()) {
        for (const nlohmann::json& image : *images) {
            const auto uri = image.find("uri");
            if (uri != image.end() && uri->is_string() && !isDataUri(uri->get<std::string>())) {
                FF_ASSIGN_OR_RETURN(
                        const std::uint64_t bytes, fileSize(dir / uri->get<std::string>()));
                input.imageBytes += bytes;
            } else if (const auto view = image.find("bufferView");
                       view != image.end() && view->is_number_unsigned()) {
                embeddedImages += bufferViewBytes(gltf, view->get<std::uint64_t>());
            }
        }
    }
    // Images inside a buffer (GLB, or a .bin) are counted as images, not as geometry input.
    embeddedImages = std::min(embeddedImages, input.bytes);
    input.bytes -= embeddedImages;
    input.imageBytes += embeddedImages;
    input.what = binary ? "glb file less embedded images"
                        : "gltf JSON + external buffers (images apart)";
    return input;
}

Result<InputSize> measureGeneratorInput(const std::string& spec) {
    FF_ASSIGN_OR_RETURN(const builder::GeneratorSpec parsed, builder::parseGeneratorSpec(spec));
    IndexedMeshSink sink;
    FF_ASSIGN_OR_RETURN(const builder::GeneratorReport report, builder::runGenerator(parsed, sink));
    (void)report;
    InputSize input;
    input.bytes = sink.bytes();
    input.what = "indexed mesh: 20 B per distinct vertex + 12 B per triangle per prototype, 48 B "
                 "per instance";
    return input;
}

nlohmann::json SceneStats::toJson() const {
    nlohmann::json out;
    out["scene"] = path;
    out["source"] = source;
    out["file_bytes"] = fileBytes;
    out["page_size"] = pageSize;
    out["pages"] = pageCount;
    if (input) {
        out["input"] = {
                {"bytes", input->bytes},
                {"image_bytes", input->imageBytes},
                {"counted", input->what}};
        out["file_per_input_byte"] = ratio(fileBytes, input->bytes);
    } else {
        out["input"] = nullptr;
        out["file_per_input_byte"] = nullptr;
    }
    out["nodes"] = {
            {"total", nodes},
            {"header_node_count", headerNodeCount},
            {"instance_level", instanceLevelNodes},
            {"prototype", prototypeNodes},
            {"instance", instanceNodes},
            {"inner_cell", innerCells},
            {"leaf_cell", leafCells},
            {"inner_cell_with_triangles", innerCellsWithTriangles},
            {"single_child_cell", singleChildCells},
            {"empty_leaf", emptyLeaves},
            {"small_leaf", smallLeaves},
            {"with_cube", nodesWithCube},
            {"max_children", maxChildren},
            {"per_stored_triangle", ratio(nodes, storedTriangles)},
            {"prototype_levels", levelsJson(prototypeLevels, cubes.has_value())},
            {"instance_levels", levelsJson(instanceLevels, cubes.has_value())},
    };
    out["triangles"] = {
            {"stored", storedTriangles},
            {"instanced", instancedTriangles},
            {"instanced_per_stored", ratio(instancedTriangles, storedTriangles)},
            {"prototypes", prototypes},
            {"instances", instances},
    };
    out["page_counts"] = {
            {"header", 1},
            {"nodes", nodePages},
            {"geometry", geometryPages},
            {"table", tablePages},
            {"unreferenced", unreferencedPages},
            {"sparse_nodes", sparseNodePages},
            {"sparse_geometry", sparseGeometryPages},
    };
    const std::uint64_t payload = storage::pagePayloadBytes(pageSize);
    out["page_fill"] = {
            {"nodes", ratio(nodeRecordBytes, nodePages * payload)},
            {"geometry", ratio(triangleBytes, geometryPages * payload)},
            {"table",
             ratio(prototypeRecordBytes + instanceRecordBytes + metadataBytes,
                   tablePages * payload)},
    };
    out["bytes"] = {
            {"header", headerBytes},
            {"node_records", nodeRecordBytes},
            {"cubes", cubeBytes},
            {"triangles", triangleBytes},
            {"prototype_records", prototypeRecordBytes},
            {"instance_transforms", instanceRecordBytes},
            {"metadata", metadataBytes},
            {"trailers", trailerBytes},
            {"header_slack", headerSlack},
            {"node_slack", nodeSlack},
            {"geometry_slack", geometrySlack},
            {"table_slack", tableSlack},
            {"unreferenced", unreferencedBytes},
    };
    if (cubes) {
        out["cube_usage"] = {
                {"paths", cubes->paths},
                {"frames_per_path", cubes->framesPerPath},
                {"epsilon", cubes->epsilonPixels},
                {"width", cubes->width},
                {"height", cubes->height},
                {"cube_draws", cubes->cubeDraws},
                {"nodes_with_cube", cubes->nodesWithCube},
                {"nodes_drawn", cubes->nodesDrawn},
                {"never_drawn", cubes->neverDrawn},
                {"never_drawn_bytes", cubes->neverDrawnBytes},
                {"never_drawn_instance", cubes->neverDrawnInstance},
                {"never_drawn_inner", cubes->neverDrawnInner},
                {"never_drawn_leaf", cubes->neverDrawnLeaf},
                {"never_drawn_leaf_parent_never_drawn", cubes->neverDrawnLeafWithNeverDrawnParent},
        };
    }
    return out;
}

} // namespace ff::bench
