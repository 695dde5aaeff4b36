// libFuzzer target for the photometric loaders: parseIes and parseEulumdat
// (core/loaders/IesLoader.h, EulumdatLoader.h) and what a table they return
// promises (core/CandelaTable.h).
//
// Input: the file's text, optionally followed by a NUL byte and the text of
// the tilt file that a TILT=<name> line gets (served from memory through the
// reader; without a NUL no tilt file can be read). Every input goes to both
// loaders: the IES one as "fuzz/lamp.ies", the EULUMDAT one as
// "fuzz/lamp.ldt".
//
// An InputError is the loader refusing bad input: a normal outcome. Any other
// exception, a broken promise about the returned table, a crash, a sanitizer
// report, a leak or a hang is a finding.
#include "core/CandelaTable.h"
#include "core/Error.h"
#include "core/loaders/EulumdatLoader.h"
#include "core/loaders/IesLoader.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <string_view>

namespace {

[[noreturn]] void finding(const std::string& what) {
    std::fprintf(stderr, "fuzz_photometric: %s\n", what.c_str());
    std::abort();  // libFuzzer saves the input as a crash artifact
}

#define EXPECT(cond, ...) \
    if (!(cond)) finding(ml::concat("broken promise: " #cond " ", ##__VA_ARGS__))

// What CandelaTable.h promises about a table a loader returns.
void checkTable(const ml::CandelaTable& t, const std::string& name) {
    EXPECT(t.source == name);
    EXPECT(t.gamma.size() >= 2, t.gamma.size());
    for (size_t i = 0; i < t.gamma.size(); ++i) {
        EXPECT(t.gamma[i] >= 0 && t.gamma[i] <= 180, t.gamma[i]);
        if (i > 0) EXPECT(t.gamma[i] > t.gamma[i - 1], i);
    }
    EXPECT(!t.c.empty() && t.c.front() == 0 && t.c.back() < 360);
    for (size_t i = 1; i < t.c.size(); ++i) EXPECT(t.c[i] > t.c[i - 1], i);
    EXPECT(t.candela.size() == t.c.size() * t.gamma.size(), t.candela.size());
    for (double v : t.candela) EXPECT(std::isfinite(v) && v >= 0 && v <= 1e15, v);
    EXPECT(t.ratedLumens == -1 || (t.ratedLumens > 0 && std::isfinite(t.ratedLumens)), t.ratedLumens);
    EXPECT(std::isfinite(t.width) && std::isfinite(t.length) && std::isfinite(t.height));
    const double peak = t.maxIntensity(), flux = t.flux();
    EXPECT(std::isfinite(peak) && peak >= 0, peak);
    // The interpolant lies within [0, peak], so its integral within [0, 4π peak].
    EXPECT(std::isfinite(flux) && flux >= 0 && flux <= 4 * M_PI * peak * (1 + 1e-9), flux, " peak ", peak);
    for (double g : {-1.0, 0.0, 0.5, 45.0, 90.0, 133.3, 180.0})
        for (double c : {-30.0, 0.0, 1e-3, 90.0, 359.999, 1e6}) {
            const double v = t.intensity(g, c);
            EXPECT(std::isfinite(v) && v >= 0 && v <= peak * (1 + 1e-12), v, " at ", g, " ", c);
        }
}

template <typename Load>
void run(Load load, const std::string& name) {
    try {
        checkTable(load(), name);
    } catch (const ml::InputError&) {
        // Refused with file:line and a reason: what bad input should get.
    } catch (const std::exception& e) {
        finding(std::string("unexpected exception: ") + e.what());
    } catch (...) {
        finding("unexpected exception of unknown type");
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string_view input(reinterpret_cast<const char*>(data), size);
    const size_t cut = input.find('\0');
    const bool hasTilt = cut != std::string_view::npos;
    const std::string text(input.substr(0, cut));
    const std::string tilt = hasTilt ? std::string(input.substr(cut + 1)) : std::string();
    const ml::PhotometricFileReader read = [&](const std::string&, std::string& out) {
        if (!hasTilt) return false;
        out = tilt;
        return true;
    };
    run([&] { return ml::parseIes(text, "fuzz/lamp.ies", read); }, "fuzz/lamp.ies");
    run([&] { return ml::parseEulumdat(text, "fuzz/lamp.ldt"); }, "fuzz/lamp.ldt");
    return 0;
}
