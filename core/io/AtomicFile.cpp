#include "AtomicFile.h"

#include "core/Error.h"

#include <unistd.h>

#include <array>
#include <atomic>
#include <climits>
#include <cstring>
#include <fstream>
#include <system_error>

namespace ml {

namespace fs = std::filesystem;

namespace {

// The temporaries being written, for removePendingOutputs: fixed storage
// and lock-free states, so a signal handler can read them.
struct PendingSlot {
    enum : int { kFree, kClaimed, kListed };
    std::atomic<int> state{kFree};
    char path[PATH_MAX] = {};
};
std::array<PendingSlot, 32> gPending;

int listPending(const fs::path& temporary) {
    std::error_code ec;
    const std::string absolute = fs::absolute(temporary, ec).string();
    if (ec || absolute.size() >= PATH_MAX) return -1;
    for (size_t i = 0; i < gPending.size(); ++i) {
        int expected = PendingSlot::kFree;
        if (!gPending[i].state.compare_exchange_strong(expected, PendingSlot::kClaimed)) continue;
        std::memcpy(gPending[i].path, absolute.c_str(), absolute.size() + 1);
        gPending[i].state.store(PendingSlot::kListed);
        return int(i);
    }
    return -1;
}

void unlistPending(int slot) {
    if (slot >= 0) gPending[size_t(slot)].state.store(PendingSlot::kFree);
}

}  // namespace

void removePendingOutputs() noexcept {
    for (PendingSlot& slot : gPending)
        if (slot.state.load() == PendingSlot::kListed) ::unlink(slot.path);
}

fs::path directoryOf(const std::string& path) {
    const fs::path dir = fs::path(path).parent_path();
    return dir.empty() ? fs::path(".") : dir;
}

void checkOutputDirectory(const std::string& path) {
    const fs::path dir = directoryOf(path);
    std::error_code ec;
    if (!fs::exists(dir, ec))
        throwInputError(SourceLocation{path}, "output directory '", dir.string(), "' does not exist");
    if (!fs::is_directory(dir, ec))
        throwInputError(SourceLocation{path}, "'", dir.string(), "' is not a directory");
}

AtomicOutput::AtomicOutput(const std::string& target) : target_(target) {
    // pid and a counter keep concurrent writers, in this process or
    // another, from sharing a temporary.
    static std::atomic<unsigned> counter{0};
    const fs::path t(target);
    path_ = directoryOf(target) / concat(".", t.filename().string(), ".tmp-", ::getpid(), "-", counter++);
    pendingSlot_ = listPending(path_);
}

AtomicOutput::~AtomicOutput() {
    unlistPending(pendingSlot_);
    if (!committed_) {
        std::error_code ignored;  // nothing useful to do if cleanup itself fails
        fs::remove(path_, ignored);
    }
}

void AtomicOutput::commit() {
    std::error_code ec;
    fs::rename(path_, target_, ec);
    if (ec) throwInputError(SourceLocation{target_}, "cannot write: ", ec.message());
    committed_ = true;
    unlistPending(pendingSlot_);
    pendingSlot_ = -1;
}

void writeTextFileAtomically(const std::string& path, const std::string& text) {
    checkOutputDirectory(path);
    AtomicOutput out(path);
    {
        std::ofstream f(out.path(), std::ios::binary);
        f << text;
        f.close();
        if (!f) throwInputError(SourceLocation{path}, "cannot write");
    }
    out.commit();
}

void makeOutputDirectory(const std::string& dir) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec || !std::filesystem::is_directory(dir, ec))
        throwInputError(SourceLocation{dir}, "cannot make the output directory",
                        ec ? concat(": ", ec.message()) : std::string());
}

}  // namespace ml
