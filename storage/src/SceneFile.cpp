#include "PageChecksum.h"
#include "PosixError.h"
#include "SectionTable.h"

#include <ff/storage/PageCheck.h>
#include <ff/storage/SceneFile.h>
#include <ff/storage/SceneWriter.h>

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>

namespace ff::storage {

namespace {

// Page types as bits, so one check can accept "Nodes or Geometry".
using PageTypeMask = std::uint32_t;

constexpr PageTypeMask maskOf(PageType type) noexcept {
    return PageTypeMask{1} << static_cast<std::uint16_t>(type);
}

constexpr PageTypeMask kHierarchyPages = maskOf(PageType::Nodes) | maskOf(PageType::Geometry);

// verified[] states. The page type is not cached: it is checked on every access (16 bytes), so
// one intact page can be asked for under any expected type and get the right answer.
constexpr std::uint8_t kUnverified = 0;
constexpr std::uint8_t kIntact = 1;

// verifyAll() reports progress after this many pages.
constexpr std::uint64_t kProgressInterval = 256;

std::string hex(std::uint64_t value) {
    char text[24];
    std::snprintf(text, sizeof(text), "0x%llx", static_cast<unsigned long long>(value));
    return text;
}

std::string maskName(PageTypeMask mask) {
    std::string name;
    for (std::uint16_t t = 1; t <= 4; ++t) {
        if ((mask & (PageTypeMask{1} << t)) == 0)
            continue;
        if (!name.empty())
            name += " or ";
        name += pageTypeName(t);
    }
    return name;
}

Status corrupt(std::uint64_t page, const std::string& what) {
    return {ErrorCode::Corrupt, "page " + std::to_string(page) + ": " + what};
}

template <typename Real>
bool allFinite(const std::array<Real, 3>& v) noexcept {
    return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
}

bool ordered(const std::array<float, 3>& lo, const std::array<float, 3>& hi) noexcept {
    return lo[0] <= hi[0] && lo[1] <= hi[1] && lo[2] <= hi[2];
}

Status checkType(std::uint16_t type, std::uint64_t index, PageTypeMask expected) {
    if (type < 32 && (expected & (PageTypeMask{1} << type)) != 0)
        return Status::ok();
    return corrupt(
            index,
            "expected a " + maskName(expected) + " page, found " + pageTypeName(type) + " (type " +
                    std::to_string(type) + ")");
}

std::string truncatedMessage(std::uint64_t fileSize) {
    return "beyond end of file (file truncated to " + std::to_string(fileSize) + " bytes)";
}

/** A read-only private mapping of a whole file; unmapped on destruction. */
class Mapping {
public:
    Mapping() = default;
    Mapping(const Mapping&) = delete;
    Mapping& operator=(const Mapping&) = delete;
    ~Mapping() {
        if (mData != nullptr)
            ::munmap(mData, mSize);
    }

    Status map(int fd, std::size_t size, const std::string& pathName) {
        if (size == 0)
            return Status::ok();
        void* data = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE, fd, 0);
        if (data == MAP_FAILED)
            return posixError(errno, "cannot map scene file " + pathName);
        mData = data;
        mSize = size;
        return Status::ok();
    }

    std::span<const std::byte> bytes() const noexcept {
        return {static_cast<const std::byte*>(mData), mSize};
    }

private:
    void* mData = nullptr;
    std::size_t mSize = 0;
};

} // namespace

struct SceneFile::Impl {
    std::filesystem::path path;
    Mapping mapping;
    std::span<const std::byte> bytes; ///< the whole file
    FileHeader header{};
    std::vector<SectionEntry> sections;
    std::uint32_t pageSize = 0;
    std::uint64_t pageCount = 0;
    std::uint32_t nodesPerPage = 0;
    std::uint32_t trianglesPerPage = 0;
    /** Per page: kUnverified or kIntact (trailer magic, checksum and index passed). Racing
     *  verifiers of one page compute the same answer over immutable bytes and store the same
     *  value, so the only shared state is this byte. */
    std::unique_ptr<std::atomic<std::uint8_t>[]> verified;
    std::vector<PrototypeRecord> prototypes;
    std::vector<InstanceRecord> instances;
    std::string metadata;

