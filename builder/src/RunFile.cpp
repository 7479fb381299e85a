#include "RunFile.h"

#include <meshoptimizer.h>

#include <algorithm>

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

/** Before every block: what it holds and how it is encoded (the file's own codec, checked). */
struct BlockHeader {
    std::uint32_t magic;
    std::uint32_t codec; ///< a SpillCodec
    std::uint32_t itemCount;
    std::uint32_t payloadBytes;
};
static_assert(sizeof(BlockHeader) == 16);
constexpr std::uint32_t kBlockMagic = 0x4B4C4246; // "FBLK"

/** The element the vertex codec codes one lane at a time: a triangle's vertex (its three
 *  vertices are three elements, so neighbouring corners delta against each other), else the
 *  whole record. */
template <class Item> constexpr std::size_t kCodecElementBytes = sizeof(Item);
template <> constexpr std::size_t kCodecElementBytes<storage::PackedTriangle> = sizeof(storage::PackedVertex);

template <class Item> constexpr std::size_t kBlockItems = kSpillBlockBytes / sizeof(Item);

template <class Item> constexpr std::size_t elementsOf(std::size_t items) {
    static_assert(sizeof(Item) % kCodecElementBytes<Item> == 0);
    static_assert(kCodecElementBytes<Item> % 4 == 0 && kCodecElementBytes<Item> <= 256); // the codec's limits
    return items * (sizeof(Item) / kCodecElementBytes<Item>);
}

template <class Item> std::size_t encodedBound(SpillCodec codec, std::size_t items) {
    return codec == SpillCodec::Raw ? items * sizeof(Item)
                                    : meshopt_encodeVertexBufferBound(elementsOf<Item>(items), kCodecElementBytes<Item>);
}

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

/** Reads exactly out.size() bytes; false at the end of the file before that. */
Result<bool> readExact(int fd, std::span<std::byte> out, const std::filesystem::path& path) {
    std::size_t done = 0;
    while (done < out.size()) {
        const ssize_t n = ::read(fd, out.data() + done, out.size() - done);
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0)
            return ioStatus(errno, "cannot read spill file", path);
        if (n == 0)
            return false;
        done += static_cast<std::size_t>(n);
    }
    return true;
}

} // namespace

std::string_view spillCodecName(SpillCodec codec) noexcept {
    return codec == SpillCodec::Raw ? "raw" : "compact";
}

std::optional<SpillCodec> parseSpillCodec(std::string_view name) noexcept {
    if (name == "raw")
        return SpillCodec::Raw;
    if (name == "compact")
        return SpillCodec::Compact;
    return std::nullopt;
}

Status ioStatus(int error, const std::string& what, const std::filesystem::path& path) {
    const ErrorCode code = (error == ENOSPC || error == EDQUOT) ? ErrorCode::DiskFull : ErrorCode::IoError;
    return {code, what + " " + path.string() + ": " + std::strerror(error)};
}

template <class Item>
SpillFile<Item>::SpillFile(std::filesystem::path path, SpillCodec codec)
    : mPath(std::move(path))
    , mCodec(codec) {}

template <class Item>
SpillFile<Item>::~SpillFile() { remove(); }

template <class Item>
SpillFile<Item>::SpillFile(SpillFile&& other) noexcept
    : mPath(std::move(other.mPath))
    , mCodec(other.mCodec)
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
    // One encoder buffer per thread (a block's bound, ~1 MiB), reused: idle files hold none,
    // and a write does not pay a fresh allocation's zeroing and page faults.
    thread_local std::vector<unsigned char> scratch;
    for (const std::span<const Item> items : {std::span<const Item>(mBuffer), more}) {
        for (std::size_t at = 0; at < items.size(); at += kBlockItems<Item>)
            FF_RETURN_IF_ERROR(writeBlock(fd.get(), items.subspan(at, std::min(kBlockItems<Item>, items.size() - at)), scratch));
    }
    if (::close(fd.release()) != 0)
        return ioStatus(errno, "cannot close", mPath);
    mBuffer.clear();
    mBuffer.shrink_to_fit(); // idle spill files should not pin their peak buffer
    return Status::ok();
}

