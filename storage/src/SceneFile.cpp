#include "PosixError.h"
#include "ReaderChecks.h"

#include <ff/storage/PageCheck.h>
#include <ff/storage/SceneFile.h>

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <string>

namespace ff::storage {

using detail::checkType;
using detail::corrupt;
using detail::maskOf;
using detail::PageTypeMask;

namespace {

// verified[] states. The page type is not cached: it is checked on every access (16 bytes), so
// one intact page can be asked for under any expected type and get the right answer.
constexpr std::uint8_t kUnverified = 0;
constexpr std::uint8_t kIntact = 1;

// verifyAll() reports progress after this many pages.
constexpr std::uint64_t kProgressInterval = 256;

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
    /** The mapped pages as an IPageSource: how the index is read, and what source() serves. */
    class MappedSource final : public IPageSource {
    public:
        explicit MappedSource(const Impl& file) : mFile(file) {}
        std::uint32_t pageSize() const override { return mFile.pageSize; }
        std::uint64_t pageCount() const override { return mFile.pageCount; }
        Status readPage(std::uint64_t index, std::span<std::byte> out) override {
            FF_ASSIGN_OR_RETURN(const PagePin pin, pinPage(index));
            FF_ASSERT(out.size() == pin.bytes().size());
            std::memcpy(out.data(), pin.bytes().data(), out.size());
            return Status::ok();
        }
        /** A view into the mapping, which outlives every use of the file. */
        Result<PagePin> pinPage(std::uint64_t index) override {
            FF_RETURN_IF_ERROR(mFile.verify(index, ~PageTypeMask{0}));
            return PagePin(mFile.page(index), nullptr);
        }

    private:
        const Impl& mFile;
    };

    std::filesystem::path path;
    Mapping mapping;
    std::span<const std::byte> bytes; ///< the whole file
    std::uint32_t pageSize = 0;
    std::uint64_t pageCount = 0;
    std::uint32_t trianglesPerPage = 0;
    std::uint32_t nodesPerPage = 0;
    /** Per page: kUnverified or kIntact (trailer magic, checksum and index passed). Racing
     *  verifiers of one page compute the same answer over immutable bytes and store the same
     *  value, so the only shared state is this byte. */
    std::unique_ptr<std::atomic<std::uint8_t>[]> verified;
    MappedSource source{*this};

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

    /** The page layout from the mapped bytes (probePageSize, checkPageLayout). */
    Status readLayout() {
        FF_ASSIGN_OR_RETURN(pageSize, probePageSize(bytes.first(std::min(bytes.size(), sizeof(FileHeader))), bytes.size()));
        FF_ASSIGN_OR_RETURN(const PageLayout layout, checkPageLayout(bytes.first(pageSize), bytes.size()));
        pageCount = layout.pageCount;
        nodesPerPage = ff::storage::nodesPerPage(pageSize);
        trianglesPerPage = ff::storage::trianglesPerPage(pageSize);
        verified = std::make_unique<std::atomic<std::uint8_t>[]>(static_cast<std::size_t>(pageCount));
        verified[0].store(kIntact, std::memory_order_release);
        return Status::ok();
    }
};

// ---- open ---------------------------------------------------------------------------------

SceneFile::SceneFile(SceneIndex index, std::unique_ptr<Impl> impl)
    : SceneIndex(std::move(index))
    , mImpl(std::move(impl)) {}

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
    FF_RETURN_IF_ERROR(impl->readLayout());
    FF_ASSIGN_OR_RETURN(SceneIndex index, SceneIndex::read(impl->source));
    std::unique_ptr<SceneFile> file(new SceneFile(std::move(index), std::move(impl)));
    if (options.verifyEveryPage)
        FF_RETURN_IF_ERROR(file->verifyAll());
    return file;
}

// ---- accessors ----------------------------------------------------------------------------

const std::filesystem::path& SceneFile::path() const noexcept {
    return mImpl->path;
}

IPageSource& SceneFile::source() const noexcept {
    return mImpl->source;
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

Result<NodeRecord> SceneFile::child(const NodeRecord& parent, std::uint32_t index) const {
    if (index >= parent.childCount)
        return Status{
                ErrorCode::InvalidArgument,
                "child index " + std::to_string(index) + " out of range (the node has " +
                        std::to_string(parent.childCount) + " children)"};
    return node(childRef(parent, index));
}

// ---- geometry -----------------------------------------------------------------------------

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
        FF_RETURN_IF_ERROR(f.verify(i, allowedPageTypes(i)));
        if (progress && ((i + 1) % kProgressInterval == 0 || i + 1 == f.pageCount))
            progress(i + 1, f.pageCount);
    }
    return Status::ok();
}

} // namespace ff::storage
