// Compact geometry, measured on the leaves a real build makes: each scene is built in format v1
// (a child `farfield build`), every node's triangles are encoded as clusters (the codec of format
// v2, storage/ClusterCodec.h) with each variant's grid and cluster limits, and decoded again on
// one core. Beside them: the v1 file's bytes a triangle and, for glTF inputs, Draco's
// (`gltf-pipeline -d`, when it is on PATH) with its decode time through the Draco library.

#include "BenchSupport.h"

#include <ff/bench/Benchmarks.h>
#include <ff/builder/ClusterBuild.h>
#include <ff/builder/GridChoice.h>
#include <ff/storage/ClusterCodec.h>
#include <ff/storage/ClusterPage.h>
#include <ff/storage/NodeRecordV2.h>
#include <ff/storage/SceneFile.h>

#include <draco/compression/decode.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

namespace ff::bench {

namespace {

struct CodecScene {
    std::string label;
    std::string generate; ///< a generator spec, or
    std::string gltf;     ///< a glTF file
};

struct CodecVariant {
    std::string label;
    int bits = storage::kDefaultPositionGridBits;
    /** > 0: the grid's step is the hierarchy's median triangle edge / edgeSteps (as many bits
     *  as its extent then needs) instead of `bits` over the extent. */
    double edgeSteps = 0.0;
    builder::ClusterLimits limits;
    std::uint64_t leafTriangles = 0; ///< 0: the v1 leaves; else subtrees this small made one leaf
};

struct CodecParams {
    std::vector<CodecScene> scenes;
    std::vector<CodecVariant> variants;
    double decodeSeconds = 1.0;
    /** Pages the clusters are packed into for the v2 file estimate. */
    std::uint32_t pageSize = storage::kDefaultPageSize;
};

double secondsSince(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/** One hierarchy's nodes with triangles of their own, and the grid over its bounds. */
struct Hierarchy {
    storage::NodeRef root;
    std::array<float, 3> boundsMin;
    std::array<float, 3> boundsMax;
};

/** Appends `node`'s own triangles to `out`. */
Status appendOwnTriangles(
        const storage::SceneFile& file,
        const storage::NodeRecord& node,
        std::vector<storage::PackedTriangle>& out) {
    std::vector<storage::GeometrySegment> segments;
    FF_RETURN_IF_ERROR(file.geometrySegments(node, segments));
    for (const storage::GeometrySegment& s : segments) {
        FF_ASSIGN_OR_RETURN(const std::span<const std::byte> bytes, file.segmentBytes(s));
        const std::size_t first = out.size();
        out.resize(first + s.count);
        std::memcpy(
                out.data() + first,
                bytes.data(),
                std::size_t{s.count} * sizeof(storage::PackedTriangle));
    }
    return Status::ok();
}

/** Triangles in the Cell subtree of `ref` (instances not entered). */
Result<std::uint64_t> subtreeTriangles(
        const storage::SceneFile& file,
        storage::NodeRef ref,
        std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint64_t>& memo) {
    FF_ASSIGN_OR_RETURN(const storage::NodeRecord node, file.node(ref));
    if (node.kind != static_cast<std::uint8_t>(storage::NodeKind::Cell))
        return std::uint64_t{0};
    std::uint64_t total = node.geometryCount;
    for (std::uint32_t c = 0; c < node.childCount; ++c) {
        FF_ASSIGN_OR_RETURN(
                const std::uint64_t below,
                subtreeTriangles(file, storage::SceneFile::childRef(node, c), memo));
        total += below;
    }
    memo[{ref.page, ref.slot}] = total;
    return total;
}

Status appendSubtreeTriangles(
        const storage::SceneFile& file,
        storage::NodeRef ref,
        std::vector<storage::PackedTriangle>& out) {
    FF_ASSIGN_OR_RETURN(const storage::NodeRecord node, file.node(ref));
    if (node.kind != static_cast<std::uint8_t>(storage::NodeKind::Cell))
        return Status::ok();
    FF_RETURN_IF_ERROR(appendOwnTriangles(file, node, out));
    for (std::uint32_t c = 0; c < node.childCount; ++c)
        FF_RETURN_IF_ERROR(
                appendSubtreeTriangles(file, storage::SceneFile::childRef(node, c), out));
    return Status::ok();
}

/**
 * Calls visit(triangles) once per leaf of the hierarchy below root: with leafTriangles 0 the v1
 * file's own (each Cell node's own triangles), else the hierarchy cut where a subtree holds at
 * most leafTriangles, each such subtree's triangles as one leaf (what a hierarchy whose leaves
 * are whole clusters would store), and the nodes above it with their own. Adds the nodes that
 * hierarchy has (the cut subtrees one node each) to `nodes`.
 */
template <typename Visit>
Status forEachLeaf(
        const storage::SceneFile& file,
        storage::NodeRef root,
        std::uint64_t leafTriangles,
        std::uint64_t& nodes,
        Visit&& visit) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint64_t> memo;
    if (leafTriangles > 0)
        FF_RETURN_IF_ERROR(subtreeTriangles(file, root, memo).status());
    std::vector<storage::PackedTriangle> triangles;
    std::deque<storage::NodeRef> pending = {root};
    while (!pending.empty()) {
        const storage::NodeRef ref = pending.front();
        pending.pop_front();
        FF_ASSIGN_OR_RETURN(const storage::NodeRecord node, file.node(ref));
        if (node.kind != static_cast<std::uint8_t>(storage::NodeKind::Cell))
            continue; // an instance: its prototype is walked on its own
        ++nodes;
        triangles.clear();
        if (leafTriangles > 0 && memo[{ref.page, ref.slot}] <= leafTriangles) {
            FF_RETURN_IF_ERROR(appendSubtreeTriangles(file, ref, triangles));
        } else {
            for (std::uint32_t c = 0; c < node.childCount; ++c)
                pending.push_back(storage::SceneFile::childRef(node, c));
            FF_RETURN_IF_ERROR(appendOwnTriangles(file, node, triangles));
        }
        if (!triangles.empty())
            FF_RETURN_IF_ERROR(visit(std::span<const storage::PackedTriangle>(triangles)));
    }
    return Status::ok();
}

struct Encoded {
    builder::ClusterBuildStats stats;
    double encodeSeconds = 0.0;
    float maxError = 0.0f; ///< the largest grid's bound, scene units
    std::uint64_t leaves = 0;
    int gridBits = 0; ///< the most any hierarchy's grid took
    /** Format v2 as it would hold these hierarchies: their nodes (48-byte records), the payloads
     *  of their leaves packed into cluster pages, a 20-byte representation per payload and page. */
    std::uint64_t v2Nodes = 0;
    std::uint64_t v2Pages = 0;
    std::uint64_t v2Representations = 0;
    /** Each hierarchy's clusters, back to back, with its grid. */
    std::vector<std::pair<storage::PositionGrid, std::vector<std::byte>>> parts;
};

/** Packs node payloads into cluster pages as a v2 writer would: whole in a page, a new page
 *  when one does not fit, a payload larger than a page split at clusters over several. */
class PagePacker {
public:
    PagePacker(std::uint32_t pageSize, Encoded& counts) : mPageSize(pageSize), mCounts(counts) {}
    ~PagePacker() {
        if (mWriter && !mWriter->empty())
            ++mCounts.v2Pages;
    }
    PagePacker(const PagePacker&) = delete;
    PagePacker& operator=(const PagePacker&) = delete;

