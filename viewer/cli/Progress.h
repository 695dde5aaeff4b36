// Progress on the terminal: a bar redrawn in place on a terminal, plain
// lines (every 10%) when stderr is a file or a pipe.
#pragma once

#include <chrono>
#include <cstddef>
#include <string>

namespace ml {

class Progress {
public:
    Progress(std::string label, size_t total);
    void update(size_t done);
    void finish();
    // Ends the bar where it stands, not at 100% (an interrupted run).
    void abandon();

private:
    std::string label_;
    size_t total_;
    bool terminal_;
    int lastDecile_ = -1;
    bool finished_ = false;
    std::chrono::steady_clock::time_point start_;
};

}  // namespace ml
