// What the viewer shows and how the lights are set: display modes, the
// per-light controls, and the compositor weights they amount to. Pure
// logic, shared by the window's controls and the script player.
//
// Light changes are instant because irradiance is linear in emission: a
// light's weight scales its own direct mesh and its own emitted radiance,
// which is exact. Indirect light is cached per bounce, not per light, so it
// cannot be split by light; it takes the power-weighted mean of the lights'
// weights (per channel, Σ w_l Φ_l / Σ Φ_l), exact when every light is scaled
// alike (all dimmed by half, all tinted the same) and an approximation
// otherwise, until the indirect meshes re-converge (they are not re-sampled
// for a light change: the worker caches the scene's own lights).
#pragma once

#include "viewer/compositor/Compositor.h"
#include "core/image/ToneMap.h"

#include <string>
#include <vector>

namespace ml {

enum class DisplayMode {
    Final,        // direct + indirect + emission
    Direct,       // direct light and emission only
    Indirect,     // Kd/π × Σ_b E_b: indirect light only, no emission
    Light,        // one light alone: its direct light and its emission
    Reflectance,  // Kd
    Illuminance,  // lux, false colour
};

// "final", "direct", "indirect", "light", "reflectance", "lux".
const char* displayModeName(DisplayMode mode);

// One light's controls. Its weight is on ? intensity × colour : 0.
struct LightControl {
    bool on = true;
    double intensity = 1;  // ≥ 0, multiplies Ke
    Rgb colour{1.0};       // per-channel tint in [0, 1]… any ≥ 0
    Rgb weight() const { return on ? intensity * colour : Rgb(0.0); }
};

struct DisplayState {
    DisplayMode mode = DisplayMode::Final;
    size_t light = 0;           // DisplayMode::Light: which one
    bool wireframe = false;     // cache meshes' edges over the image, a colour per mesh
    bool contours = true;       // iso-lux lines at 1-2-5 values (Illuminance)
    bool luxAuto = true;        // range from the image (autoLuxRange) when asked
    double luxMin = 1, luxMax = 1000;  // false-colour range, lux
    double exposureEV = 0;      // stops on top of the metered exposure
    // Meter the exposure (FrameMeter): once, from the first snapshot shown,
    // and when asked again. Off (--no-auto-exposure): 2^exposureEV alone,
    // the same in every frame and screenshot of a recording.
    bool autoExposure = true;
    ToneOperator op = ToneOperator::Aces;
    bool showUi = true;         // the control panel (the lux legend stays)
};

// Per channel Σ w_l Φ_l / Σ Φ_l over the lights' powers Φ_l (any common unit);
// 1 where every light's power is 0 in that channel.
Rgb indirectWeight(const std::vector<LightControl>& lights, const std::vector<Rgb>& powers);

// The weights and quantity the compositor uses for a mode.
LightWeights compositeWeights(const DisplayState& display, const std::vector<LightControl>& lights,
                              const std::vector<Rgb>& powers);
CompositeQuantity compositeQuantity(DisplayMode mode);

}  // namespace ml
