#include "SectionTable.h"

#include <ff/storage/PrototypeRecordV2.h>

#include <string>

namespace ff::storage {

const char* sectionTypeName(std::uint32_t type) noexcept {
    switch (static_cast<SectionType>(type)) {
    case SectionType::Prototypes:
        return "Prototypes";
    case SectionType::Instances:
        return "Instances";
    case SectionType::Metadata:
        return "Metadata";
    case SectionType::Hierarchy:
        return "Hierarchy";
    case SectionType::NodePages:
        return "NodePages";
    }
    return "unknown";
}

std::size_t sectionRecordSize(std::uint32_t type, std::uint32_t formatVersion) noexcept {
    switch (static_cast<SectionType>(type)) {
    case SectionType::Prototypes:
        return formatVersion >= kFormatVersion2 ? kPrototypeRecordV2Size : sizeof(PrototypeRecord);
    case SectionType::Instances:
        return sizeof(InstanceRecord);
    case SectionType::NodePages:
        return sizeof(std::uint32_t);
    case SectionType::Metadata:
    case SectionType::Hierarchy:
        return 0;
    }
    return 0;
}

std::uint64_t sectionPagesFor(std::uint64_t byteLength, std::uint32_t pageSize) noexcept {
    const std::uint64_t payload = pagePayloadBytes(pageSize);
    return byteLength / payload + (byteLength % payload != 0 ? 1 : 0);
}

std::string findSectionTableProblem(
        std::span<const SectionEntry> sections,
        std::uint64_t pageCount,
        std::uint32_t pageSize,
        std::uint32_t formatVersion) {
    constexpr std::uint32_t kMaxTypes = 5;
    const std::uint32_t kTypeCount = formatVersion >= kFormatVersion2 ? 5 : 4;
    bool seen[kMaxTypes + 1] = {};
    for (std::size_t i = 0; i < sections.size(); ++i) {
        const SectionEntry& s = sections[i];
        const std::string name =
                "section " + std::to_string(i) + " (" + sectionTypeName(s.type) + ")";
        if (s.type == 0 || s.type > kTypeCount)
            return name + ": unknown section type " + std::to_string(s.type);
        if (seen[s.type])
            return name + ": duplicate section type";
        seen[s.type] = true;

        // [firstPage, firstPage + pageCount) inside [1, pageCount), written without overflow.
        if (s.firstPage < 1 || s.firstPage > pageCount || s.pageCount > pageCount - s.firstPage)
            return name + ": pages [" + std::to_string(s.firstPage) + ", +" +
                   std::to_string(s.pageCount) + ") outside the file's pages [1, " +
                   std::to_string(pageCount) + ")";

        const bool shared = formatVersion >= kFormatVersion2; // v2 streams may share pages
        if (static_cast<SectionType>(s.type) == SectionType::Hierarchy) {
            if (s.byteLength != 0)
                return name + ": byte length " + std::to_string(s.byteLength) +
                       " (a hierarchy section has no byte stream)";
            if (shared && s.offset != 0)
                return name + ": offset " + std::to_string(s.offset) + " (a hierarchy section has no byte stream)";
        } else {
            if (shared && s.offset >= pagePayloadBytes(pageSize))
                return name + ": offset " + std::to_string(s.offset) + " past a page's payload";
            // Before any sum with it: a garbage length must not wrap the arithmetic below.
            if (s.byteLength > pageCount * std::uint64_t{pagePayloadBytes(pageSize)})
                return name + ": byte length " + std::to_string(s.byteLength) + " larger than the file";
            const std::uint64_t start = shared ? s.offset : 0;
            const std::uint64_t needed = s.byteLength == 0 ? 0 : sectionPagesFor(start + s.byteLength, pageSize);
            if (s.pageCount != needed)
                return name + ": " + std::to_string(s.byteLength) + " bytes need " +
                       std::to_string(needed) + " pages, the entry says " +
                       std::to_string(s.pageCount);
            const std::size_t recordSize = sectionRecordSize(s.type, formatVersion);
            if (recordSize != 0 &&
                (s.byteLength % recordSize != 0 || s.byteLength / recordSize != s.itemCount))
                return name + ": " + std::to_string(s.byteLength) + " bytes do not hold " +
                       std::to_string(s.itemCount) + " records of " + std::to_string(recordSize) +
                       " bytes";
        }

        for (std::size_t j = 0; j < i; ++j) {
            const SectionEntry& o = sections[j];
            const bool tables = shared && static_cast<SectionType>(s.type) != SectionType::Hierarchy &&
                                static_cast<SectionType>(o.type) != SectionType::Hierarchy;
            bool disjoint = false;
            if (tables) { // two v2 streams may share a page, never a byte
                const std::uint64_t payload = pagePayloadBytes(pageSize);
                const std::uint64_t a = s.firstPage * payload + s.offset;
                const std::uint64_t b = o.firstPage * payload + o.offset;
                disjoint = a + s.byteLength <= b || b + o.byteLength <= a;
            } else {
                disjoint = s.firstPage + s.pageCount <= o.firstPage || o.firstPage + o.pageCount <= s.firstPage;
            }
            if (!disjoint && s.pageCount != 0 && o.pageCount != 0)
                return name + std::string(tables ? ": bytes" : ": pages") + " overlap section " + std::to_string(j) + " (" +
                       sectionTypeName(o.type) + ")";
        }
    }
    return {};
}

} // namespace ff::storage
