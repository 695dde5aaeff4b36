// Errors a user can cause (bad files, bad options) versus internal invariants.
//
// InputError carries the place that caused it ("scene.mtl:14: Ke has 2 values,
// expected 3", as pbrt's ErrorExit(loc, ...)); the command line catches it,
// prints it and exits non-zero before any output file is written.
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>

namespace ml {

// Where in a user's input something went wrong; line 0 means "the whole file".
struct SourceLocation {
    std::string file;
    int line = 0;

    std::string str() const {
        if (file.empty()) return {};
        return line > 0 ? file + ":" + std::to_string(line) : file;
    }
};

class InputError : public std::runtime_error {
public:
    InputError(const SourceLocation& where, const std::string& what)
        : std::runtime_error(where.str().empty() ? what : where.str() + ": " + what),
          where_(where) {}
    explicit InputError(const std::string& what) : std::runtime_error(what) {}
    const SourceLocation& where() const { return where_; }

private:
    SourceLocation where_;
};

namespace detail {
inline void appendAll(std::ostringstream&) {}
template <typename T, typename... Rest>
void appendAll(std::ostringstream& os, const T& v, const Rest&... rest) {
    os << v;
    appendAll(os, rest...);
}
}  // namespace detail

// Concatenates its arguments with operator<< (a small stand-in for fmt).
template <typename... Args>
std::string concat(const Args&... args) {
    std::ostringstream os;
    os.precision(9);
    detail::appendAll(os, args...);
    return os.str();
}

template <typename... Args>
[[noreturn]] void throwInputError(const SourceLocation& where, const Args&... args) {
    throw InputError(where, concat(args...));
}

}  // namespace ml

// A violated internal invariant is a Meshlight bug, not the user's: it throws
// std::logic_error naming the condition and the source line, always on (cheap).
#define ML_ASSERT(cond, ...)                                                              \
    do {                                                                                  \
        if (!(cond))                                                                      \
            throw std::logic_error(::ml::concat(__FILE__, ":", __LINE__,                 \
                                                ": internal error: " #cond " ", ##__VA_ARGS__)); \
    } while (0)
