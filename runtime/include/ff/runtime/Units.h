#pragma once

#include <ff/storage/Status.h>

#include <glm/glm.hpp>

#include <cstdint>
#include <string>
#include <string_view>

namespace ff::runtime {

/** "1GiB", "512MiB", "64KiB", "1G", "1000000" (bytes) -> bytes. */
[[nodiscard]] Result<std::uint64_t> parseByteSize(std::string_view text);
/** "640x480" -> (640, 480). */
[[nodiscard]] Result<glm::ivec2> parseImageSize(std::string_view text);
/** "1,2.5,-3" -> vec3. */
[[nodiscard]] Result<glm::vec3> parseVec3(std::string_view text);
/** The same in double precision (world positions far from the origin). */
[[nodiscard]] Result<glm::dvec3> parseDVec3(std::string_view text);
/** 1536 -> "1.5 KiB". */
std::string formatBytes(std::uint64_t bytes);

} // namespace ff::runtime