template <class Item>
Status SpillFile<Item>::writeBlock(int fd, std::span<const Item> items, std::vector<unsigned char>& scratch) {
    std::span<const std::byte> payload = std::as_bytes(items);
    if (mCodec == SpillCodec::Compact) {
        scratch.resize(std::max(scratch.size(), encodedBound<Item>(mCodec, items.size())));
        const std::size_t n = meshopt_encodeVertexBuffer(
                scratch.data(), scratch.size(), items.data(), elementsOf<Item>(items.size()), kCodecElementBytes<Item>);
        if (n == 0)
            return Status(ErrorCode::Internal, "cannot encode a block of spill file " + mPath.string());
        payload = std::as_bytes(std::span(scratch.data(), n));
    }
    const BlockHeader header{kBlockMagic, static_cast<std::uint32_t>(mCodec), static_cast<std::uint32_t>(items.size()),
                             static_cast<std::uint32_t>(payload.size())};
    FF_RETURN_IF_ERROR(writeAll(fd, reinterpret_cast<const std::byte*>(&header), sizeof(header), mPath));
    FF_RETURN_IF_ERROR(writeAll(fd, payload.data(), payload.size(), mPath));
    mBytesWritten += sizeof(header) + payload.size();
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
    const std::size_t most = std::max<std::size_t>(batchSize, 1);
    const auto corrupt = [this](std::uint64_t at, const std::string& what) {
        return Status(ErrorCode::IoError,
                      "spill file " + mPath.string() + ": block at byte " + std::to_string(at) + " " + what);
    };
    std::vector<Item> block;
    std::vector<unsigned char> encoded;
    std::uint64_t remaining = mCount;
    std::uint64_t bytesRead = 0;
    while (remaining > 0) {
        BlockHeader header{};
        FF_ASSIGN_OR_RETURN(const bool got, readExact(fd.get(), std::as_writable_bytes(std::span(&header, 1)), mPath));
        if (!got)
            return Status(ErrorCode::IoError, "spill file " + mPath.string() + " is shorter than written");
        // Our own file, but on a disk: a block that does not say what was written is an error.
        if (header.magic != kBlockMagic || header.codec != static_cast<std::uint32_t>(mCodec) ||
            header.itemCount == 0 || header.itemCount > kBlockItems<Item> || header.itemCount > remaining ||
            header.payloadBytes > encodedBound<Item>(mCodec, header.itemCount) ||
            (mCodec == SpillCodec::Raw && header.payloadBytes != header.itemCount * sizeof(Item)))
            return corrupt(bytesRead, "has a bad header");
        block.resize(header.itemCount);
        std::span<std::byte> payload = std::as_writable_bytes(std::span(block));
        if (mCodec == SpillCodec::Compact) {
            encoded.resize(header.payloadBytes);
            payload = std::as_writable_bytes(std::span(encoded));
        }
        FF_ASSIGN_OR_RETURN(const bool whole, readExact(fd.get(), payload.first(header.payloadBytes), mPath));
        if (!whole)
            return Status(ErrorCode::IoError, "spill file " + mPath.string() + " is shorter than written");
        if (mCodec == SpillCodec::Compact &&
            meshopt_decodeVertexBuffer(block.data(), elementsOf<Item>(block.size()), kCodecElementBytes<Item>, encoded.data(),
                                       encoded.size()) != 0)
            return corrupt(bytesRead, "does not decode");
        for (std::size_t at = 0; at < block.size(); at += most)
            FF_RETURN_IF_ERROR(visit(std::span(block).subspan(at, std::min(most, block.size() - at))));
        remaining -= header.itemCount;
        bytesRead += sizeof(header) + header.payloadBytes;
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
template class SpillFile<PendingNodeV2>;

} // namespace ff::builder
