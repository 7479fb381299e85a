#include <ff/cache/ScenePageSource.h>
#include <ff/storage/PageCheck.h>
#include <ff/storage/SceneIndex.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

namespace ff::cache {

namespace {

Status ioError(int err, const std::string& what) {
    const ErrorCode code = err == ENOENT ? ErrorCode::NotFound : ErrorCode::IoError;
    return {code, what + ": " + std::generic_category().message(err)};
}

/** Reads bytes [offset, offset + out.size()) or fewer at the end of the file; how many. `what`
 *  (a function: the message is built only on error) names the read in an I/O error. */
template <typename What>
Result<std::size_t> readAt(int fd, std::uint64_t offset, std::span<std::byte> out, const What& what) {
    std::size_t done = 0;
    while (done < out.size()) {
        const ssize_t n = ::pread(fd, out.data() + done, out.size() - done, static_cast<off_t>(offset + done));
        if (n < 0) {
            const int err = errno; // before `what` allocates
            if (err == EINTR)
                continue;
            return ioError(err, what());
        }
        if (n == 0)
            break;
        done += static_cast<std::size_t>(n);
    }
    return done;
}

} // namespace

Result<std::unique_ptr<ScenePageSource>> ScenePageSource::open(const std::filesystem::path& path) {
    const std::string name = path.string();
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return ioError(errno, "cannot open scene file " + name);
    std::unique_ptr<ScenePageSource> source(new ScenePageSource(path, fd, 0, 0));

    struct stat st {};
    if (::fstat(fd, &st) != 0)
        return ioError(errno, "cannot stat scene file " + name);
    if (!S_ISREG(st.st_mode))
        return Status{ErrorCode::InvalidArgument, name + " is not a regular file"};
    const auto fileSize = static_cast<std::uint64_t>(st.st_size);
    const auto what = [&name] { return "cannot read scene file " + name; };

    // The layout as the mapped reader learns it (storage::probePageSize, checkPageLayout), from
    // our own descriptor: the per-page index and checksum catch a file replaced later.
    std::array<std::byte, sizeof(storage::FileHeader)> start{};
    FF_ASSIGN_OR_RETURN(const std::size_t got, readAt(fd, 0, start, what));
    FF_ASSIGN_OR_RETURN(const std::uint32_t pageSize, storage::probePageSize(std::span(start).first(got), fileSize));
    std::vector<std::byte> page0(pageSize);
    FF_ASSIGN_OR_RETURN(const std::size_t got0, readAt(fd, 0, page0, what));
    if (got0 != page0.size())
        return Status{ErrorCode::Corrupt, name + ": the file changed while being opened"};
    FF_ASSIGN_OR_RETURN(const storage::PageLayout layout, storage::checkPageLayout(page0, fileSize));
    source->mPageSize = layout.pageSize;
    source->mPageCount = layout.pageCount;
    return source;
}

ScenePageSource::ScenePageSource(
        std::filesystem::path path, int fd, std::uint32_t pageSize, std::uint64_t pageCount)
    : mPath(std::move(path))
    , mFd(fd)
    , mPageSize(pageSize)
    , mPageCount(pageCount) {}

ScenePageSource::~ScenePageSource() {
    if (mFd >= 0)
        ::close(mFd);
}

std::uint32_t ScenePageSource::pageSize() const {
    return mPageSize;
}

std::uint64_t ScenePageSource::pageCount() const {
    return mPageCount;
}

const std::filesystem::path& ScenePageSource::path() const noexcept {
    return mPath;
}

Status ScenePageSource::readPage(std::uint64_t index, std::span<std::byte> out) {
    FF_ASSERT(out.size() == mPageSize);
    if (index >= mPageCount)
        return Status{
                ErrorCode::Corrupt,
                "page " + std::to_string(index) + ": beyond end of file (the file has " +
                        std::to_string(mPageCount) + " pages)"};
    FF_ASSIGN_OR_RETURN(
            const std::size_t got,
            readAt(mFd, index * mPageSize, out, [&] {
                return "page " + std::to_string(index) + ": cannot read scene file " + mPath.string();
            }));
    if (got != out.size())
        return Status{
                ErrorCode::Corrupt,
                "page " + std::to_string(index) +
                        ": beyond end of file (the file shrank since it was opened)"};
    return storage::verifyPageBytes(out, index);
}

} // namespace ff::cache
