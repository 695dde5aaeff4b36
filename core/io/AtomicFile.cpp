#include "AtomicFile.h"

#include "core/Error.h"

#include <unistd.h>

#include <atomic>
#include <fstream>
#include <system_error>

namespace ml {

namespace fs = std::filesystem;

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
}

AtomicOutput::~AtomicOutput() {
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
