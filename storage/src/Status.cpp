#include <ff/storage/Status.h>

namespace ff {

const char* errorCodeName(ErrorCode code) noexcept {
    switch (code) {
    case ErrorCode::Ok: return "ok";
    case ErrorCode::InvalidArgument: return "invalid-argument";
    case ErrorCode::NotFound: return "not-found";
    case ErrorCode::IoError: return "io-error";
    case ErrorCode::DiskFull: return "disk-full";
    case ErrorCode::Corrupt: return "corrupt";
    case ErrorCode::Unsupported: return "unsupported";
    case ErrorCode::InvalidInput: return "invalid-input";
    case ErrorCode::OutOfBudget: return "out-of-budget";
    case ErrorCode::Internal: return "internal";
    }
    return "unknown";
}

std::string Status::toString() const {
    if (isOk())
        return "ok";
    return std::string(errorCodeName(mCode)) + ": " + mMessage;
}

Status Status::withContext(const std::string& context) const {
    if (isOk())
        return *this;
    return {mCode, context + ": " + mMessage};
}

} // namespace ff
