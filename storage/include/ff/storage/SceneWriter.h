#pragma once

#include <ff/storage/SceneFormat.h>
#include <ff/storage/Status.h>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <vector>

namespace ff::storage {

struct SceneWriterOptions {
    std::uint32_t pageSize = kDefaultPageSize; ///< power of two, see isValidPageSize()
    /** kFormatVersion or kFormatVersion2: what commit() states in the header and which section
     *  table rules apply. The pages' contents are the caller's. */
    std::uint32_t formatVersion = kFormatVersion;
};

/**
 * Writes a scene file page by page. Pages are appended in order; page 0 (the header) is written
 * last by commit(). Everything goes to a temporary file beside the final path, which commit()
 * fsyncs and renames into place, so a crash or an error never leaves a half file under the final
 * name. Destroying a writer that was not committed removes the temporary file.
 *
 * Single-threaded: one thread owns a writer.
 */
class SceneWriter {
public:
    /** Creates `<finalPath>.tmp-<pid>` (the directory must exist and be writable). */
    [[nodiscard]] static Result<std::unique_ptr<SceneWriter>> create(
            const std::filesystem::path& finalPath, const SceneWriterOptions& options = {});

    ~SceneWriter();
    SceneWriter(const SceneWriter&) = delete;
    SceneWriter& operator=(const SceneWriter&) = delete;

    std::uint32_t pageSize() const noexcept;
    std::uint32_t formatVersion() const noexcept;
    /** Index the next appended page will get (page 0 is reserved for the header). */
    std::uint64_t nextPageIndex() const noexcept;

    /**
     * Appends one page of type `type` holding `payload` (at most pagePayloadBytes(pageSize());
     * the rest is zero) plus its trailer and checksum. Returns the page's index. Errors: DiskFull,
     * IoError.
     */
    [[nodiscard]] Result<std::uint64_t> appendPage(PageType type, std::span<const std::byte> payload);

    /** One table section's stream, for appendSections(). */
    struct SectionStream {
        SectionType type;
        std::span<const std::byte> bytes;
        std::uint64_t itemCount = 0;
    };

    /** Appends table sections: version 2 packs their streams back to back over shared Table
     *  pages (small sections then cost one page together), version 1 gives each its own pages
     *  (appendSection). Returns their table entries, in order. */
    [[nodiscard]] Result<std::vector<SectionEntry>> appendSections(std::span<const SectionStream> streams);

    /** Appends `bytes` as a section stream over new Table pages; returns its table entry. */
    [[nodiscard]] Result<SectionEntry> appendSection(
            SectionType type, std::span<const std::byte> bytes, std::uint64_t itemCount);

    /**
     * Completes `header` (magic, version, page size and count, struct sizes, section count),
     * writes page 0 with the section table, flushes, fsyncs, renames to the final path and
     * fsyncs the directory. The writer is finished afterwards, whatever the outcome.
     */
    [[nodiscard]] Status commit(FileHeader header, std::span<const SectionEntry> sections);

    const std::filesystem::path& temporaryPath() const noexcept;

private:
    struct Impl;
    explicit SceneWriter(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> mImpl;
};

/** Maximum number of sections that fit in page 0 for a page size. */
std::uint32_t maxSectionCount(std::uint32_t pageSize) noexcept;

} // namespace ff::storage
