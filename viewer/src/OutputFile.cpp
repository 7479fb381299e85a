#include "OutputFile.h"

#include "ImageOutput.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <string>
#include <system_error>
#include <utility>

namespace ff::viewer {

namespace fs = std::filesystem;

namespace {

Status ioError(const fs::path& path, int error) {
    return Status(
            ErrorCode::IoError, "cannot write " + path.string() + ": " + std::strerror(error));
}

/** Creates `path` empty (it must not exist yet), or says why it cannot. */
Status createExclusive(const fs::path& path, const fs::path& reported) {
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd < 0)
        return ioError(reported, errno);
    ::close(fd);
    return Status::ok();
}

} // namespace

Result<PendingOutput> PendingOutput::reserve(const fs::path& path, OutputKind kind) {
    if (path.empty() || !path.has_filename())
        return Status(
                ErrorCode::InvalidArgument, "output path '" + path.string() + "' names no file");
    std::error_code error;
    if (fs::is_directory(path, error))
        return Status(ErrorCode::InvalidArgument, "output " + path.string() + " is a folder");
    const fs::path folder = path.has_parent_path() ? path.parent_path() : fs::path(".");
    if (!fs::is_directory(folder, error))
        return Status(
                ErrorCode::NotFound, "output directory " + folder.string() + " does not exist");
    if (kind == OutputKind::Image)
        FF_RETURN_IF_ERROR(checkImageFormat(path));
    const fs::path temporary =
            folder / ("." + path.stem().string() + "." + std::to_string(::getpid()) + ".tmp" +
                      path.extension().string());
    FF_RETURN_IF_ERROR(createExclusive(temporary, path));
    return PendingOutput(path, temporary);
}

PendingOutput::PendingOutput(fs::path path, fs::path temporary)
    : mPath(std::move(path))
    , mTemporary(std::move(temporary)) {}

PendingOutput::PendingOutput(PendingOutput&& other) noexcept
    : mPath(std::move(other.mPath))
    , mTemporary(std::exchange(other.mTemporary, fs::path())) {}

PendingOutput& PendingOutput::operator=(PendingOutput&& other) noexcept {
    if (this != &other) {
        discard();
        mPath = std::move(other.mPath);
        mTemporary = std::exchange(other.mTemporary, fs::path());
    }
    return *this;
}

PendingOutput::~PendingOutput() {
    discard();
}

void PendingOutput::discard() noexcept {
    if (!mTemporary.empty()) {
        std::error_code ignored;
        fs::remove(mTemporary, ignored);
        mTemporary.clear();
    }
}

Status PendingOutput::commitText(std::string_view text) {
    {
        std::ofstream out(mTemporary, std::ios::binary | std::ios::trunc);
        out.write(text.data(), static_cast<std::streamsize>(text.size()));
        out.flush();
        if (!out)
            return Status(ErrorCode::IoError, "cannot write " + mPath.string());
    }
    return commit();
}

Status PendingOutput::commitImage(const runtime::Image& image, bool withCoverage) {
    FF_RETURN_IF_ERROR(writeImage(mTemporary, image, withCoverage));
    return commit();
}

Status PendingOutput::commit() {
    if (mTemporary.empty())
        return Status(ErrorCode::Internal, mPath.string() + ": output already committed");
    std::error_code error;
    fs::rename(mTemporary, mPath, error);
    if (error)
        return Status(
                ErrorCode::IoError, "cannot write " + mPath.string() + ": " + error.message());
    mTemporary.clear();
    return Status::ok();
}

Result<std::optional<PendingOutput>> reserveIfNamed(const fs::path& path, OutputKind kind) {
    if (path.empty())
        return std::optional<PendingOutput>();
    FF_ASSIGN_OR_RETURN(PendingOutput output, PendingOutput::reserve(path, kind));
    return std::optional<PendingOutput>(std::move(output));
}

Status prepareOutputFolder(const fs::path& folder) {
    std::error_code error;
    fs::create_directories(folder, error);
    if (error || !fs::is_directory(folder, error))
        return Status(
                ErrorCode::IoError,
                "cannot create folder " + folder.string() +
                        (error ? ": " + error.message() : std::string()));
    const fs::path probe = folder / (".farfield-probe." + std::to_string(::getpid()));
    FF_RETURN_IF_ERROR(createExclusive(probe, folder));
    fs::remove(probe, error);
    return Status::ok();
}

} // namespace ff::viewer