    /** Page `index` < pageCount, whole. */
    std::span<const std::byte> page(std::uint64_t index) const noexcept {
        return bytes.subspan(index * pageSize, pageSize);
    }

    Status verify(std::uint64_t index, PageTypeMask expected) const {
        if (index >= pageCount)
            return corrupt(
                    index,
                    "beyond end of file (the file has " + std::to_string(pageCount) + " pages)");
        if (verified[index].load(std::memory_order_acquire) == kUnverified) {
            FF_RETURN_IF_ERROR(verifyPageBytes(page(index), index));
            verified[index].store(kIntact, std::memory_order_release);
        }
        return checkType(readTrailer(page(index)).pageType, index, expected);
    }

    /** Types allowed on page `index` by the section table (verifyAll). */
    PageTypeMask expectedTypes(std::uint64_t index) const noexcept {
        if (index == 0)
            return maskOf(PageType::Header);
        for (const SectionEntry& s : sections) {
            if (static_cast<SectionType>(s.type) != SectionType::Hierarchy &&
                index >= s.firstPage && index - s.firstPage < s.pageCount)
                return maskOf(PageType::Table);
        }
        return kHierarchyPages;
    }

    /** Reassembles the byte stream of a table section from its verified pages. */
    Status readStream(const SectionEntry& s, std::vector<std::byte>& out) const {
        const std::uint64_t payload = pagePayloadBytes(pageSize);
        out.resize(static_cast<std::size_t>(s.byteLength));
        std::uint64_t at = 0;
        for (std::uint64_t p = 0; p < s.pageCount; ++p) {
            FF_RETURN_IF_ERROR(verify(s.firstPage + p, maskOf(PageType::Table)));
            const std::uint64_t n = std::min(payload, s.byteLength - at);
            std::memcpy(out.data() + at, page(s.firstPage + p).data(), static_cast<std::size_t>(n));
            at += n;
        }
        return Status::ok();
    }

    /** Page of the table section `s` holding logical byte `offset`. */
    std::uint64_t streamPage(const SectionEntry& s, std::uint64_t offset) const noexcept {
        return s.firstPage + offset / pagePayloadBytes(pageSize);
    }

    bool nodeRefInFile(NodeRef ref) const noexcept {
        return ref.page >= 1 && ref.page < pageCount && ref.slot < nodesPerPage;
    }

    Status openHeader();
    Status readSections();
    /** Why a Cell's triangle run leaves the file, or empty if it stays inside. */
    std::string geometryRunProblem(const NodeRecord& node) const;
};

// ---- open ---------------------------------------------------------------------------------