    Status add(std::span<const std::byte> clusters, std::uint32_t count) {
        if (count == 0)
            return Status::ok();
        if (place(clusters, count)) {
            ++mCounts.v2Representations;
            return Status::ok();
        }
        // Larger than a page: one cluster at a time, one representation per page it reaches.
        std::uint64_t lastPage = ~std::uint64_t{0};
        while (!clusters.empty()) {
            FF_ASSIGN_OR_RETURN(const storage::ClusterInfo info, storage::readClusterInfo(clusters));
            if (!place(clusters.first(info.encodedBytes), 1))
                return Status(ErrorCode::Internal, "a cluster larger than a page");
            if (mCounts.v2Pages != lastPage) // the open page is the v2Pages-th
                ++mCounts.v2Representations;
            lastPage = mCounts.v2Pages;
            clusters = clusters.subspan(info.encodedBytes);
        }
        return Status::ok();
    }

private:
    /** Appends to the open page, or to a new one when it does not fit; false if it cannot fit
     *  even an empty page. */
    bool place(std::span<const std::byte> clusters, std::uint32_t count) {
        if (!mWriter || !mWriter->fits(clusters, count)) {
            if (mWriter && !mWriter->empty())
                ++mCounts.v2Pages;
            mWriter.emplace(mPageSize, 0);
            if (!mWriter->fits(clusters, count))
                return false;
        }
        return mWriter->append(clusters, count).isOk();
    }

