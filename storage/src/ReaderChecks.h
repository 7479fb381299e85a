#pragma once

// Checks and messages shared by the readers of a scene file (the scene index, the mapped file),
// so every reader words a failure the same way: "page N: what".

#include "PageChecksum.h"

#include <ff/storage/SceneFormat.h>
#include <ff/storage/Status.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>

namespace ff::storage::detail {

// Page types as bits, so one check can accept "Nodes or Geometry".
using PageTypeMask = std::uint32_t;

constexpr PageTypeMask maskOf(PageType type) noexcept {
    return PageTypeMask{1} << static_cast<std::uint16_t>(type);
}

constexpr PageTypeMask kHierarchyPages = maskOf(PageType::Nodes) | maskOf(PageType::Geometry);

inline std::string hex(std::uint64_t value) {
    char text[24];
    std::snprintf(text, sizeof(text), "0x%llx", static_cast<unsigned long long>(value));
    return text;
}

inline Status corrupt(std::uint64_t page, const std::string& what) {
    return {ErrorCode::Corrupt, "page " + std::to_string(page) + ": " + what};
}

inline std::string truncatedMessage(std::uint64_t fileSize) {
    return "beyond end of file (file truncated to " + std::to_string(fileSize) + " bytes)";
}

/** The trailer's type is one of `expected`, else Corrupt "page N: expected a ... page". */
inline Status checkType(std::uint16_t type, std::uint64_t index, PageTypeMask expected) {
    if (type < 32 && (expected & (PageTypeMask{1} << type)) != 0)
        return Status::ok();
    std::string names;
    for (std::uint16_t t = 1; t <= 4; ++t) {
        if ((expected & (PageTypeMask{1} << t)) == 0)
            continue;
        if (!names.empty())
            names += " or ";
        names += pageTypeName(t);
    }
    return corrupt(
            index,
            "expected a " + names + " page, found " + pageTypeName(type) + " (type " +
                    std::to_string(type) + ")");
}

template <typename Real> bool allFinite(const std::array<Real, 3>& v) noexcept {
    return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
}

inline bool ordered(const std::array<float, 3>& lo, const std::array<float, 3>& hi) noexcept {
    return lo[0] <= hi[0] && lo[1] <= hi[1] && lo[2] <= hi[2];
}

} // namespace ff::storage::detail
