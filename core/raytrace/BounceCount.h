// How many indirect bounces a scene calls for (§5.1): light loses a factor
// of the albedo it meets at every bounce, so after n bounces of indirect
// light the reflected light still missing is about ā^(n+1) of its total
// (direct light is the first reflection), where ā is
// the albedo that direct light meets, weighted by area and direct
// irradiance (for a closed scene of uniform albedo a emitting Le: L =
// Le/(1−a), and n bounces give Le(1−a^(n+2))/(1−a)). The count is the smallest n that
// leaves less than the set fraction missing, up to a cap; an albedo near 1
// hits the cap, and the plan says how much energy is then left out.
#pragma once

#include "core/Scene.h"

#include <optional>
#include <string>

namespace ml {

struct BounceCountSettings {
    // Stop once the radiance still missing is below this fraction of the total.
    double missingFraction = 0.01;
    int maxBounces = 24;               // the cap
    std::optional<int> forced;         // --bounces N: this many, whatever the albedo
    int points = 4096;                 // surface points the albedo is averaged over
    int lightSamples = 16;             // shadow rays per light and point
    // Past this many lights, each point draws lightSamples × everyLightUpTo
    // lights in proportion to their power instead of lightSamples rays to
    // every light (countBounces).
    int everyLightUpTo = 16;
    int threads = 0;                   // 0: every core; the count is the same for any
    uint32_t seed = 1;
    void validate() const;
};

struct BounceCount {
    // Per channel, area- and direct-irradiance-weighted: Kd, plus what a
    // mirror or glass sends on (its reflectance, its transmission filter)
    // times the area-weighted albedo, where that caustic is reflected.
    Rgb albedo{0.0};
    double meanAlbedo = 0;  // ā: the largest channel (it decays slowest)
    // The largest channel of the albedo weighted by area alone: what light
    // meets once a few bounces have spread it over the scene (the ambient
    // term of progressive radiosity, Cohen et al. 1988), the ratio of each
    // later bounce to the one before. Larger than ā where direct light
    // lands on a dark floor in a light room (the office: 0.63 against 0.54).
    double areaAlbedo = 0;
    // The ratio of bounce 2's reflected power to bounce 1's, by rays: from
    // the points (weighted by the light they reflect, direct irradiance ×
    // Kd), one cosine-distributed ray each, the albedo where it lands (0
    // where it leaves the scene), largest channel. Below areaAlbedo where
    // light escapes (the Cornell box's open front), near it in a closed
    // room; 0 when no point is lit.
    double bounceRatio = 0;
    int bounces = 0;
    double missing = 0;     // fraction of the reflected light left out: ā^(bounces+1)
    bool capped = false;    // the cap, not the fraction, set the count
    std::string reason;     // one line for the plan
};

// Direct irradiance at the points comes from shadow rays to points on the
// lights (Embree), so light blocked by walls does not count.
BounceCount countBounces(const Scene& scene, const BounceCountSettings& settings = {});

}  // namespace ml
