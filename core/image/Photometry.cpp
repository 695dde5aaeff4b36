#include "Photometry.h"

#include "core/Error.h"

namespace ml {

void Photometry::validate() const {
    if (!(efficacy > 0 && efficacy < 1e6))
        throw InputError(concat("luminous efficacy ", efficacy, " lm/W is not within (0, 1e6)"));
}

std::string Photometry::describe() const {
    return concat(name, " (", efficacy, " lm/W × (", weights.r, ", ", weights.g, ", ", weights.b, "))");
}

Photometry photometryNamed(const std::string& name) {
    Photometry p;
    p.name = name;
    if (name == "radiance") {
        p.weights = Rgb(0.265, 0.670, 0.065);
    } else if (name == "rec709") {
        p.weights = Rgb(0.2126, 0.7152, 0.0722);
    } else {
        throw InputError(concat("unknown photometry '", name, "' (use ", photometryNames(), ")"));
    }
    return p;
}

const char* photometryNames() { return "radiance|rec709"; }

}  // namespace ml
