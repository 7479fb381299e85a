#pragma once

// A small scene file for the storage tests, written through SceneWriter, with every record kept
// so tests can compare what they read against what was written, and byte-level helpers for
// corruption and truncation tests.
//
// Page layout (P = page size, T = trianglesPerPage(P), N = nodesPerPage(P)):
//   0      Header
//   1      Nodes A: root (3 children at A:1..3), child0 (2 children at B:0..1, triangle run over
//          three Geometry pages), child1 (Instance 2), child2 (5 triangles)
//   2      Nodes B: two leaves with triangles on the third Geometry page
//   3..5   Geometry, every slot filled with makeTriangle(page, slot)
//   6      Table: Prototypes (3 records)
//   7..8   Table: Instances (a record straddles the page boundary with 4 KiB pages)
//   9..10  Table: Metadata JSON (longer than one page payload)

#include <ff/storage/SceneFile.h>
#include <ff/storage/SceneWriter.h>

#include <gtest/gtest.h>
#include <unistd.h>
#include <xxhash.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <system_error>
#include <vector>

namespace ff::storage::test {

/** A fresh, empty directory for the running test (tests may run in parallel processes). */
inline std::filesystem::path freshTestDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string(info->test_suite_name()) + "." + info->name();
    for (char& c : name) {
        if (c == '/')
            c = '_';
    }
    const std::filesystem::path dir = std::filesystem::path(FF_TEST_TMP_DIR) / name;
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
    std::filesystem::create_directories(dir);
    return dir;
}

inline std::vector<std::byte> readBytes(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::vector<char> chars((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::vector<std::byte> bytes(chars.size());
    if (!chars.empty())
        std::memcpy(bytes.data(), chars.data(), chars.size());
    return bytes;
}

inline void
writeBytes(const std::filesystem::path& path, const std::vector<std::byte>& bytes, std::size_t n) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(n));
    ASSERT_TRUE(out.good()) << path;
}

inline void writeBytes(const std::filesystem::path& path, const std::vector<std::byte>& bytes) {
    writeBytes(path, bytes, bytes.size());
}

template <typename T> T loadAt(const std::vector<std::byte>& bytes, std::size_t offset) {
    T value{};
    std::memcpy(&value, bytes.data() + offset, sizeof(T));
    return value;
}

template <typename T> void storeAt(std::vector<std::byte>& bytes, std::size_t offset, T value) {
    std::memcpy(bytes.data() + offset, &value, sizeof(T));
}

/** Recomputes page `index`'s checksum the way FORMAT.md defines it (independent of src/). */
inline void resealPage(std::vector<std::byte>& bytes, std::uint32_t pageSize, std::uint64_t index) {
    const std::size_t base = static_cast<std::size_t>(index) * pageSize;
    const std::uint64_t sum = XXH3_64bits(bytes.data() + base, pageSize - 8);
    storeAt(bytes, base + pageSize - 8, sum);
}

/** Deterministic triangle for slot `slot` of page `page`. */
inline PackedTriangle makeTriangle(std::uint64_t page, std::uint32_t slot) {
    PackedTriangle t{};
    for (std::size_t v = 0; v < 3; ++v) {
        const auto base = static_cast<float>(page * 1000 + slot);
        t.vertices[v].position = {base, static_cast<float>(v), -base};
        t.vertices[v].normalOct = {static_cast<std::int16_t>(slot), static_cast<std::int16_t>(v)};
        t.vertices[v].color = {
                static_cast<std::uint8_t>(page),
                static_cast<std::uint8_t>(slot),
                static_cast<std::uint8_t>(v),
                255};
    }
    return t;
}

inline NodeRecord makeCell(float lo, float hi) {
    NodeRecord n{};
    n.cellMin = {lo, lo, lo};
    n.cellMax = {hi, hi, hi};
    n.boundsMin = n.cellMin;
    n.boundsMax = n.cellMax;
    n.kind = static_cast<std::uint8_t>(NodeKind::Cell);
    n.flags = kNodeHasCube;
    for (std::size_t f = 0; f < n.cube.size(); ++f)
        n.cube[f] = {static_cast<std::uint8_t>(f), 10, 20, 255};
    return n;
}

