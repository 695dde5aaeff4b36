#include "GatheredLights.h"

#include "core/Error.h"

#include <algorithm>

namespace ml {

bool GatheredLights::any() const { return std::any_of(gathered.begin(), gathered.end(), [](char g) { return g != 0; }); }

GatheredLights chooseGatheredLights(const Scene& scene, double ratio) {
    if (!(ratio >= 0 && ratio < 1)) throw InputError(concat("glow ratio ", ratio, " is not in [0, 1)"));
    GatheredLights g;
    if (ratio == 0) {
        g.reason = "every light is sampled directly (--glow-ratio 0)";
        return g;
    }
    double brightest = 0;
    for (const Light& l : scene.lights)
        if (!l.punctual()) brightest = std::max(brightest, luminance(l.radiance));
    g.gathered.assign(scene.lights.size(), 0);
    size_t count = 0;
    double power = 0, total = 0;
    std::string names;
    for (size_t i = 0; i < scene.lights.size(); ++i) {
        const Light& l = scene.lights[i];
        const double p = luminance(l.power());
        total += p;
        if (l.punctual() || !(luminance(l.radiance) < ratio * brightest)) continue;
        g.gathered[i] = 1;
        power += p;
        if (count < 4) names += concat(count ? ", " : "", "'", l.name, "'");
        ++count;
    }
    if (count == 0) {
        g.gathered.clear();
        g.reason = concat("every light is sampled directly (none is dimmer than ", ratio,
                          " of the brightest light's radiance)");
        return g;
    }
    char share[32];
    std::snprintf(share, sizeof share, "%.3g%%", total > 0 ? 100 * power / total : 0.0);
    g.reason = concat(count, count == 1 ? " light" : " lights", " (", names, count > 4 ? ", ..." : "",
                      "; ", share, " of the power) glow with less than ", ratio,
                      " of the brightest light's radiance: gathered by bounce 1's rays, which read their "
                      "emission where they land, not sampled as lights (each would fill the sampling image "
                      "and draw the room's occluders); their light is in the indirect meshes, not in a "
                      "light layer of its own, and the viewer's light switches do not reach it");
    return g;
}

}  // namespace ml
