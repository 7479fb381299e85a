#include "PageChecksum.h"
#include "PosixError.h"
#include "SectionTable.h"

#include <ff/storage/SceneWriter.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <limits>
#include <string>
#include <system_error>
#include <vector>

namespace ff::storage {

namespace {

// Pages are collected into a buffer of about this size before one pwrite, so a writer appending
// 4 KiB pages does not make one system call per page.
constexpr std::size_t kWriteBufferBytes = 1u << 20;

/** pwrite all of `bytes` at `offset`, retrying on EINTR and short writes. Returns 0 or errno. */
int writeAll(int fd, const std::byte* bytes, std::size_t size, std::uint64_t offset) noexcept {
    while (size > 0) {
        const ssize_t n = ::pwrite(fd, bytes, size, static_cast<off_t>(offset));
        if (n < 0) {
            if (errno == EINTR)
                continue;
            return errno;
        }
        if (n == 0)
            return ENOSPC; // no progress and no error: the device accepts nothing more
        const auto written = static_cast<std::size_t>(n);
        bytes += written;
        size -= written;
        offset += written;
    }
    return 0;
}

/** Makes a rename in `dir` durable. Filesystems that cannot sync directories are accepted. */
int syncDirectory(const std::filesystem::path& dir) noexcept {
    const int fd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0)
        return errno;
    int err = 0;
    if (::fsync(fd) != 0 && errno != EINVAL && errno != EROFS)
        err = errno;
    ::close(fd);
    return err;
}

} // namespace

struct SceneWriter::Impl {
    std::filesystem::path finalPath;
    std::filesystem::path tempPath;
    std::uint32_t pageSize = 0;
    std::uint32_t formatVersion = kFormatVersion;
    int fd = -1;
    std::uint64_t nextPage = 1;     ///< page 0 is written by commit()
    std::uint64_t flushedPages = 1; ///< pages [1, flushedPages) are in the file
    std::vector<std::byte> buffer;  ///< pages [flushedPages, nextPage)
    std::size_t bufferedBytes = 0;
    Status failure;         ///< sticky: the first I/O error ends the file
    bool finished = false;  ///< commit() was called
    bool committed = false; ///< the file is under its final name

    ~Impl() { abandon(); }

    /** Closes and removes the temporary file (frees the space at once on a full disk). */
    void abandon() noexcept {
        if (fd >= 0) {
            ::close(fd);
            fd = -1;
        }
        if (!committed && !tempPath.empty()) {
            ::unlink(tempPath.c_str());
            tempPath.clear();
        }
    }

    Status fail(Status status) {
        failure = status;
        abandon();
        return status;
    }

    Status writeError(int err) {
        return fail(posixError(err, "cannot write " + tempPath.string()));
    }

    Status flush() {
        if (bufferedBytes == 0)
            return Status::ok();
        const int err = writeAll(fd, buffer.data(), bufferedBytes, flushedPages * pageSize);
        if (err != 0)
            return writeError(err);
        flushedPages += bufferedBytes / pageSize;
        bufferedBytes = 0;
        return Status::ok();
    }

    Status usable() const {
        if (finished)
            return {ErrorCode::InvalidArgument,
                    "scene writer for " + finalPath.string() + " is already committed"};
        return failure;
    }
};

SceneWriter::SceneWriter(std::unique_ptr<Impl> impl)
    : mImpl(std::move(impl)) {}

SceneWriter::~SceneWriter() = default;