    std::uint32_t mPageSize;
    Encoded& mCounts;
    std::optional<storage::ClusterPageWriter> mWriter;
};

/** The variant's grid over one hierarchy: bits over its extent, or the builder's rule (a step
 *  from its sampled median edge, builder::chooseGrid) at the variant's steps per edge. */
Result<storage::PositionGrid>
gridFor(const storage::SceneFile& file, const Hierarchy& h, const CodecVariant& variant) {
    if (variant.edgeSteps <= 0.0)
        return storage::PositionGrid::covering(h.boundsMin, h.boundsMax, variant.bits);
    builder::EdgeSampler edges;
    std::uint64_t nodes = 0;
    FF_RETURN_IF_ERROR(forEachLeaf(file, h.root, 0, nodes, [&](std::span<const storage::PackedTriangle> t) {
        edges.add(t);
        return Status::ok();
    }));
    return builder::chooseGrid(h.boundsMin, h.boundsMax, edges, static_cast<float>(variant.edgeSteps));
}

Result<Encoded> encodeScene(const storage::SceneFile& file, const CodecVariant& variant, std::uint32_t pageSize) {
    std::vector<Hierarchy> hierarchies = {
            {file.header().root, file.header().boundsMin, file.header().boundsMax}};
    for (const storage::PrototypeRecord& p : file.prototypes())
        hierarchies.push_back({p.root, p.boundsMin, p.boundsMax});
    Encoded encoded;
    builder::ClusterEncoder encoder(variant.limits);
    const auto start = std::chrono::steady_clock::now();
    for (const Hierarchy& h : hierarchies) {
        FF_ASSIGN_OR_RETURN(const storage::PositionGrid grid, gridFor(file, h, variant));
        std::vector<std::byte> bytes;
        PagePacker pages(pageSize, encoded); // one prototype's clusters share pages
        FF_RETURN_IF_ERROR(forEachLeaf(
                file,
                h.root,
                variant.leafTriangles,
                encoded.v2Nodes,
                [&](std::span<const storage::PackedTriangle> t) -> Status {
                    ++encoded.leaves;
                    const std::size_t first = bytes.size();
                    FF_ASSIGN_OR_RETURN(
                            const builder::ClusterBuildStats stats, encoder.encode(t, grid, bytes));
                    encoded.stats += stats;
                    return pages.add(
                            std::span<const std::byte>(bytes).subspan(first),
                            static_cast<std::uint32_t>(stats.clusters));
                }));
        if (!bytes.empty()) {
            encoded.maxError = std::max(encoded.maxError, grid.maxError());
            encoded.gridBits = std::max(encoded.gridBits, grid.bits);
            encoded.parts.emplace_back(grid, std::move(bytes));
        }
    }
    encoded.encodeSeconds = secondsSince(start);
    return encoded;
}

struct DecodeRate {
    double gigabytesPerSecond = 0.0; ///< decoded PackedVertex (20 B) and index (1 B) bytes
    double trianglesPerSecond = 0.0;
};

/** Decodes every cluster again and again for at least `seconds` on this thread. */
Result<DecodeRate> timeDecode(const Encoded& encoded, double seconds) {
    std::vector<storage::PackedVertex> vertices(storage::kMaxClusterVertices);
    std::vector<std::uint8_t> indices(storage::kMaxClusterTriangles * 3);
    std::uint64_t outBytes = 0;
    std::uint64_t triangles = 0;
    const auto start = std::chrono::steady_clock::now();
    double elapsed = 0.0;
    do {
        for (const auto& [grid, bytes] : encoded.parts) {
            std::span<const std::byte> rest(bytes);
            while (!rest.empty()) {
                FF_ASSIGN_OR_RETURN(
                        const storage::ClusterInfo info, storage::readClusterInfo(rest));
                FF_RETURN_IF_ERROR(storage::decodeCluster(rest, grid, vertices, indices));
                outBytes += std::uint64_t{info.vertexCount} * sizeof(storage::PackedVertex) +
                            info.triangleCount * 3ull;
                triangles += info.triangleCount;
                rest = rest.subspan(info.encodedBytes);
            }
        }
        elapsed = secondsSince(start);
    } while (elapsed < seconds);
    return DecodeRate{
            static_cast<double>(outBytes) / elapsed / 1e9,
            static_cast<double>(triangles) / elapsed};
}

bool onPath(const std::string& program) {
    const char* path = std::getenv("PATH");
    std::istringstream dirs(path ? path : "");
    for (std::string dir; std::getline(dirs, dir, ':');)
        if (!dir.empty() && std::filesystem::exists(std::filesystem::path(dir) / program))
            return true;
    return false;
}

struct DracoResult {
    std::uint64_t fileBytes = 0;
    std::uint64_t meshBytes = 0; ///< the Draco buffers alone
    double decodeSeconds = 0.0;  ///< decoding them once, the fastest of several
};

/** Decodes every Draco primitive of a GLB `path` (KHR_draco_mesh_compression). */
Result<DracoResult> measureDraco(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::vector<char> glb((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const auto u32 = [&](std::size_t at) {
        std::uint32_t v = 0;
        if (at + 4 <= glb.size())
            std::memcpy(&v, glb.data() + at, 4);
        return v;
    };
    if (glb.size() < 20 || u32(0) != 0x46546C67u)
        return Status(ErrorCode::Internal, path.string() + " is not a GLB");
    const std::size_t jsonLength = u32(12);
    const std::size_t binAt = 20 + jsonLength + 8;
    if (20 + jsonLength + 8 > glb.size())
        return Status(ErrorCode::Internal, path.string() + ": no binary chunk");
    const nlohmann::json doc = nlohmann::json::parse(
            glb.begin() + 20,
            glb.begin() + 20 + static_cast<std::ptrdiff_t>(jsonLength),
            nullptr,
            false);
    if (!doc.is_object())
        return Status(ErrorCode::Internal, path.string() + ": unreadable JSON chunk");
    std::vector<std::pair<std::size_t, std::size_t>> buffers; // offset in glb, length
    for (const auto& mesh : doc.value("meshes", nlohmann::json::array()))
        for (const auto& primitive : mesh.value("primitives", nlohmann::json::array())) {
            const auto ext = primitive.value("extensions", nlohmann::json::object());
            if (!ext.contains("KHR_draco_mesh_compression"))
                continue;
            // gltf-pipeline's output, but still bytes from a file: every index checked.
            const auto& draco = ext["KHR_draco_mesh_compression"];
            const auto views = doc.value("bufferViews", nlohmann::json::array());
            if (!draco.is_object() || !draco.contains("bufferView") ||
                !draco["bufferView"].is_number_unsigned() ||
                draco["bufferView"].get<std::size_t>() >= views.size() ||
                !views[draco["bufferView"].get<std::size_t>()].is_object())
                return Status(
                        ErrorCode::Internal,
                        path.string() + ": a Draco primitive without a valid bufferView");
            const auto& view = views[draco["bufferView"].get<std::size_t>()];
            const std::size_t offset = binAt + view.value("byteOffset", std::size_t{0});
            const std::size_t length = view.value("byteLength", std::size_t{0});
            if (offset > glb.size() || length > glb.size() - offset)
                return Status(
                        ErrorCode::Internal, path.string() + ": a Draco buffer past the file");
            buffers.emplace_back(offset, length);
        }
    if (buffers.empty())
        return Status(ErrorCode::Internal, path.string() + ": no Draco primitive");
    DracoResult result;
    result.fileBytes = glb.size();
    for (const auto& [offset, length] : buffers)
        result.meshBytes += length;
    result.decodeSeconds = 1e30;
    for (int run = 0; run < 5; ++run) {
        const auto start = std::chrono::steady_clock::now();
        for (const auto& [offset, length] : buffers) {
            draco::DecoderBuffer buffer;
            buffer.Init(glb.data() + offset, length);
            draco::Decoder decoder;
            auto mesh = decoder.DecodeMeshFromBuffer(&buffer);
            if (!mesh.ok())
                return Status(
                        ErrorCode::Internal, path.string() + ": Draco cannot decode a primitive");
        }
        result.decodeSeconds = std::min(result.decodeSeconds, secondsSince(start));
    }
    return result;
}

Status runCodec(const CodecParams& p, const Scenario& scenario, const BenchOptions& options) {
    ScenarioRun scenarioRun(scenario, options);
    const std::filesystem::path& work = scenarioRun.work();
    const bool haveDraco = onPath("gltf-pipeline");
    CsvTable table(
            {"scene",
             "variant",
             "grid_bits",
             "max_vertices",
             "max_triangles",
             "leaf_triangles",
             "leaves",
             "stored_triangles",
             "triangles_kept",
             "clusters",
             "wide_share",
             "vertices_per_triangle",
             "cluster_bytes",
             "bytes_per_triangle",
             "v1_file_bytes_per_triangle",
             "v2_nodes",
             "v2_pages",
             "v2_estimate_bytes_per_triangle",
             "max_position_error",
             "extent",
             "encode_seconds",
             "decode_gb_per_s",
             "decode_mtri_per_s"});
    CsvTable draco(
            {"scene",
             "setting",
             "triangles",
             "draco_file_bytes",
             "draco_mesh_bytes",
             "draco_bytes_per_triangle",
             "draco_decode_mtri_per_s",
             "source_file_bytes"});
    for (const CodecScene& s : p.scenes) {
        std::fprintf(stderr, "%s: building %s\n", scenario.name.c_str(), s.label.c_str());
        const std::filesystem::path scene = work / "scene.ffs";
        // Format 1: the codecs are measured against its 60-byte triangles, read from its segments.
        std::vector<std::string> argv = {options.selfExe, "build", "--format", "1", "-o", scene.string(), "-q"};
        if (!s.generate.empty())
            argv.insert(argv.end(), {"--generate", s.generate});
        else
            argv.push_back(s.gltf);
        FF_RETURN_IF_ERROR(runChild(argv).status());
        FF_ASSIGN_OR_RETURN(const auto file, storage::SceneFile::open(scene));
        const std::uint64_t stored = file->header().storedTriangles;
        const double v1 = static_cast<double>(std::filesystem::file_size(scene)) /
                          static_cast<double>(stored);
        float extent = 0.0f;
        for (std::size_t a = 0; a < 3; ++a)
            extent = std::max(extent, file->header().boundsMax[a] - file->header().boundsMin[a]);
        for (const CodecVariant& v : p.variants) {
            std::fprintf(
                    stderr,
                    "%s: %s, %s\n",
                    scenario.name.c_str(),
                    s.label.c_str(),
                    v.label.c_str());
            FF_ASSIGN_OR_RETURN(const Encoded encoded, encodeScene(*file, v, p.pageSize));
            FF_ASSIGN_OR_RETURN(const DecodeRate rate, timeDecode(encoded, p.decodeSeconds));
            const auto& st = encoded.stats;
            const double kept = static_cast<double>(std::max<std::uint64_t>(st.trianglesKept, 1));
            table.addRow(
                    {s.label,
                     v.label,
                     std::to_string(encoded.gridBits),
                     std::to_string(v.limits.maxVertices),
                     std::to_string(v.limits.maxTriangles),
                     std::to_string(v.leafTriangles),
                     std::to_string(encoded.leaves),
                     std::to_string(stored),
                     std::to_string(st.trianglesKept),
                     std::to_string(st.clusters),
                     formatNumber(
                             static_cast<double>(st.wideClusters) /
                                     static_cast<double>(std::max<std::uint64_t>(st.clusters, 1)),
                             3),
                     formatNumber(static_cast<double>(st.clusterVertices) / kept, 3),
                     std::to_string(st.encodedBytes),
                     formatNumber(static_cast<double>(st.encodedBytes) / kept, 3),
                     formatNumber(v1, 2),
                     std::to_string(encoded.v2Nodes),
                     std::to_string(encoded.v2Pages),
                     formatNumber(
                             static_cast<double>(
                                     encoded.v2Pages * p.pageSize +
                                     encoded.v2Nodes * storage::kNodeRecordV2Size +
                                     encoded.v2Representations * storage::kRepresentationRecordSize) /
                                     static_cast<double>(std::max<std::uint64_t>(stored, 1)),
                             3),
                     formatNumber(encoded.maxError, 9),
                     formatNumber(extent, 3),
                     formatNumber(encoded.encodeSeconds, 3),
                     formatNumber(rate.gigabytesPerSecond, 3),
                     formatNumber(rate.trianglesPerSecond / 1e6, 1)});
        }
        std::filesystem::remove(scene);
        if (s.gltf.empty() || !haveDraco)
            continue;
        // Draco at gltf-pipeline's defaults, and at about the clusters' precision.
        for (const auto& [setting, flags] :
             {std::pair<std::string, std::string>{"defaults (11-bit positions; 8-bit normals)", ""},
              {"16-bit positions; 12-bit normals",
               "--draco.quantizePositionBits 16 --draco.quantizeNormalBits 12"}}) {
            const std::filesystem::path compressed = work / "draco.glb";
            FF_RETURN_IF_ERROR(
                    runChild({"/bin/sh",
                              "-c",
                              "exec gltf-pipeline -i \"$0\" -o \"$1\" -d " + flags + " > /dev/null",
                              s.gltf,
                              compressed.string()})
                            .status());
            FF_ASSIGN_OR_RETURN(const DracoResult d, measureDraco(compressed));
            draco.addRow(
                    {s.label,
                     setting,
                     std::to_string(stored),
                     std::to_string(d.fileBytes),
                     std::to_string(d.meshBytes),
                     formatNumber(
                             static_cast<double>(d.meshBytes) / static_cast<double>(stored), 3),
                     formatNumber(static_cast<double>(stored) / d.decodeSeconds / 1e6, 1),
                     std::to_string(std::filesystem::file_size(s.gltf))});
            std::filesystem::remove(compressed);
        }
    }
    const std::filesystem::path csv = options.outDir / (scenario.name + ".csv");
    FF_RETURN_IF_ERROR(table.write(csv));
    std::ostringstream md;
    md << "Command: `" << options.command << "`\n\n"
       << "Each scene built in format v1 by `farfield build` (default octree, page size auto); the "
          "triangles of every "
          "node encoded as clusters per variant (grid bits over each hierarchy's largest extent; "
          "cluster limits), then "
          "decoded again and again for "
       << formatNumber(p.decodeSeconds, 1)
       << " s on one core (output: 20-byte PackedVertex and 1-byte indices). bytes_per_triangle = "
          "cluster bytes / "
          "triangles kept (node records and page slack not counted; v1_file_bytes_per_triangle is "
          "the whole v1 file "
          "over its stored triangles). v2_estimate_bytes_per_triangle: the clusters packed into "
       << p.pageSize
       << "-byte cluster pages as a v2 writer would, plus a 48-byte record per node of the cut "
          "hierarchy and a 20-byte representation per payload and page, over the stored triangles. "
          "max_position_error: the grid's bound, scene units.\n\n"
       << table.markdown() << "\n";
    if (haveDraco && draco.rowCount() > 0) {
        const std::filesystem::path dracoCsv = options.outDir / (scenario.name + "-draco.csv");
        FF_RETURN_IF_ERROR(draco.write(dracoCsv));
        md << "Draco (`gltf-pipeline -d` on the source glTF, compression level 7; decode of its "
              "mesh buffers alone "
              "through the Draco library, fastest of 5, one core; triangles = the v1 file's stored "
              "ones):\n\n"
           << draco.markdown() << "\n";
    } else {
        md << "Draco: not measured (`gltf-pipeline` not on PATH, or no glTF scene).\n\n";
    }
    md << "![bytes a triangle and decode rate](" << scenario.name << ".png)\n";
    return scenarioRun.finish("codec", csv, md.str());
}

} // namespace

Result<BenchRun> prepareCodec(const Scenario& scenario) {
    CodecParams p;
    ScenarioReader reader = readScenario(scenario);
    for (ScenarioReader& s : reader.objects("scenes")) {
        CodecScene scene;
        scene.label = s.string("label", "");
        scene.generate = s.string("generate", "");
        scene.gltf = s.string("gltf", "");
        if (scene.generate.empty() == scene.gltf.empty())
            s.fail("generate", "give one of generate and gltf");
        if (!scene.gltf.empty()) {
            if (auto expanded = expandShared(scene.gltf))
                scene.gltf = *expanded;
            else
                s.fail("gltf", expanded.status().message());
        }
        if (scene.label.empty())
            scene.label = scene.generate.empty() ? scene.gltf : scene.generate;
        if (scene.label.find(',') != std::string::npos)
            s.fail("label", "must not hold a comma (it is a CSV cell)");
        p.scenes.push_back(scene);
    }
    for (ScenarioReader& v : reader.objects("variants")) {
        CodecVariant variant;
        variant.bits = static_cast<int>(v.integer("bits", storage::kDefaultPositionGridBits));
        variant.edgeSteps = v.number("edge_steps", 0.0);
        if (!(variant.edgeSteps >= 0.0))
            v.fail("edge_steps", "must be 0 (bits over the extent) or the steps a median edge spans");
        variant.limits.maxVertices = static_cast<std::uint32_t>(v.integer("max_vertices", 128));
        variant.limits.maxTriangles = static_cast<std::uint32_t>(v.integer("max_triangles", 256));
        const std::int64_t leaf = v.integer("leaf_triangles", 0);
        if (leaf < 0)
            v.fail("leaf_triangles", "must be 0 (the v1 leaves) or a triangle count");
        variant.leafTriangles = static_cast<std::uint64_t>(std::max<std::int64_t>(leaf, 0));
        // No commas: labels are CSV cells.
        variant.label = v.string(
                "label",
                (variant.edgeSteps > 0.0 ? "step edge/" + formatNumber(variant.edgeSteps, 0) + "; "
                                          : std::to_string(variant.bits) + "-bit grid; ") +
                        std::to_string(variant.limits.maxVertices) + " v / " +
                        std::to_string(variant.limits.maxTriangles) + " t; " +
                        (leaf > 0 ? "leaves ≤ " + std::to_string(leaf) + " t" : "v1 leaves"));
        if (variant.label.find(',') != std::string::npos)
            v.fail("label", "must not hold a comma (it is a CSV cell)");
        if (variant.bits < 1 || variant.bits > storage::kMaxPositionGridBits)
            v.fail("bits", "must be 1-24");
        p.variants.push_back(variant);
    }
    if (p.scenes.empty())
        reader.fail("scenes", "needs at least one scene");
    if (p.variants.empty())
        reader.fail("variants", "needs at least one variant");
    p.decodeSeconds = reader.number("decode_seconds", 1.0);
    const double pageSize = reader.number("page_size", storage::kDefaultPageSize);
    if (pageSize >= storage::kMinPageSize && pageSize <= storage::kMaxPageSize &&
        storage::isValidPageSize(static_cast<std::uint32_t>(pageSize)))
        p.pageSize = static_cast<std::uint32_t>(pageSize);
    else
        reader.fail("page_size", "must be a power of two from 4096 to 16 MiB");
    FF_RETURN_IF_ERROR(reader.finish());
    return BenchRun(
            [p, scenario](const BenchOptions& options) { return runCodec(p, scenario, options); });
}

} // namespace ff::bench
