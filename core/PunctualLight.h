// Punctual lights: a point with an intensity distribution (isotropic, a
// glTF spot cone, a photometric luminaire's candela table), or parallel
// light from far away (directional). They have no area, so there is nothing
// to rasterise and no penumbra: a receiver either sees the point or it does
// not, and one shadow ray decides (the issue's "simulate only what the scene
// calls for": no soft-shadow sampling for them).
//
// Units. Intensity is radiometric, W·sr⁻¹ per RGB channel; a loader turns
// candela into it with the photometric efficacy K = 179 lm/W
// (Photometry.h), so a white light of I cd is I/179 W·sr⁻¹ in each channel
// and reads I lux at 1 m facing it under either luminance convention (their
// weights sum to 1). Distances are converted to metres with the scene's
// metresPerUnit before the inverse-square law:
//   point:        E(x) = I(ω) · max(0, n·ω') / (s·d)²,   ω = (x − p)/d, ω' = −ω
//   directional:  E(x) = E⊥ · max(0, −n·axis)
// with d = |x − p|, s metres per scene unit.
//
// The singularity. At d = 0 the receiver is at the light: there is no
// direction, and a light lying on a surface lights that surface edge-on
// (cos = 0 everywhere on its plane). So E = 0 where d < kPunctualMinDistance
// × the scene's size, and the inverse-square law holds unclamped above it: a
// light 1e-6 m off a wall gives the wall the (large, finite) I/d² a point
// light gives. The renderer, the exact reference and the path tracer all
// call punctualIrradiance(), so they treat it identically.
#pragma once

#include "Math.h"

#include <memory>
#include <string>

namespace ml {

struct CandelaTable;

// Below this fraction of the scene's bounding diagonal a receiver is taken to
// be at the light (E = 0, see above).
constexpr double kPunctualMinDistance = 1e-12;

// How a point light's intensity varies with direction, relative to its
// peak (PunctualEmission::intensity): profile(ω) in [0, 1].
struct IntensityProfile {
    enum class Shape {
        Isotropic,  // the same in every direction
        Spot,       // glTF KHR_lights_punctual's cone: 1 inside the inner cone, smooth to 0 at the outer
        Table,      // a photometric file's candela table (Type C: γ from the axis, C around it)
    };
    Shape shape = Shape::Isotropic;
    // Spot: cosines of the inner and outer cone half-angles (cosOuter < cosInner).
    double cosInner = 1, cosOuter = 0;
    // Table: the luminaire's distribution, absolute candela; profile = I/max.
    std::shared_ptr<const CandelaTable> table;
    // Table: the table's largest value, cd, set by Scene::finalize (every
    // shadow ray evaluates the profile; the maximum is a scan of the table).
    double tablePeak = 0;

    // profile along `cosGamma` = axis·ω and, for a table, `cAngle` (degrees,
    // around the axis from the reference direction).
    double operator()(double cosGamma, double cAngleDegrees) const;
    // ∫ profile dω over the sphere, sr: power = intensity × this.
    double solidAngle() const;
    // "isotropic", "spot 25°/30°", "table 'lamp.ies'"
    std::string describe() const;
};

// A punctual light's emission (Light::emission for kinds Point and Directional).
struct PunctualEmission {
    Vec3 position{0.0};            // point lights, scene units
    // Unit: where a spot or luminaire aims (γ = 0, its nadir for a ceiling
    // luminaire); for a directional light, the direction its light travels.
    Vec3 axis{0.0, -1.0, 0.0};
    // Unit, perpendicular to axis: the C = 0° half-plane of a candela table.
    Vec3 reference{1.0, 0.0, 0.0};
    // Point: W·sr⁻¹ where profile = 1 (the peak). Directional: W·m⁻² on a
    // surface facing it.
    Rgb intensity{0.0};
    IntensityProfile profile;      // point lights only

    // Set by Scene::finalize from the scene:
    double metresPerUnit = 1;      // Scene::metresPerUnit
    double minDistance = 0;        // kPunctualMinDistance × the scene's diagonal, scene units
    double sceneRadius = 0;        // half the scene's bounding diagonal (a directional light's reach)

    // I(ω), W·sr⁻¹, ω the unit direction from the light outward.
    Rgb intensityToward(const Vec3& w) const;
};

// What a punctual light gives a receiver with nothing in the way
// (punctualIncidence() in Scene.h).
struct PunctualIncidence {
    Rgb irradiance{0.0};  // W·m⁻²; zero where x is at the light or the light is behind n
    Vec3 toLight{0.0};    // unit, from x toward the light (the shadow ray's direction)
    double distance = 0;  // to the light, scene units; +inf for a directional light
};

}  // namespace ml