Status SceneFile::Impl::openHeader() {
    const std::uint64_t size = bytes.size();

    // Magic and version come first and never move, so any future version is recognised as such
    // before the rest of the header (page size, trailer) is trusted.
    if (!bytes.empty())
        std::memcpy(&header, bytes.data(), std::min(bytes.size(), sizeof(FileHeader)));
    if (size >= sizeof(header.magic) && header.magic != kFileMagic)
        return corrupt(0, "bad magic (not a farfield scene file)");
    if (size < sizeof(FileHeader))
        return corrupt(0, truncatedMessage(size));
    if (header.formatVersion != kFormatVersion)
        return {ErrorCode::Unsupported,
                "page 0: format version " + std::to_string(header.formatVersion) +
                        " is not supported (this build reads version " +
                        std::to_string(kFormatVersion) + ")"};
    if (!isValidPageSize(header.pageSize))
        return corrupt(0, "invalid page size " + std::to_string(header.pageSize));
    pageSize = header.pageSize;
    if (size < pageSize)
        return corrupt(0, truncatedMessage(size));
    FF_RETURN_IF_ERROR(verifyPageBytes(page(0), 0));
    FF_RETURN_IF_ERROR(checkType(readTrailer(page(0)).pageType, 0, maskOf(PageType::Header)));

    const struct {
        const char* name;
        std::uint32_t stored;
        std::size_t expected;
    } structSizes[] = {
            {"headerSize", header.headerSize, sizeof(FileHeader)},
            {"sectionEntrySize", header.sectionEntrySize, sizeof(SectionEntry)},
            {"nodeRecordSize", header.nodeRecordSize, sizeof(NodeRecord)},
            {"triangleSize", header.triangleSize, sizeof(PackedTriangle)},
            {"prototypeRecordSize", header.prototypeRecordSize, sizeof(PrototypeRecord)},
            {"instanceRecordSize", header.instanceRecordSize, sizeof(InstanceRecord)},
    };
    for (const auto& s : structSizes) {
        if (s.stored != s.expected)
            return corrupt(
                    0,
                    std::string(s.name) + " is " + std::to_string(s.stored) + ", version " +
                            std::to_string(kFormatVersion) + " has " + std::to_string(s.expected));
    }
    if (header.flags != 0)
        return {ErrorCode::Unsupported, "page 0: unknown header flags " + hex(header.flags)};

    // NodeRef and the trailer hold 32-bit page indices.
    constexpr std::uint64_t kMaxPages = std::uint64_t{1} << 32;
    if (header.pageCount == 0 || header.pageCount > kMaxPages)
        return corrupt(0, "page count " + std::to_string(header.pageCount) + " out of range");
    pageCount = header.pageCount;
    const std::uint64_t expectedSize = pageCount * pageSize;
    if (size < expectedSize)
        return corrupt(
                size / pageSize,
                truncatedMessage(size) + "; the header says " + std::to_string(pageCount) +
                        " pages of " + std::to_string(pageSize) + " bytes");
    if (size > expectedSize)
        return corrupt(
                pageCount,
                std::to_string(size - expectedSize) +
                        " bytes past the last page (the header says " + std::to_string(pageCount) +
                        " pages of " + std::to_string(pageSize) + " bytes)");

    nodesPerPage = ff::storage::nodesPerPage(pageSize);
    trianglesPerPage = ff::storage::trianglesPerPage(pageSize);
    verified = std::make_unique<std::atomic<std::uint8_t>[]>(static_cast<std::size_t>(pageCount));
    verified[0].store(kIntact, std::memory_order_release);

    if (header.sectionCount > maxSectionCount(pageSize))
        return corrupt(
                0,
                std::to_string(header.sectionCount) + " sections, page 0 holds at most " +
                        std::to_string(maxSectionCount(pageSize)));
    sections.resize(header.sectionCount);
    if (!sections.empty())
        std::memcpy(
                sections.data(),
                page(0).data() + sizeof(FileHeader),
                sections.size() * sizeof(SectionEntry));
    if (std::string problem = findSectionTableProblem(sections, pageCount, pageSize);
        !problem.empty())
        return corrupt(0, problem);
    if (header.root != kNullNodeRef && !nodeRefInFile(header.root))
        return corrupt(
                0,
                "root node (page " + std::to_string(header.root.page) + ", slot " +
                        std::to_string(header.root.slot) + ") outside the file's node slots");
    if (!allFinite(header.origin))
        return corrupt(0, "the file frame's origin is not finite");

    return readSections();
}

