// Output files that appear whole or not at all: written to a temporary
// sibling, then renamed over the target. A failed command leaves no partial
// output file behind, and neither does one ended by a second Ctrl-C
// (InterruptGuard.h calls removePendingOutputs before it exits).
#pragma once

#include <filesystem>
#include <string>

namespace ml {

// The directory a file named by `path` lives in ("." for a bare file name).
std::filesystem::path directoryOf(const std::string& path);

// Throws InputError naming `path` if its directory is missing or not a directory.
void checkOutputDirectory(const std::string& path);

// A temporary sibling of the target file. rename() within one directory is
// atomic on POSIX, so readers of the target (and a crash mid-write) never see
// a partial file; the destructor removes the temporary unless committed.
class AtomicOutput {
public:
    explicit AtomicOutput(const std::string& target);
    AtomicOutput(const AtomicOutput&) = delete;
    AtomicOutput& operator=(const AtomicOutput&) = delete;
    ~AtomicOutput();

    // Where to write before commit().
    const std::filesystem::path& path() const { return path_; }
    // Renames the temporary over the target; throws InputError on failure.
    void commit();

private:
    std::string target_;
    std::filesystem::path path_;
    bool committed_ = false;
    int pendingSlot_ = -1;  // where removePendingOutputs finds the temporary; -1: not listed
};

// Makes the folder `dir` (and its parents) if missing; throws InputError
// naming it if it cannot be made or is not a folder.
void makeOutputDirectory(const std::string& dir);

// Removes the temporary of every AtomicOutput not yet committed or
// destroyed. Async-signal-safe (unlink only): for a signal handler about to
// _exit. Up to 32 temporaries at a time are known to it; more are rare
// (one per file being written) and would only be left behind.
void removePendingOutputs() noexcept;

// Writes `text` to `path` through an AtomicOutput.
void writeTextFileAtomically(const std::string& path, const std::string& text);

}  // namespace ml
