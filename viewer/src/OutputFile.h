#pragma once

// Outputs reserved before the work that fills them. Every verb opens each file it will write
// (images, JSON statistics, CSV, summaries) before it renders or replays anything: a mistyped
// or unwritable path then fails at once, not after minutes of work. The file is written under
// a temporary name in the target folder and renamed over the target at the end, so a failure
// never leaves half a file behind or clobbers an existing one.

#include <ff/runtime/Image.h>
#include <ff/storage/Status.h>

#include <filesystem>
#include <optional>
#include <string_view>

namespace ff::viewer {

/** What a reserved output will hold: images must have an extension the image writer knows. */
enum class OutputKind { Text, Image };

/**
 * A file that will be written at `path()`. Reserving it creates an empty temporary file
 * `.<name>.<pid>.tmp<extension>` beside the target (same folder, so the final rename is atomic;
 * same extension, so the image writer picks the target's format). The temporary is removed
 * unless commit() renamed it. Movable, not copyable. Main thread.
 */
class PendingOutput {
public:
    /** Fails (NotFound, InvalidArgument, IoError) if the folder is missing, the path names a
     *  folder, the image format is unknown or the folder is not writable. */
    [[nodiscard]] static Result<PendingOutput>
    reserve(const std::filesystem::path& path, OutputKind kind);

    PendingOutput(PendingOutput&& other) noexcept;
    PendingOutput& operator=(PendingOutput&& other) noexcept;
    PendingOutput(const PendingOutput&) = delete;
    PendingOutput& operator=(const PendingOutput&) = delete;
    ~PendingOutput();

    const std::filesystem::path& path() const noexcept { return mPath; }
    /** Where the writer writes, before commit(). */
    const std::filesystem::path& temporaryPath() const noexcept { return mTemporary; }

    /** Replaces `text`'s target with it: writes the temporary, flushes, renames. */
    [[nodiscard]] Status commitText(std::string_view text);
    /** Replaces the target with `image` (writeImage() into the temporary, then the rename). */
    [[nodiscard]] Status commitImage(const runtime::Image& image, bool withCoverage = false);
    /** Renames the written temporary over the target. */
    [[nodiscard]] Status commit();

private:
    PendingOutput(std::filesystem::path path, std::filesystem::path temporary);
    void discard() noexcept;

    std::filesystem::path mPath;
    std::filesystem::path mTemporary; ///< empty once committed or moved from
};

/** reserve() for an optional flag's path: no output where the path is empty. */
[[nodiscard]] Result<std::optional<PendingOutput>>
reserveIfNamed(const std::filesystem::path& path, OutputKind kind);

/**
 * A folder that will receive many files (replay's frames, bench results, view's screenshots):
 * created if missing (with its parents) and proven writable by creating and removing a probe
 * file in it.
 */
[[nodiscard]] Status prepareOutputFolder(const std::filesystem::path& folder);

} // namespace ff::viewer
