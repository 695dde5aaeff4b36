#include "DisplayState.h"

#include "core/Error.h"

namespace ml {

const char* displayModeName(DisplayMode mode) {
    switch (mode) {
        case DisplayMode::Final: return "final";
        case DisplayMode::Direct: return "direct";
        case DisplayMode::Indirect: return "indirect";
        case DisplayMode::Light: return "light";
        case DisplayMode::Reflectance: return "reflectance";
        case DisplayMode::Illuminance: return "lux";
    }
    return "?";
}

Rgb indirectWeight(const std::vector<LightControl>& lights, const std::vector<Rgb>& powers) {
    ML_ASSERT(lights.size() == powers.size(), lights.size(), " lights, ", powers.size(), " powers");
    Rgb weighted(0.0), total(0.0);
    for (size_t l = 0; l < lights.size(); ++l) {
        weighted += lights[l].weight() * powers[l];
        total += powers[l];
    }
    Rgb w(1.0);
    for (int c = 0; c < 3; ++c)
        if (total[c] > 0) w[c] = weighted[c] / total[c];
    return w;
}

LightWeights compositeWeights(const DisplayState& d, const std::vector<LightControl>& lights,
                              const std::vector<Rgb>& powers) {
    LightWeights w;
    for (const LightControl& l : lights) w.light.push_back(l.weight());
    w.indirect = indirectWeight(lights, powers);
    // The mesh lights share holds many lights' direct light: it takes their
    // mean weight like indirect light (exact when all change alike).
    w.shared = w.indirect;
    switch (d.mode) {
        case DisplayMode::Final:
        case DisplayMode::Reflectance:
        case DisplayMode::Illuminance: break;
        case DisplayMode::Direct: w.indirect = Rgb(0.0); break;
        case DisplayMode::Indirect:
            for (Rgb& l : w.light) l = Rgb(0.0);
            w.shared = Rgb(0.0);
            break;
        case DisplayMode::Light:
            for (size_t l = 0; l < w.light.size(); ++l)
                if (l != d.light) w.light[l] = Rgb(0.0);
            // What the light gave the shared mesh is not told apart there.
            w.indirect = Rgb(0.0);
            w.shared = Rgb(0.0);
            break;
    }
    return w;
}

CompositeQuantity compositeQuantity(DisplayMode mode) {
    switch (mode) {
        case DisplayMode::Reflectance: return CompositeQuantity::Reflectance;
        case DisplayMode::Illuminance: return CompositeQuantity::Illuminance;
        default: return CompositeQuantity::Radiance;
    }
}

}  // namespace ml
