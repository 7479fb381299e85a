#pragma once

// errno -> Status, one mapping for the whole module (STYLE.md §4).

#include <ff/storage/Status.h>

#include <cerrno>
#include <string>
#include <system_error>

namespace ff::storage {

/** `what` names the operation and path ("cannot write /a/b.ffs.tmp-7"); strerror is appended.
 *  ENOSPC/EDQUOT -> DiskFull, ENOENT -> NotFound, anything else -> IoError. */
inline Status posixError(int err, const std::string& what) {
    const std::string reason = std::generic_category().message(err);
    if (err == ENOSPC || err == EDQUOT)
        return {ErrorCode::DiskFull, what + ": disk full (" + reason + ")"};
    if (err == ENOENT)
        return {ErrorCode::NotFound, what + ": " + reason};
    return {ErrorCode::IoError, what + ": " + reason};
}

} // namespace ff::storage