template <typename T> std::vector<std::byte> asBytes(const std::vector<T>& items) {
    std::vector<std::byte> bytes(items.size() * sizeof(T));
    if (!bytes.empty())
        std::memcpy(bytes.data(), items.data(), bytes.size());
    return bytes;
}

/** What writeTestScene() wrote; tests may change records before writing (see `tweak`). */
struct TestScene {
    std::uint32_t pageSize = 0;
    std::uint32_t trianglesPerPage = 0;
    std::uint32_t nodesPerPage = 0;
    static constexpr std::uint32_t kNodePageA = 1;
    static constexpr std::uint32_t kNodePageB = 2;
    static constexpr std::uint32_t kFirstGeometryPage = 3;
    static constexpr std::uint32_t kGeometryPages = 3;
    static constexpr std::uint64_t kPrototypePage = 6;
    static constexpr std::uint64_t kFirstInstancePage = 7;
    static constexpr std::uint64_t kFirstMetadataPage = 9;
    static constexpr std::uint64_t kPageCount = 11;
    static constexpr NodeRef kRoot = {kNodePageA, 0};

    std::vector<NodeRecord> nodesA;
    std::vector<NodeRecord> nodesB;
    std::vector<PrototypeRecord> prototypes;
    std::vector<InstanceRecord> instances;
    std::string metadata;

    bool isNodePage(std::uint64_t page) const { return page == kNodePageA || page == kNodePageB; }
    bool isGeometryPage(std::uint64_t page) const {
        return page >= kFirstGeometryPage && page < kFirstGeometryPage + kGeometryPages;
    }
};

/** The records of the test scene for `pageSize` (see the layout at the top). */
inline TestScene makeTestScene(std::uint32_t pageSize) {
    TestScene s;
    s.pageSize = pageSize;
    s.trianglesPerPage = trianglesPerPage(pageSize);
    s.nodesPerPage = nodesPerPage(pageSize);
    const std::uint32_t g0 = TestScene::kFirstGeometryPage;

    NodeRecord root = makeCell(0.0f, 8.0f);
    root.childCount = 3;
    root.firstChild = {TestScene::kNodePageA, 1};
    NodeRecord child0 = makeCell(0.0f, 4.0f);
    child0.childCount = 2;
    child0.firstChild = {TestScene::kNodePageB, 0};
    child0.level = 1;
    child0.geometryPage = g0; // 8 + T + 24 triangles over three pages
    child0.geometryFirst = s.trianglesPerPage - 8;
    child0.geometryCount = s.trianglesPerPage + 32;
    NodeRecord child1 = makeCell(4.0f, 8.0f);
    child1.kind = static_cast<std::uint8_t>(NodeKind::Instance);
    child1.geometryPage = 2; // instance index
    child1.level = 1;
    NodeRecord child2 = makeCell(2.0f, 6.0f);
    child2.geometryPage = g0;
    child2.geometryFirst = 0;
    child2.geometryCount = 5;
    child2.level = 1;
    s.nodesA = {root, child0, child1, child2};

    NodeRecord leaf0 = makeCell(0.0f, 2.0f);
    leaf0.flags |= kNodeOctreeChildren;
    leaf0.level = 2;
    leaf0.geometryPage = g0 + 2;
    leaf0.geometryFirst = 24;
    leaf0.geometryCount = 10;
    NodeRecord leaf1 = leaf0;
    leaf1.geometryFirst = 34;
    leaf1.geometryCount = 3;
    s.nodesB = {leaf0, leaf1};

    for (std::uint32_t i = 0; i < 3; ++i) {
        PrototypeRecord p{};
        p.root = {TestScene::kNodePageB, i % 2};
        p.boundsMin = {0.0f, 0.0f, static_cast<float>(i)};
        p.boundsMax = {1.0f, 1.0f, static_cast<float>(i + 1)};
        p.triangleCount = 100 + i;
        p.nodeCount = 1;
        s.prototypes.push_back(p);
    }
    // More than fit a page payload, so the section takes two pages. With 4 KiB pages a record
    // straddles the boundary (4080 % 56 == 48); with 64 KiB pages none does (65520 % 56 == 0).
    const std::size_t instanceCount = pagePayloadBytes(pageSize) / sizeof(InstanceRecord) + 2;
    for (std::size_t i = 0; i < instanceCount; ++i) {
        InstanceRecord r{};
        for (std::size_t k = 0; k < r.transform.size(); ++k)
            r.transform[k] = static_cast<float>(i) + static_cast<float>(k) * 0.25f;
        r.prototype = static_cast<std::uint32_t>(i % s.prototypes.size());
        s.instances.push_back(r);
    }
    s.metadata = "{\"generator\":\"farfield tests\",\"name\":\"caf\xc3\xa9\",\"pad\":\"";
    while (s.metadata.size() < pagePayloadBytes(pageSize) + pageSize / 2)
        s.metadata += "0123456789abcdef";
    s.metadata += "\"}";
    return s;
}

