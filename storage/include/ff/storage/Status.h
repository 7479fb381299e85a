#pragma once

// One error model for the whole project (STYLE.md §4): environment and data failures travel as
// Status / Result<T>; bugs are FF_ASSERTs; "not yet" is a state, not an error. Lives in the root
// module so every other module can use it.

#include <ff/storage/Assert.h>

#include <string>
#include <utility>
#include <variant>

namespace ff {

enum class ErrorCode {
    Ok = 0,
    InvalidArgument, ///< the caller asked for something impossible (bad flag, bad size)
    NotFound,        ///< a file or an object named by the input does not exist
    IoError,         ///< read/write/mmap/fsync failed
    DiskFull,        ///< ENOSPC / EDQUOT while writing
    Corrupt,         ///< bytes on disk fail a check (checksum, bounds, magic)
    Unsupported,     ///< valid input that farfield does not handle (named in the message)
    InvalidInput,    ///< malformed input file (glTF that breaks the spec)
    OutOfBudget,     ///< a memory budget too small for the job
    Internal,        ///< an invariant broke in a way that is not the caller's fault
};

/** Short stable name of a code ("corrupt", "io-error", ...), for messages and JSON. */
const char* errorCodeName(ErrorCode code) noexcept;

/** The outcome of an operation that can fail for reasons outside the program. */
class [[nodiscard]] Status {
public:
    Status() = default;
    Status(ErrorCode code, std::string message) : mCode(code), mMessage(std::move(message)) {}

    static Status ok() { return {}; }

    bool isOk() const noexcept { return mCode == ErrorCode::Ok; }
    explicit operator bool() const noexcept { return isOk(); }
    ErrorCode code() const noexcept { return mCode; }
    const std::string& message() const noexcept { return mMessage; }

    /** "corrupt: page 12: checksum mismatch" */
    std::string toString() const;

    /** Returns a copy whose message is prefixed with `context: `. */
    Status withContext(const std::string& context) const;

private:
    ErrorCode mCode = ErrorCode::Ok;
    std::string mMessage;
};

/** A value or the Status that explains why there is none. */
template <typename T> class [[nodiscard]] Result {
public:
    Result(T value) : mData(std::move(value)) {}
    Result(Status status) : mData(std::move(status)) {
        FF_ASSERT(!std::get<Status>(mData).isOk());
    }

    bool isOk() const noexcept { return std::holds_alternative<T>(mData); }
    explicit operator bool() const noexcept { return isOk(); }

    const Status& status() const {
        static const Status kOk;
        return isOk() ? kOk : std::get<Status>(mData);
    }

    T& value() & {
        FF_ASSERT(isOk());
        return std::get<T>(mData);
    }
    const T& value() const& {
        FF_ASSERT(isOk());
        return std::get<T>(mData);
    }
    T&& value() && {
        FF_ASSERT(isOk());
        return std::get<T>(std::move(mData));
    }
    T* operator->() { return &value(); }
    const T* operator->() const { return &value(); }
    T& operator*() & { return value(); }
    const T& operator*() const& { return value(); }

private:
    std::variant<T, Status> mData;
};

} // namespace ff

#define FF_STATUS_CONCAT_INNER(a, b) a##b
#define FF_STATUS_CONCAT(a, b) FF_STATUS_CONCAT_INNER(a, b)

/** Returns the Status of `expr` from the enclosing function if it is an error. */
#define FF_RETURN_IF_ERROR(expr)                                                                   \
    FF_RETURN_IF_ERROR_IMPL(FF_STATUS_CONCAT(ffStatusTmp_, __LINE__), expr)
#define FF_RETURN_IF_ERROR_IMPL(tmp, expr)                                                         \
    do {                                                                                           \
        ::ff::Status tmp = (expr);                                                                 \
        if (!tmp.isOk())                                                                           \
            return tmp;                                                                            \
    } while (false)

/** `FF_ASSIGN_OR_RETURN(auto x, makeX());` declares x from a Result or returns its Status. */
#define FF_ASSIGN_OR_RETURN(decl, expr)                                                            \
    FF_ASSIGN_OR_RETURN_IMPL(FF_STATUS_CONCAT(ffResultTmp_, __LINE__), decl, expr)
#define FF_ASSIGN_OR_RETURN_IMPL(tmp, decl, expr)                                                  \
    auto tmp = (expr);                                                                             \
    if (!tmp.isOk())                                                                               \
        return tmp.status();                                                                       \
    decl = std::move(tmp).value()
