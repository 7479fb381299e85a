#include "RunFile.h"

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <unistd.h>

namespace ff::builder {

namespace {

class FileDescriptor {
public:
    explicit FileDescriptor(int fd) : mFd(fd) {}
    ~FileDescriptor() {
        if (mFd >= 0)
            ::close(mFd);
    }
    FileDescriptor(const FileDescriptor&) = delete;
    FileDescriptor& operator=(const FileDescriptor&) = delete;
    int get() const { return mFd; }
    int release() {
        const int fd = mFd;
        mFd = -1;
        return fd;
    }

private:
    int mFd;
};

Status writeAll(int fd, const std::byte* data, std::size_t size, const std::filesystem::path& path) {
    while (size > 0) {
        const ssize_t n = ::write(fd, data, size);
        if (n < 0) {
            if (errno == EINTR)
                continue;
            return ioStatus(errno, "cannot write", path);
        }
        data += n;
        size -= static_cast<std::size_t>(n);
    }
    return Status::ok();
}

} // namespace

Status ioStatus(int error, const std::string& what, const std::filesystem::path& path) {
    const ErrorCode code = (error == ENOSPC || error == EDQUOT) ? ErrorCode::DiskFull : ErrorCode::IoError;
    return {code, what + " " + path.string() + ": " + std::strerror(error)};
}

template <class Item>
SpillFile<Item>::SpillFile(std::filesystem::path path) : mPath(std::move(path)) {}

template <class Item>
SpillFile<Item>::~SpillFile() { remove(); }

template <class Item>
SpillFile<Item>::SpillFile(SpillFile&& other) noexcept
    : mPath(std::move(other.mPath))
    , mBuffer(std::move(other.mBuffer))
    , mBufferLimitBytes(other.mBufferLimitBytes)
    , mCount(other.mCount)
    , mBytesWritten(other.mBytesWritten)
    , mCreated(other.mCreated) {
    other.mCreated = false;
    other.mPath.clear();
}

template <class Item>
Status SpillFile<Item>::append(std::span<const Item> items) {
    mCount += items.size();
    if (bufferedBytes() + items.size_bytes() < mBufferLimitBytes) {
        mBuffer.insert(mBuffer.end(), items.begin(), items.end());
        return Status::ok();
    }
    return writeOut(items); // straight from the caller's memory: no copy of a large append
}

template <class Item>
Status SpillFile<Item>::flush() {
    if (mBuffer.empty() && mCreated)
        return Status::ok();
    return writeOut({});
}

template <class Item>
Status SpillFile<Item>::writeOut(std::span<const Item> more) {
    const int flags = O_WRONLY | O_CREAT | O_CLOEXEC | (mCreated ? O_APPEND : O_TRUNC);
    FileDescriptor fd(::open(mPath.c_str(), flags, 0600));
    if (fd.get() < 0)
        return ioStatus(errno, "cannot open spill file", mPath);
    mCreated = true;
    for (const auto bytes : {std::as_bytes(std::span(mBuffer)), std::as_bytes(more)}) {
        FF_RETURN_IF_ERROR(writeAll(fd.get(), bytes.data(), bytes.size(), mPath));
        mBytesWritten += bytes.size();
    }
    if (::close(fd.release()) != 0)
        return ioStatus(errno, "cannot close", mPath);
    mBuffer.clear();
    mBuffer.shrink_to_fit(); // idle spill files should not pin their peak buffer
    return Status::ok();
}

template <class Item>
Status SpillFile<Item>::forEachBatch(
        std::size_t batchSize,
        const std::function<Status(std::span<const Item>)>& visit) {
    return readBatches(batchSize, O_RDONLY, visit, {});
}

template <class Item>
Result<std::uint64_t> SpillFile<Item>::consumeBatches(
        std::size_t batchSize,
        const std::function<Status(std::span<const Item>)>& visit) {
    std::uint64_t released = 0;
    bool punching = true;
    // In whole MiB: few calls, and a partly read file-system block must keep its data anyway.
    constexpr std::uint64_t kBlock = 1u << 20;
    const Status status = readBatches(batchSize, O_RDWR, visit, [&](int fd, std::uint64_t bytesRead) {
        const std::uint64_t end = bytesRead / kBlock * kBlock;
        if (!punching || end <= released)
            return;
        if (::fallocate(fd, FALLOC_FL_PUNCH_HOLE | FALLOC_FL_KEEP_SIZE, static_cast<off_t>(released),
                        static_cast<off_t>(end - released)) == 0)
            released = end;
        else
            punching = false; // not supported here (or failing): the space comes back at remove()
    });
    remove();
    if (!status.isOk())
        return status;
    return released;
}

template <class Item>
Status SpillFile<Item>::readBatches(
        std::size_t batchSize,
        int openFlags,
        const std::function<Status(std::span<const Item>)>& visit,
        const std::function<void(int fd, std::uint64_t bytesRead)>& afterBatch) {
    FF_RETURN_IF_ERROR(flush());
    FileDescriptor fd(::open(mPath.c_str(), openFlags | O_CLOEXEC));
    if (fd.get() < 0)
        return ioStatus(errno, "cannot open spill file", mPath);
    std::vector<Item> batch(std::max<std::size_t>(batchSize, 1));
    std::uint64_t remaining = mCount;
    std::uint64_t bytesRead = 0;
    while (remaining > 0) {
        const std::size_t want = static_cast<std::size_t>(std::min<std::uint64_t>(remaining, batch.size()));
        auto* out = reinterpret_cast<char*>(batch.data());
        std::size_t bytes = want * sizeof(Item);
        while (bytes > 0) {
            const ssize_t n = ::read(fd.get(), out, bytes);
            if (n < 0 && errno == EINTR)
                continue;
            if (n < 0)
                return ioStatus(errno, "cannot read spill file", mPath);
            if (n == 0)
                return Status(ErrorCode::IoError, "spill file " + mPath.string() + " is shorter than written");
            out += n;
            bytes -= static_cast<std::size_t>(n);
        }
        FF_RETURN_IF_ERROR(visit(std::span(batch.data(), want)));
        remaining -= want;
        bytesRead += want * sizeof(Item);
        if (afterBatch)
            afterBatch(fd.get(), bytesRead);
    }
    return Status::ok();
}

template <class Item>
Result<std::vector<Item>> SpillFile<Item>::readAll() {
    std::vector<Item> all;
    all.reserve(static_cast<std::size_t>(mCount));
    FF_RETURN_IF_ERROR(forEachBatch(1u << 16, [&all](std::span<const Item> batch) {
        all.insert(all.end(), batch.begin(), batch.end());
        return Status::ok();
    }));
    return all;
}

template <class Item>
void SpillFile<Item>::remove() noexcept {
    if (mCreated && !mPath.empty())
        ::unlink(mPath.c_str());
    mCreated = false;
    mBuffer.clear();
    mBuffer.shrink_to_fit();
    mCount = 0;
}

template class SpillFile<storage::PackedTriangle>;
template class SpillFile<storage::NodeRecord>;

} // namespace ff::builder
