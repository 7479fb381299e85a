#include <ff/storage/PageSource.h>

#include <vector>

namespace ff::storage {

Result<PagePin> IPageSource::pinPage(std::uint64_t index) {
    auto buffer = std::make_shared<std::vector<std::byte>>(pageSize());
    FF_RETURN_IF_ERROR(readPage(index, *buffer));
    const std::span<const std::byte> bytes(*buffer);
    return PagePin(bytes, std::move(buffer));
}

} // namespace ff::storage