Result<std::unique_ptr<SceneWriter>>
SceneWriter::create(const std::filesystem::path& finalPath, const SceneWriterOptions& options) {
    if (!isValidPageSize(options.pageSize))
        return Status{
                ErrorCode::InvalidArgument,
                "page size " + std::to_string(options.pageSize) + " is not a power of two in [" +
                        std::to_string(kMinPageSize) + ", " + std::to_string(kMaxPageSize) + "]"};
    if (finalPath.empty() || !finalPath.has_filename())
        return Status{
                ErrorCode::InvalidArgument,
                "scene file path '" + finalPath.string() + "' does not name a file"};
    std::error_code ec;
    if (std::filesystem::is_directory(finalPath, ec))
        return Status{
                ErrorCode::InvalidArgument,
                "cannot write scene file " + finalPath.string() + ": it is a directory"};

    auto impl = std::make_unique<Impl>();
    impl->finalPath = finalPath;
    impl->pageSize = options.pageSize;
    if (options.formatVersion != kFormatVersion && options.formatVersion != kFormatVersion2)
        return Status{
                ErrorCode::InvalidArgument,
                "format version " + std::to_string(options.formatVersion) + " is not one this build writes"};
    impl->formatVersion = options.formatVersion;
    impl->tempPath = finalPath;
    impl->tempPath += ".tmp-" + std::to_string(::getpid());
    impl->buffer.resize(std::max<std::size_t>(kWriteBufferBytes, options.pageSize));

    impl->fd = ::open(impl->tempPath.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (impl->fd < 0) {
        const int err = errno;
        const std::string tempName = impl->tempPath.string();
        impl->tempPath.clear(); // not ours: nothing to remove
        return posixError(
                err,
                "cannot create temporary file " + tempName + " for scene file " +
                        finalPath.string());
    }
    return std::unique_ptr<SceneWriter>(new SceneWriter(std::move(impl)));
}

std::uint32_t SceneWriter::pageSize() const noexcept {
    return mImpl->pageSize;
}

std::uint32_t SceneWriter::formatVersion() const noexcept {
    return mImpl->formatVersion;
}

std::uint64_t SceneWriter::nextPageIndex() const noexcept {
    return mImpl->nextPage;
}

const std::filesystem::path& SceneWriter::temporaryPath() const noexcept {
    return mImpl->tempPath;
}

Result<std::uint64_t> SceneWriter::appendPage(PageType type, std::span<const std::byte> payload) {
    Impl& w = *mImpl;
    FF_RETURN_IF_ERROR(w.usable());
    if (type != PageType::Nodes && type != PageType::Geometry && type != PageType::Table)
        return Status{
                ErrorCode::InvalidArgument,
                std::string("cannot append a page of type ") +
                        pageTypeName(static_cast<std::uint16_t>(type)) +
                        " (page 0 is written by commit())"};
    const std::uint32_t payloadBytes = pagePayloadBytes(w.pageSize);
    if (payload.size() > payloadBytes)
        return Status{
                ErrorCode::InvalidArgument,
                "page payload of " + std::to_string(payload.size()) + " bytes exceeds the " +
                        std::to_string(payloadBytes) + " bytes of a " + std::to_string(w.pageSize) +
                        "-byte page"};
    if (w.nextPage > std::numeric_limits<std::uint32_t>::max())
        return Status{
                ErrorCode::Unsupported,
                "scene file " + w.finalPath.string() + " would exceed 2^32 pages"};

    if (w.bufferedBytes + w.pageSize > w.buffer.size())
        FF_RETURN_IF_ERROR(w.flush());

    const std::span<std::byte> page(w.buffer.data() + w.bufferedBytes, w.pageSize);
    if (!payload.empty())
        std::memcpy(page.data(), payload.data(), payload.size());
    std::memset(page.data() + payload.size(), 0, w.pageSize - payload.size());
    sealPage(page, static_cast<std::uint32_t>(w.nextPage), type);
    w.bufferedBytes += w.pageSize;
    return w.nextPage++;
}

Result<SectionEntry> SceneWriter::appendSection(
        SectionType type, std::span<const std::byte> bytes, std::uint64_t itemCount) {
    FF_RETURN_IF_ERROR(mImpl->usable());
    const auto typeValue = static_cast<std::uint32_t>(type);
    const bool v2Section = type == SectionType::NodePages && mImpl->formatVersion >= kFormatVersion2;
    if (type != SectionType::Prototypes && type != SectionType::Instances &&
        type != SectionType::Metadata && !v2Section)
        return Status{
                ErrorCode::InvalidArgument,
                std::string("section type ") + sectionTypeName(typeValue) +
                        " has no byte stream; build its SectionEntry directly"};
    const std::size_t recordSize = sectionRecordSize(typeValue, mImpl->formatVersion);
    if (recordSize != 0 &&
        (bytes.size() % recordSize != 0 || bytes.size() / recordSize != itemCount))
        return Status{
                ErrorCode::InvalidArgument,
                std::string(sectionTypeName(typeValue)) +
                        " section: " + std::to_string(bytes.size()) + " bytes do not hold " +
                        std::to_string(itemCount) + " records of " + std::to_string(recordSize) +
                        " bytes"};

    SectionEntry entry{};
    entry.type = typeValue;
    entry.firstPage = mImpl->nextPage;
    entry.byteLength = bytes.size();
    entry.itemCount = itemCount;
    const std::size_t payloadBytes = pagePayloadBytes(mImpl->pageSize);
    for (std::size_t at = 0; at < bytes.size(); at += payloadBytes) {
        const std::size_t n = std::min(payloadBytes, bytes.size() - at);
        const Result<std::uint64_t> page = appendPage(PageType::Table, bytes.subspan(at, n));
        if (!page)
            return page.status();
        ++entry.pageCount;
    }
    return entry;
}

Result<std::vector<SectionEntry>> SceneWriter::appendSections(std::span<const SectionStream> streams) {
    FF_RETURN_IF_ERROR(mImpl->usable());
    std::vector<SectionEntry> entries;
    if (mImpl->formatVersion < kFormatVersion2) {
        for (const SectionStream& s : streams) {
            FF_ASSIGN_OR_RETURN(SectionEntry entry, appendSection(s.type, s.bytes, s.itemCount));
            entries.push_back(entry);
        }
        return entries;
    }
    const std::uint64_t payload = pagePayloadBytes(mImpl->pageSize);
    std::vector<std::byte> packed;
    for (const SectionStream& s : streams) {
        // The checks appendSection makes, on a stream that is not written yet.
        const auto typeValue = static_cast<std::uint32_t>(s.type);
        if (s.type == SectionType::Hierarchy)
            return Status{ErrorCode::InvalidArgument, "a Hierarchy section has no byte stream"};
        const std::size_t recordSize = sectionRecordSize(typeValue, mImpl->formatVersion);
        if (recordSize != 0 && (s.bytes.size() % recordSize != 0 || s.bytes.size() / recordSize != s.itemCount))
            return Status{
                    ErrorCode::InvalidArgument,
                    std::string(sectionTypeName(typeValue)) + " section: " + std::to_string(s.bytes.size()) +
                            " bytes do not hold " + std::to_string(s.itemCount) + " records of " +
                            std::to_string(recordSize) + " bytes"};
        SectionEntry entry{};
        entry.type = typeValue;
        entry.firstPage = mImpl->nextPage + packed.size() / payload;
        entry.offset = static_cast<std::uint32_t>(packed.size() % payload);
        entry.byteLength = s.bytes.size();
        entry.itemCount = s.itemCount;
        entry.pageCount = s.bytes.empty() ? 0 : (entry.offset + s.bytes.size() + payload - 1) / payload;
        packed.insert(packed.end(), s.bytes.begin(), s.bytes.end());
        entries.push_back(entry);
    }
    for (std::size_t at = 0; at < packed.size(); at += payload) {
        const std::size_t n = std::min<std::size_t>(payload, packed.size() - at);
        FF_RETURN_IF_ERROR(appendPage(PageType::Table, std::span(packed).subspan(at, n)).status());
    }
    return entries;
}

Status SceneWriter::commit(FileHeader header, std::span<const SectionEntry> sections) {
    Impl& w = *mImpl;
    FF_RETURN_IF_ERROR(w.usable());
    w.finished = true;

    const std::uint32_t maxSections = maxSectionCount(w.pageSize);
    if (sections.size() > maxSections)
        return w.fail(
                {ErrorCode::InvalidArgument,
                 "cannot commit " + w.finalPath.string() + ": " + std::to_string(sections.size()) +
                         " sections, page 0 holds at most " + std::to_string(maxSections)});
    const std::string problem = findSectionTableProblem(sections, w.nextPage, w.pageSize, w.formatVersion);
    if (!problem.empty())
        return w.fail(
                {ErrorCode::InvalidArgument,
                 "cannot commit " + w.finalPath.string() + ": " + problem});

    header.magic = kFileMagic;
    header.formatVersion = w.formatVersion;
    header.pageSize = w.pageSize;
    header.pageCount = w.nextPage;
    const StructSizes sizes = structSizesOf(w.formatVersion);
    header.headerSize = sizes.header;
    header.sectionEntrySize = sizes.sectionEntry;
    header.nodeRecordSize = sizes.nodeRecord;
    header.triangleSize = sizes.triangleOrRepresentation;
    header.prototypeRecordSize = sizes.prototypeRecord;
    header.instanceRecordSize = sizes.instanceRecord;
    header.sectionCount = static_cast<std::uint32_t>(sections.size());

    FF_RETURN_IF_ERROR(w.flush());

    std::vector<std::byte> page0(w.pageSize);
    std::memcpy(page0.data(), &header, sizeof(header));
    if (!sections.empty())
        std::memcpy(page0.data() + sizeof(header), sections.data(), sections.size_bytes());
    sealPage(page0, 0, PageType::Header);
    if (const int err = writeAll(w.fd, page0.data(), page0.size(), 0); err != 0)
        return w.writeError(err);

    if (::fsync(w.fd) != 0)
        return w.fail(posixError(errno, "cannot sync " + w.tempPath.string()));
    const int fd = w.fd;
    w.fd = -1;
    if (::close(fd) != 0)
        return w.fail(posixError(errno, "cannot close " + w.tempPath.string()));
    if (::rename(w.tempPath.c_str(), w.finalPath.c_str()) != 0)
        return w.fail(posixError(
                errno, "cannot rename " + w.tempPath.string() + " to " + w.finalPath.string()));
    w.committed = true;
    if (const int err = syncDirectory(w.finalPath.parent_path()); err != 0)
        return posixError(err, "wrote " + w.finalPath.string() + " but cannot sync its directory");
    return Status::ok();
}

std::uint32_t maxSectionCount(std::uint32_t pageSize) noexcept {
    if (!isValidPageSize(pageSize))
        return 0;
    return static_cast<std::uint32_t>(
            (pagePayloadBytes(pageSize) - sizeof(FileHeader)) / sizeof(SectionEntry));
}

} // namespace ff::storage
