#pragma once

// Format v2's geometry between the page cache, which keeps pages encoded, and the GPU arena,
// which keeps them decoded: what the renderer uploads, and the service that decodes it off the
// render thread (runtime/src/GeometryDecodeStage.h).

#include <ff/storage/SceneFormat.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>

namespace ff::runtime {

/** A geometry page decoded: its 20-byte vertices, then its cluster-local u8 indices. */
struct DecodedGeometry {
    std::unique_ptr<std::byte[]> bytes;
    std::uint32_t vertexCount = 0;
    std::uint32_t indexCount = 0;

    std::span<const storage::PackedVertex> vertices() const noexcept {
        return {reinterpret_cast<const storage::PackedVertex*>(bytes.get()), vertexCount};
    }
    std::span<const std::uint8_t> indices() const noexcept {
        return {reinterpret_cast<const std::uint8_t*>(bytes.get()) +
                        std::size_t{vertexCount} * sizeof(storage::PackedVertex),
                indexCount};
    }
    std::size_t size() const noexcept {
        return std::size_t{vertexCount} * sizeof(storage::PackedVertex) + indexCount;
    }
};

/**
 * Where the renderer gets a format v2 page's decoded geometry before uploading it. Decoding
 * takes time the render thread must not spend, so a page is asked for a frame ahead: prepare()
 * says whether it is decoded and, if not, asks for it. Answers are stable within a frame.
 * Main thread only.
 */
class IDecodedGeometry {
public:
    virtual ~IDecodedGeometry() = default;
    /** Whether `page` (a geometry page resident in the cache this frame) is decoded and may be
     *  uploaded now; when not, it is asked for (ready a later frame, if there is room). */
    [[nodiscard]] virtual bool prepare(std::uint64_t page) = 0;
    /** The decoded page prepare() answered true for, until uploaded() or the next frame;
     *  null otherwise. */
    [[nodiscard]] virtual const DecodedGeometry* decoded(std::uint64_t page) const = 0;
    /** The page is on the GPU: its decoded copy is freed now (decoded() is null from here on;
     *  a renderer that needs it again this frame decodes it itself). */
    virtual void uploaded(std::uint64_t page) = 0;
};

} // namespace ff::runtime
