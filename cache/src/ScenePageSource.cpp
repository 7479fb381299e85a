#include <ff/cache/ScenePageSource.h>
#include <ff/storage/PageCheck.h>
#include <ff/storage/SceneFile.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <string>
#include <system_error>
#include <utility>

namespace ff::cache {

namespace {

Status ioError(int err, const std::string& what) {
    const ErrorCode code = err == ENOENT ? ErrorCode::NotFound : ErrorCode::IoError;
    return {code, what + ": " + std::generic_category().message(err)};
}

} // namespace

Result<std::unique_ptr<ScenePageSource>> ScenePageSource::open(const std::filesystem::path& path) {
    const std::string name = path.string();
    // Our descriptor first, then the header check: should the path be replaced in between, the
    // size check below or the per-page index and checksum catch it.
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return ioError(errno, "cannot open scene file " + name);
    std::unique_ptr<ScenePageSource> source(new ScenePageSource(path, fd, 0, 0));

    auto file = storage::SceneFile::open(path);
    if (!file.isOk())
        return file.status().withContext(name);
    source->mPageSize = (*file)->pageSize();
    source->mPageCount = (*file)->pageCount();

    struct stat st {};
    if (::fstat(fd, &st) != 0)
        return ioError(errno, "cannot stat scene file " + name);
    const std::uint64_t expected = source->mPageCount * source->mPageSize;
    if (static_cast<std::uint64_t>(st.st_size) != expected)
        return Status{
                ErrorCode::Corrupt,
                name + ": the file changed while being opened (" + std::to_string(st.st_size) +
                        " bytes, the header says " + std::to_string(expected) + ")"};
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
    const std::uint64_t base = index * mPageSize;
    std::size_t done = 0;
    while (done < out.size()) {
        const ssize_t n =
                ::pread(mFd, out.data() + done, out.size() - done, static_cast<off_t>(base + done));
        if (n < 0) {
            if (errno == EINTR)
                continue;
            return ioError(
                    errno,
                    "page " + std::to_string(index) + ": cannot read scene file " + mPath.string());
        }
        if (n == 0)
            return Status{
                    ErrorCode::Corrupt,
                    "page " + std::to_string(index) +
                            ": beyond end of file (the file shrank since it was opened)"};
        done += static_cast<std::size_t>(n);
    }
    return storage::verifyPageBytes(out, index);
}

} // namespace ff::cache