Status SceneFile::Impl::readSections() {
    std::vector<std::byte> stream;
    const SectionEntry* instanceSection = nullptr;
    for (const SectionEntry& s : sections) {
        switch (static_cast<SectionType>(s.type)) {
        case SectionType::Prototypes: {
            FF_RETURN_IF_ERROR(readStream(s, stream));
            prototypes.resize(static_cast<std::size_t>(s.itemCount));
            if (!stream.empty())
                std::memcpy(prototypes.data(), stream.data(), stream.size());
            for (std::size_t i = 0; i < prototypes.size(); ++i) {
                const PrototypeRecord& p = prototypes[i];
                const std::uint64_t at = streamPage(s, i * sizeof(PrototypeRecord));
                if (!nodeRefInFile(p.root))
                    return corrupt(
                            at,
                            "prototype " + std::to_string(i) + ": root node (page " +
                                    std::to_string(p.root.page) + ", slot " +
                                    std::to_string(p.root.slot) +
                                    ") outside the file's node slots");
                if (!allFinite(p.boundsMin) || !allFinite(p.boundsMax))
                    return corrupt(at, "prototype " + std::to_string(i) + ": non-finite bounds");
            }
            break;
        }
        case SectionType::Instances:
            FF_RETURN_IF_ERROR(readStream(s, stream));
            instances.resize(static_cast<std::size_t>(s.itemCount));
            if (!stream.empty())
                std::memcpy(instances.data(), stream.data(), stream.size());
            instanceSection = &s;
            break;
        case SectionType::Metadata:
            FF_RETURN_IF_ERROR(readStream(s, stream));
            metadata.assign(reinterpret_cast<const char*>(stream.data()), stream.size());
            break;
        case SectionType::Hierarchy:
            break;
        }
    }
    // After the loop: the instance section may come before the prototype section.
    for (std::size_t i = 0; i < instances.size(); ++i) {
        const InstanceRecord& inst = instances[i];
        const std::uint64_t at = streamPage(*instanceSection, i * sizeof(InstanceRecord));
        if (inst.prototype >= prototypes.size())
            return corrupt(
                    at,
                    "instance " + std::to_string(i) + " refers to prototype " +
                            std::to_string(inst.prototype) + ", the file has " +
                            std::to_string(prototypes.size()));
        for (float f : inst.transform) {
            if (!std::isfinite(f))
                return corrupt(at, "instance " + std::to_string(i) + ": non-finite transform");
        }
    }
    return Status::ok();
}

SceneFile::SceneFile(std::unique_ptr<Impl> impl)
    : mImpl(std::move(impl)) {}

SceneFile::~SceneFile() = default;

Result<std::unique_ptr<SceneFile>>
SceneFile::open(const std::filesystem::path& path, const SceneFileOptions& options) {
    auto impl = std::make_unique<Impl>();
    impl->path = path;
    const std::string name = path.string();

    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return posixError(errno, "cannot open scene file " + name);
    struct stat st {};
    if (::fstat(fd, &st) != 0) {
        const int err = errno;
        ::close(fd);
        return posixError(err, "cannot stat scene file " + name);
    }
    if (!S_ISREG(st.st_mode)) {
        ::close(fd);
        return Status{ErrorCode::InvalidArgument, name + " is not a regular file"};
    }
    // The mapping keeps the file alive; the descriptor is not needed afterwards.
    const Status mapped = impl->mapping.map(fd, static_cast<std::size_t>(st.st_size), name);
    ::close(fd);
    FF_RETURN_IF_ERROR(mapped);
    impl->bytes = impl->mapping.bytes();

    // Corrupt messages start with "page N: " (the caller knows the path).
    FF_RETURN_IF_ERROR(impl->openHeader());
    std::unique_ptr<SceneFile> file(new SceneFile(std::move(impl)));
    if (options.verifyEveryPage)
        FF_RETURN_IF_ERROR(file->verifyAll());
    return file;
}

// ---- accessors ----------------------------------------------------------------------------

const FileHeader& SceneFile::header() const noexcept {
    return mImpl->header;
}

std::span<const SectionEntry> SceneFile::sections() const noexcept {
    return mImpl->sections;
}

std::uint32_t SceneFile::pageSize() const noexcept {
    return mImpl->pageSize;
}

std::uint64_t SceneFile::pageCount() const noexcept {
    return mImpl->pageCount;
}

const std::filesystem::path& SceneFile::path() const noexcept {
    return mImpl->path;
}

const std::vector<PrototypeRecord>& SceneFile::prototypes() const noexcept {
    return mImpl->prototypes;
}

const std::vector<InstanceRecord>& SceneFile::instances() const noexcept {
    return mImpl->instances;
}

