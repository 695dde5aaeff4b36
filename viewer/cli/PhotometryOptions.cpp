#include "PhotometryOptions.h"

#include "core/Error.h"

namespace ml {

void declarePhotometryOption(Options& options) {
    options.value("photometry", photometryNames(),
                  "irradiance to lux: radiance = 179 lm/W x (0.265, 0.670, 0.065), as RADIANCE's rtrace -I and rcalc; "
                  "rec709 = 179 lm/W x (0.2126, 0.7152, 0.0722)",
                  std::string("radiance"));
}

Photometry readPhotometryOption(const Options& options) {
    try {
        return photometryNamed(options.str("photometry"));
    } catch (const InputError& e) {
        throw InputError(concat("--photometry: ", e.what()));
    }
}

}  // namespace ml
