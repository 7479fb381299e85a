#include "ReaderChecks.h"
#include "SectionTable.h"

#include <ff/storage/PageCheck.h>
#include <ff/storage/PrototypeRecordV2.h>
#include <ff/storage/SceneIndex.h>
#include <ff/storage/SceneWriter.h>

#include <algorithm>
#include <cstring>
#include <string>

namespace ff::storage {

using detail::allFinite;
using detail::checkType;
using detail::corrupt;
using detail::hex;
using detail::maskOf;
using detail::ordered;
using detail::truncatedMessage;

// ---- opening ------------------------------------------------------------------------------

Result<std::uint32_t> probePageSize(std::span<const std::byte> start, std::uint64_t fileSize) {
    FileHeader header{};
    if (!start.empty())
        std::memcpy(&header, start.data(), std::min(start.size(), sizeof(FileHeader)));
    if (start.size() >= sizeof(header.magic) && header.magic != kFileMagic)
        return corrupt(0, "bad magic (not a farfield scene file)");
    if (start.size() < sizeof(FileHeader))
        return corrupt(0, truncatedMessage(fileSize));
    if (header.formatVersion != kFormatVersion && header.formatVersion != kFormatVersion2)
        return Status{
                ErrorCode::Unsupported,
                "page 0: format version " + std::to_string(header.formatVersion) +
                        " is not supported (this build reads versions " +
                        std::to_string(kFormatVersion) + " and " + std::to_string(kFormatVersion2) + ")"};
    if (!isValidPageSize(header.pageSize))
        return corrupt(0, "invalid page size " + std::to_string(header.pageSize));
    if (fileSize < header.pageSize)
        return corrupt(0, truncatedMessage(fileSize));
    return header.pageSize;
}

Result<PageLayout> checkPageLayout(std::span<const std::byte> page0, std::uint64_t fileSize) {
    FF_RETURN_IF_ERROR(verifyPageBytes(page0, 0));
    FF_RETURN_IF_ERROR(checkType(readTrailer(page0).pageType, 0, maskOf(PageType::Header)));
    FileHeader header{};
    std::memcpy(&header, page0.data(), sizeof(FileHeader));

    // NodeRef and the trailer hold 32-bit page indices.
    constexpr std::uint64_t kMaxPages = std::uint64_t{1} << 32;
    if (header.pageCount == 0 || header.pageCount > kMaxPages)
        return corrupt(0, "page count " + std::to_string(header.pageCount) + " out of range");
    const PageLayout layout{header.pageSize, header.pageCount};
    const std::uint64_t expectedSize = layout.pageCount * layout.pageSize;
    const std::string says = " pages of " + std::to_string(layout.pageSize) + " bytes";
    if (fileSize < expectedSize)
        return corrupt(
                fileSize / layout.pageSize,
                truncatedMessage(fileSize) + "; the header says " +
                        std::to_string(layout.pageCount) + says);
    if (fileSize > expectedSize)
        return corrupt(
                layout.pageCount,
                std::to_string(fileSize - expectedSize) +
                        " bytes past the last page (the header says " +
                        std::to_string(layout.pageCount) + says + ")");
    return layout;
}

// ---- the index ----------------------------------------------------------------------------

Result<SceneIndex> SceneIndex::read(IPageSource& source) {
    SceneIndex index;
    FF_ASSIGN_OR_RETURN(const PagePin page0, source.pinPage(0));
    if (page0.bytes().size() != source.pageSize() || page0.bytes().size() < sizeof(FileHeader))
        return corrupt(0, "the source served " + std::to_string(page0.bytes().size()) + " bytes");
    FF_RETURN_IF_ERROR(checkType(readTrailer(page0.bytes()).pageType, 0, maskOf(PageType::Header)));
    // The source learnt its layout from this header (checkPageLayout): a source serving another
    // file, or none, must not have its page size trusted below.
    FileHeader header{};
    std::memcpy(&header, page0.bytes().data(), sizeof(FileHeader));
    if (header.pageSize != source.pageSize() || header.pageCount != source.pageCount())
        return corrupt(
                0,
                "the header says " + std::to_string(header.pageCount) + " pages of " +
                        std::to_string(header.pageSize) + " bytes, the source serves " +
                        std::to_string(source.pageCount()) + " of " +
                        std::to_string(source.pageSize()));
    FF_RETURN_IF_ERROR(index.readHeader(page0.bytes()));
    FF_RETURN_IF_ERROR(index.readTables(source));
    return index;
}

Status SceneIndex::readHeader(std::span<const std::byte> page0) {
    std::memcpy(&mHeader, page0.data(), sizeof(FileHeader));
    const std::uint32_t version = mHeader.formatVersion; // 1 or 2: probePageSize checked it
    const StructSizes sizes = structSizesOf(version);
    const struct {
        const char* name;
        std::uint32_t stored;
        std::size_t expected;
    } structSizes[] = {
            {"headerSize", mHeader.headerSize, sizes.header},
            {"sectionEntrySize", mHeader.sectionEntrySize, sizes.sectionEntry},
            {"nodeRecordSize", mHeader.nodeRecordSize, sizes.nodeRecord},
            {version == kFormatVersion2 ? "representationRecordSize" : "triangleSize",
             mHeader.triangleSize,
             sizes.triangleOrRepresentation},
            {"prototypeRecordSize", mHeader.prototypeRecordSize, sizes.prototypeRecord},
            {"instanceRecordSize", mHeader.instanceRecordSize, sizes.instanceRecord},
    };
    for (const auto& s : structSizes) {
        if (s.stored != s.expected)
            return corrupt(
                    0,
                    std::string(s.name) + " is " + std::to_string(s.stored) + ", version " +
                            std::to_string(version) + " has " + std::to_string(s.expected));
    }
    const std::uint32_t knownFlags = version == kFormatVersion2 ? kFileV2HasRoot : 0u;
    if ((mHeader.flags & ~knownFlags) != 0)
        return {ErrorCode::Unsupported, "page 0: unknown header flags " + hex(mHeader.flags)};

    mNodesPerPage = version == kFormatVersion2 ? nodesPerPageV2(pageSize()) : nodesPerPage(pageSize());
    mTrianglesPerPage = trianglesPerPage(pageSize());
    if (mHeader.sectionCount > maxSectionCount(pageSize()))
        return corrupt(
                0,
                std::to_string(mHeader.sectionCount) + " sections, page 0 holds at most " +
                        std::to_string(maxSectionCount(pageSize())));
    mSections.resize(mHeader.sectionCount);
    if (!mSections.empty())
        std::memcpy(
                mSections.data(),
                page0.data() + sizeof(FileHeader),
                mSections.size() * sizeof(SectionEntry));
    if (std::string problem = findSectionTableProblem(mSections, pageCount(), pageSize(), version);
        !problem.empty())
        return corrupt(0, problem);
    if (version == kFormatVersion2) {
        // The root is a node index, checked once the NodePages section is read.
        if (mHeader.root.slot != 0)
            return corrupt(0, "root field's second word is " + std::to_string(mHeader.root.slot) + ", version 2 has 0");
    } else if (mHeader.root != kNullNodeRef && !nodeRefInFile(mHeader.root))
        return corrupt(
                0,
                "root node (page " + std::to_string(mHeader.root.page) + ", slot " +
                        std::to_string(mHeader.root.slot) + ") outside the file's node slots");
    if (!allFinite(mHeader.origin))
        return corrupt(0, "the file frame's origin is not finite");
    return Status::ok();
}

Status SceneIndex::readStream(
        IPageSource& source, const SectionEntry& s, std::vector<std::byte>& out) const {
    const std::uint64_t payload = pagePayloadBytes(pageSize());
    out.resize(static_cast<std::size_t>(s.byteLength));
    std::uint64_t at = 0;
    std::uint64_t skip = streamOffset(s); // < payload: the section table rules checked it
    for (std::uint64_t p = 0; p < s.pageCount; ++p) {
        FF_ASSIGN_OR_RETURN(const PagePin page, source.pinPage(s.firstPage + p));
        FF_RETURN_IF_ERROR(checkType(
                readTrailer(page.bytes()).pageType, s.firstPage + p, maskOf(PageType::Table)));
        const std::uint64_t n = std::min(payload - skip, s.byteLength - at);
        std::memcpy(out.data() + at, page.bytes().data() + skip, static_cast<std::size_t>(n));
        at += n;
        skip = 0;
    }
    return Status::ok();
}

std::uint64_t SceneIndex::streamOffset(const SectionEntry& s) const noexcept {
    return formatVersion() == kFormatVersion2 ? s.offset : 0; // v1: a reserved field, ignored
}

std::uint64_t SceneIndex::streamPage(const SectionEntry& s, std::uint64_t offset) const noexcept {
    return s.firstPage + (streamOffset(s) + offset) / pagePayloadBytes(pageSize());
}

Status SceneIndex::readTables(IPageSource& source) {
    std::vector<std::byte> stream;
    const SectionEntry* instanceSection = nullptr;
    for (const SectionEntry& s : mSections) {
        switch (static_cast<SectionType>(s.type)) {
        case SectionType::Prototypes: {
            FF_RETURN_IF_ERROR(readStream(source, s, stream));
            if (formatVersion() == kFormatVersion2) {
                mPrototypesV2.reserve(static_cast<std::size_t>(s.itemCount));
                for (std::size_t i = 0; i < s.itemCount; ++i) {
                    Result<PrototypeV2> p = decodePrototypeV2(
                            std::span(stream).subspan(i * kPrototypeRecordV2Size, kPrototypeRecordV2Size));
                    if (!p)
                        return corrupt(
                                streamPage(s, i * kPrototypeRecordV2Size),
                                "prototype " + std::to_string(i) + ": " + p.status().message());
                    mPrototypesV2.push_back(*p);
                }
                break;
            }
            mPrototypes.resize(static_cast<std::size_t>(s.itemCount));
            if (!stream.empty())
                std::memcpy(mPrototypes.data(), stream.data(), stream.size());
            for (std::size_t i = 0; i < mPrototypes.size(); ++i) {
                const PrototypeRecord& p = mPrototypes[i];
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
            FF_RETURN_IF_ERROR(readStream(source, s, stream));
            mInstances.resize(static_cast<std::size_t>(s.itemCount));
            if (!stream.empty())
                std::memcpy(mInstances.data(), stream.data(), stream.size());
            instanceSection = &s;
            break;
        case SectionType::Metadata:
            FF_RETURN_IF_ERROR(readStream(source, s, stream));
            mMetadata.assign(reinterpret_cast<const char*>(stream.data()), stream.size());
            break;
        case SectionType::Hierarchy:
            break;
        case SectionType::NodePages:
            FF_RETURN_IF_ERROR(readStream(source, s, stream));
            mNodePages.resize(static_cast<std::size_t>(s.itemCount));
            if (!stream.empty())
                std::memcpy(mNodePages.data(), stream.data(), stream.size());
            for (std::size_t i = 0; i < mNodePages.size(); ++i) {
                const std::uint32_t page = mNodePages[i];
                const std::uint64_t at = streamPage(s, i * sizeof(std::uint32_t));
                if (page == 0 || page >= pageCount() ||
                    (allowedPageTypes(page) & maskOf(PageType::Nodes)) == 0)
                    return corrupt(
                            at,
                            "node page " + std::to_string(i) + " is page " + std::to_string(page) +
                                    ", not one that can hold nodes");
                if (i > 0 && page <= mNodePages[i - 1])
                    return corrupt(at, "node pages out of order (entry " + std::to_string(i) + ")");
            }
            break;
        }
    }
    if (formatVersion() == kFormatVersion2)
        FF_RETURN_IF_ERROR(checkRootsV2());
    // After the loop: the instance section may come before the prototype section.
    for (std::size_t i = 0; i < mInstances.size(); ++i) {
        const InstanceRecord& inst = mInstances[i];
        const std::uint64_t at = streamPage(*instanceSection, i * sizeof(InstanceRecord));
        if (inst.prototype >= prototypeCount())
            return corrupt(
                    at,
                    "instance " + std::to_string(i) + " refers to prototype " +
                            std::to_string(inst.prototype) + ", the file has " +
                            std::to_string(prototypeCount()));
        for (float f : inst.transform) {
            if (!std::isfinite(f))
                return corrupt(at, "instance " + std::to_string(i) + ": non-finite transform");
        }
    }
    return Status::ok();
}

Status SceneIndex::checkRootsV2() const {
    const std::uint64_t slots = nodeSlotCount();
    if ((mHeader.flags & kFileV2HasRoot) != 0 && mHeader.root.page >= slots)
        return corrupt(
                0,
                "root node " + std::to_string(mHeader.root.page) + " outside the file's " +
                        std::to_string(slots) + " node slots");
    for (std::size_t i = 0; i < mPrototypesV2.size(); ++i) {
        if (mPrototypesV2[i].rootNode >= slots)
            return corrupt(
                    0,
                    "prototype " + std::to_string(i) + ": root node " +
                            std::to_string(mPrototypesV2[i].rootNode) + " outside the file's " +
                            std::to_string(slots) + " node slots");
    }
    return Status::ok();
}

std::uint64_t SceneIndex::prototypeCount() const noexcept {
    return formatVersion() == kFormatVersion2 ? mPrototypesV2.size() : mPrototypes.size();
}

Result<NodeRef> SceneIndex::nodeLocation(std::uint32_t nodeIndex) const {
    const std::uint64_t ordinal = nodeIndex / mNodesPerPage;
    if (formatVersion() != kFormatVersion2 || ordinal >= mNodePages.size())
        return Status{
                ErrorCode::Corrupt,
                "node " + std::to_string(nodeIndex) + " outside the file's " +
                        std::to_string(nodeSlotCount()) + " node slots"};
    return NodeRef{mNodePages[ordinal], nodeIndex % mNodesPerPage};
}

std::uint32_t SceneIndex::allowedPageTypes(std::uint64_t index) const noexcept {
    if (index == 0)
        return maskOf(PageType::Header);
    for (const SectionEntry& s : mSections) {
        if (static_cast<SectionType>(s.type) != SectionType::Hierarchy && index >= s.firstPage &&
            index - s.firstPage < s.pageCount)
            return maskOf(PageType::Table);
    }
    return detail::kHierarchyPages;
}

// ---- nodes --------------------------------------------------------------------------------

bool SceneIndex::nodeRefInFile(NodeRef ref) const noexcept {
    return ref.page >= 1 && ref.page < pageCount() && ref.slot < mNodesPerPage;
}

std::string SceneIndex::geometryRunProblem(const NodeRecord& node) const {
    if (node.geometryCount == 0)
        return {};
    // Built only on the error path: decodeNode() asks for every node of every frame.
    const auto run = [&node] {
        return "geometry run of " + std::to_string(node.geometryCount) + " triangles from page " +
               std::to_string(node.geometryPage) + " slot " + std::to_string(node.geometryFirst);
    };
    if (node.geometryPage == 0 || node.geometryPage >= pageCount())
        return run() + ": page outside the file (" + std::to_string(pageCount()) + " pages)";
    if (node.geometryFirst >= mTrianglesPerPage)
        return run() + ": slot out of range (a Geometry page holds " +
               std::to_string(mTrianglesPerPage) + ")";
    // geometryFirst < trianglesPerPage and counts are 32-bit: no overflow in 64 bits.
    const std::uint64_t lastPage =
            node.geometryPage +
            (std::uint64_t{node.geometryFirst} + node.geometryCount - 1) / mTrianglesPerPage;
    if (lastPage >= pageCount())
        return run() + ": ends on page " + std::to_string(lastPage) + ", past the end of the file (" +
               std::to_string(pageCount()) + " pages)";
    return {};
}

Result<NodeRecord> SceneIndex::decodeNode(std::span<const std::byte> payload, NodeRef ref) const {
    if (formatVersion() != kFormatVersion)
        return Status{ErrorCode::Unsupported, "version 2 nodes are read with readNodeV2 (NodePageV2.h)"};
    if (ref.slot >= mNodesPerPage ||
        payload.size() < std::size_t{mNodesPerPage} * sizeof(NodeRecord))
        return corrupt(
                ref.page,
                "node slot " + std::to_string(ref.slot) + " out of range (a Nodes page holds " +
                        std::to_string(mNodesPerPage) + ")");
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
        if (c.page == 0 || c.page >= pageCount())
            return corrupt(
                    ref.page,
                    at() + "children on page " + std::to_string(c.page) + ", outside the file (" +
                            std::to_string(pageCount()) + " pages)");
        if (c.slot >= mNodesPerPage || n.childCount > mNodesPerPage - c.slot)
            return corrupt(
                    ref.page,
                    at() + "children in slots [" + std::to_string(c.slot) + ", " +
                            std::to_string(std::uint64_t{c.slot} + n.childCount) +
                            ") cross the end of Nodes page " + std::to_string(c.page) + " (" +
                            std::to_string(mNodesPerPage) + " slots)");
    }
    if (n.kind == static_cast<std::uint8_t>(NodeKind::Cell)) {
        if (std::string problem = geometryRunProblem(n); !problem.empty())
            return corrupt(ref.page, at() + problem);
    } else if (n.geometryPage >= mInstances.size()) {
        return corrupt(
                ref.page,
                at() + "instance index " + std::to_string(n.geometryPage) +
                        " out of range (the file has " + std::to_string(mInstances.size()) +
                        " instances)");
    }
    return n;
}

// ---- geometry -----------------------------------------------------------------------------

Status
SceneIndex::geometrySegments(const NodeRecord& node, std::vector<GeometrySegment>& out) const {
    if (formatVersion() != kFormatVersion)
        return Status{ErrorCode::Unsupported, "version 2 geometry is read through representations (NodePageV2.h)"};
    if (node.kind != static_cast<std::uint8_t>(NodeKind::Cell) || node.geometryCount == 0)
        return Status::ok();
    if (std::string problem = geometryRunProblem(node); !problem.empty())
        return corrupt(node.geometryPage, problem);
    std::uint64_t page = node.geometryPage;
    std::uint32_t first = node.geometryFirst;
    std::uint32_t remaining = node.geometryCount;
    while (remaining > 0) {
        const std::uint32_t n = std::min(remaining, mTrianglesPerPage - first);
        out.push_back({page, first, n});
        remaining -= n;
        ++page;
        first = 0;
    }
    return Status::ok();
}

} // namespace ff::storage