const std::string& SceneFile::metadataJson() const noexcept {
    return mImpl->metadata;
}

Status SceneFile::verifyPage(std::uint64_t index, PageType expected) const {
    return mImpl->verify(index, maskOf(expected));
}

Result<std::span<const std::byte>>
SceneFile::pagePayload(std::uint64_t index, PageType expected) const {
    FF_RETURN_IF_ERROR(mImpl->verify(index, maskOf(expected)));
    return mImpl->page(index).first(pagePayloadBytes(mImpl->pageSize));
}

// ---- nodes --------------------------------------------------------------------------------

std::string SceneFile::Impl::geometryRunProblem(const NodeRecord& node) const {
    if (node.geometryCount == 0)
        return {};
    const std::string run = "geometry run of " + std::to_string(node.geometryCount) +
                            " triangles from page " + std::to_string(node.geometryPage) + " slot " +
                            std::to_string(node.geometryFirst);
    if (node.geometryPage == 0 || node.geometryPage >= pageCount)
        return run + ": page outside the file (" + std::to_string(pageCount) + " pages)";
    if (node.geometryFirst >= trianglesPerPage)
        return run + ": slot out of range (a Geometry page holds " +
               std::to_string(trianglesPerPage) + ")";
    // geometryFirst < trianglesPerPage and counts are 32-bit: no overflow in 64 bits.
    const std::uint64_t lastPage =
            node.geometryPage +
            (std::uint64_t{node.geometryFirst} + node.geometryCount - 1) / trianglesPerPage;
    if (lastPage >= pageCount)
        return run + ": ends on page " + std::to_string(lastPage) + ", past the end of the file (" +
               std::to_string(pageCount) + " pages)";
    return {};
}

Result<NodeRecord> SceneFile::node(NodeRef ref) const {
    const Impl& f = *mImpl;
    if (ref.slot >= f.nodesPerPage)
        return corrupt(
                ref.page,
                "node slot " + std::to_string(ref.slot) + " out of range (a Nodes page holds " +
                        std::to_string(f.nodesPerPage) + ")");
    FF_ASSIGN_OR_RETURN(std::span<const std::byte> payload, pagePayload(ref.page, PageType::Nodes));
    return decodeNode(payload, ref);
}

Result<NodeRecord> SceneFile::decodeNode(std::span<const std::byte> payload, NodeRef ref) const {
    const Impl& f = *mImpl;
    if (ref.slot >= f.nodesPerPage || payload.size() < std::size_t{f.nodesPerPage} * sizeof(NodeRecord))
        return corrupt(
                ref.page,
                "node slot " + std::to_string(ref.slot) + " out of range (a Nodes page holds " +
                        std::to_string(f.nodesPerPage) + ")");
    NodeRecord n{};
    std::memcpy(&n, payload.data() + std::size_t{ref.slot} * sizeof(NodeRecord), sizeof(n));

    // Built only on the error path: this runs for every node of every frame.
    const auto at = [&ref] { return "node slot " + std::to_string(ref.slot) + ": "; };
    if (n.kind != static_cast<std::uint8_t>(NodeKind::Cell) &&
        n.kind != static_cast<std::uint8_t>(NodeKind::Instance))
        return corrupt(ref.page, at() + "unknown node kind " + std::to_string(n.kind));
    constexpr std::uint8_t kKnownFlags = kNodeHasCube | kNodeOctreeChildren;
    if ((n.flags & ~kKnownFlags) != 0)
        return corrupt(ref.page, at() + "unknown node flags " + hex(n.flags));
    if (!allFinite(n.cellMin) || !allFinite(n.cellMax) || !allFinite(n.boundsMin) ||
        !allFinite(n.boundsMax))
        return corrupt(ref.page, at() + "non-finite bounds");
    if (!ordered(n.cellMin, n.cellMax) || !ordered(n.boundsMin, n.boundsMax))
        return corrupt(ref.page, at() + "bounds with min > max");
    if (n.childCount > 0) {
        const NodeRef c = n.firstChild;
        if (c.page == 0 || c.page >= f.pageCount)
            return corrupt(
                    ref.page,
                    at() + "children on page " + std::to_string(c.page) + ", outside the file (" +
                            std::to_string(f.pageCount) + " pages)");
        if (c.slot >= f.nodesPerPage || n.childCount > f.nodesPerPage - c.slot)
            return corrupt(
                    ref.page,
                    at() + "children in slots [" + std::to_string(c.slot) + ", " +
                            std::to_string(std::uint64_t{c.slot} + n.childCount) +
                            ") cross the end of Nodes page " + std::to_string(c.page) + " (" +
                            std::to_string(f.nodesPerPage) + " slots)");
    }
    if (n.kind == static_cast<std::uint8_t>(NodeKind::Cell)) {
        if (std::string problem = f.geometryRunProblem(n); !problem.empty())
            return corrupt(ref.page, at() + problem);
    } else if (n.geometryPage >= f.instances.size()) {
        return corrupt(
                ref.page,
                at() + "instance index " + std::to_string(n.geometryPage) +
                        " out of range (the file has " + std::to_string(f.instances.size()) +
                        " instances)");
    }
    return n;
}