/** Writes `scene` to `path` in the layout above; fails the test on any writer error. */
inline void writeTestScene(const std::filesystem::path& path, const TestScene& s) {
    SceneWriterOptions options;
    options.pageSize = s.pageSize;
    auto writer = SceneWriter::create(path, options);
    ASSERT_TRUE(writer.isOk()) << writer.status().toString();
    SceneWriter& w = **writer;

    auto appendNodes = [&](const std::vector<NodeRecord>& nodes, std::uint64_t expectedPage) {
        const auto page = w.appendPage(PageType::Nodes, asBytes(nodes));
        ASSERT_TRUE(page.isOk()) << page.status().toString();
        ASSERT_EQ(*page, expectedPage);
    };
    appendNodes(s.nodesA, TestScene::kNodePageA);
    appendNodes(s.nodesB, TestScene::kNodePageB);
    for (std::uint32_t g = 0; g < TestScene::kGeometryPages; ++g) {
        const std::uint64_t pageIndex = TestScene::kFirstGeometryPage + g;
        std::vector<PackedTriangle> triangles;
        for (std::uint32_t slot = 0; slot < s.trianglesPerPage; ++slot)
            triangles.push_back(makeTriangle(pageIndex, slot));
        const auto page = w.appendPage(PageType::Geometry, asBytes(triangles));
        ASSERT_TRUE(page.isOk()) << page.status().toString();
        ASSERT_EQ(*page, pageIndex);
    }
    std::vector<SectionEntry> sections;
    auto appendSection = [&](SectionType type, std::vector<std::byte> bytes, std::uint64_t items) {
        const auto entry = w.appendSection(type, bytes, items);
        ASSERT_TRUE(entry.isOk()) << entry.status().toString();
        sections.push_back(*entry);
    };
    appendSection(SectionType::Prototypes, asBytes(s.prototypes), s.prototypes.size());
    appendSection(SectionType::Instances, asBytes(s.instances), s.instances.size());
    std::vector<std::byte> json(s.metadata.size());
    std::memcpy(json.data(), s.metadata.data(), json.size());
    appendSection(SectionType::Metadata, json, 1);
    SectionEntry hierarchy{};
    hierarchy.type = static_cast<std::uint32_t>(SectionType::Hierarchy);
    hierarchy.firstPage = TestScene::kNodePageA;
    hierarchy.pageCount = 2 + TestScene::kGeometryPages;
    hierarchy.itemCount = s.nodesA.size() + s.nodesB.size();
    sections.push_back(hierarchy);
    ASSERT_EQ(w.nextPageIndex(), TestScene::kPageCount);

    FileHeader header{};
    header.root = TestScene::kRoot;
    header.boundsMin = {0.0f, 0.0f, 0.0f};
    header.boundsMax = {8.0f, 8.0f, 8.0f};
    header.nodeCount = hierarchy.itemCount;
    header.storedTriangles = s.trianglesPerPage * TestScene::kGeometryPages;
    header.instancedTriangles = header.storedTriangles * 2;
    const Status committed = w.commit(header, sections);
    ASSERT_TRUE(committed.isOk()) << committed.toString();
}

/** Starts with `prefix`? (gtest's StartsWith matcher needs gmock.) */
inline bool startsWith(const std::string& text, const std::string& prefix) {
    return text.compare(0, prefix.size(), prefix) == 0;
}

} // namespace ff::storage::test
