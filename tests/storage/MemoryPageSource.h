#pragma once

// A scene file's bytes in memory, served page by page as a range server would: its layout is
// learnt from the bytes exactly as a file source learns it (probePageSize, checkPageLayout), and
// every page is verified as it is read. Counts the reads of each page. For the tests that show
// the scene index and a whole streaming session need no file.

#include <ff/storage/PageCheck.h>
#include <ff/storage/PageSource.h>
#include <ff/storage/SceneIndex.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace ff::storage::test {

class MemoryPageSource final : public IPageSource {
public:
    static Result<std::unique_ptr<MemoryPageSource>> open(std::vector<std::byte> bytes) {
        std::unique_ptr<MemoryPageSource> source(new MemoryPageSource(std::move(bytes)));
        const std::span<const std::byte> all(source->mBytes);
        FF_ASSIGN_OR_RETURN(
                const std::uint32_t pageSize,
                probePageSize(all.first(std::min(all.size(), sizeof(FileHeader))), all.size()));
        FF_ASSIGN_OR_RETURN(source->mLayout, checkPageLayout(all.first(pageSize), all.size()));
        return source;
    }

    std::uint32_t pageSize() const override { return mLayout.pageSize; }
    std::uint64_t pageCount() const override { return mLayout.pageCount; }
    Status readPage(std::uint64_t index, std::span<std::byte> out) override {
        {
            std::lock_guard lock(mMutex);
            ++mReads[index];
        }
        if (index >= mLayout.pageCount || out.size() != mLayout.pageSize)
            return {ErrorCode::Corrupt, "page " + std::to_string(index) + ": beyond the source"};
        std::memcpy(out.data(), mBytes.data() + index * mLayout.pageSize, out.size());
        return verifyPageBytes(out, index);
    }

    /** Reads per page so far. */
    std::map<std::uint64_t, int> reads() const {
        std::lock_guard lock(mMutex);
        return mReads;
    }

private:
    explicit MemoryPageSource(std::vector<std::byte> bytes)
        : mBytes(std::move(bytes)) {}
    std::vector<std::byte> mBytes;
    PageLayout mLayout;
    mutable std::mutex mMutex;
    std::map<std::uint64_t, int> mReads;
};

} // namespace ff::storage::test