Result<NodeRecord> SceneFile::child(const NodeRecord& parent, std::uint32_t index) const {
    if (index >= parent.childCount)
        return Status{
                ErrorCode::InvalidArgument,
                "child index " + std::to_string(index) + " out of range (the node has " +
                        std::to_string(parent.childCount) + " children)"};
    return node(childRef(parent, index));
}

// ---- geometry -----------------------------------------------------------------------------

Status
SceneFile::geometrySegments(const NodeRecord& node, std::vector<GeometrySegment>& out) const {
    const Impl& f = *mImpl;
    if (node.kind != static_cast<std::uint8_t>(NodeKind::Cell) || node.geometryCount == 0)
        return Status::ok();
    if (std::string problem = f.geometryRunProblem(node); !problem.empty())
        return corrupt(node.geometryPage, problem);
    std::uint64_t page = node.geometryPage;
    std::uint32_t first = node.geometryFirst;
    std::uint32_t remaining = node.geometryCount;
    while (remaining > 0) {
        const std::uint32_t n = std::min(remaining, f.trianglesPerPage - first);
        out.push_back({page, first, n});
        remaining -= n;
        ++page;
        first = 0;
    }
    return Status::ok();
}

Result<std::span<const std::byte>> SceneFile::segmentBytes(const GeometrySegment& s) const {
    const Impl& f = *mImpl;
    if (s.count == 0 || s.firstSlot >= f.trianglesPerPage ||
        s.count > f.trianglesPerPage - s.firstSlot)
        return Status{
                ErrorCode::InvalidArgument,
                "page " + std::to_string(s.page) + ": segment slots [" +
                        std::to_string(s.firstSlot) + ", " +
                        std::to_string(std::uint64_t{s.firstSlot} + s.count) +
                        ") do not fit a Geometry page of " + std::to_string(f.trianglesPerPage) +
                        " slots"};
    FF_ASSIGN_OR_RETURN(
            std::span<const std::byte> payload, pagePayload(s.page, PageType::Geometry));
    return payload.subspan(
            std::size_t{s.firstSlot} * sizeof(PackedTriangle),
            std::size_t{s.count} * sizeof(PackedTriangle));
}

// ---- verification -------------------------------------------------------------------------

Status
SceneFile::verifyAll(const std::function<void(std::uint64_t, std::uint64_t)>& progress) const {
    const Impl& f = *mImpl;
    if (progress)
        progress(0, f.pageCount);
    for (std::uint64_t i = 0; i < f.pageCount; ++i) {
        FF_RETURN_IF_ERROR(f.verify(i, f.expectedTypes(i)));
        if (progress && ((i + 1) % kProgressInterval == 0 || i + 1 == f.pageCount))
            progress(i + 1, f.pageCount);
    }
    return Status::ok();
}

} // namespace ff::storage
