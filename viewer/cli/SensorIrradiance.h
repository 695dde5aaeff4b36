// Irradiance at sensor points, the machinery `probe` and `grid` share:
// points in (read from a CSV file or RADIANCE's rtrace input), direct
// irradiance per light and indirect irradiance out, by one of probe's
// methods (the cache's samplers with indirect light as `render` computes it,
// the exact closed form, the ray-traced peer of the jittered sampler, or the
// path tracer), with probe's options, declared and read here once.
//
// Interrupts. measureSensors takes an InterruptGuard: the first signal ends
// the phase under way. During the caches' refinement (GPU and exact
// methods), refinement stops and every point is evaluated from what is
// cached, as `render` writes the image of what is cached. During the
// evaluation of the points, the point under way is finished and the rest
// are left out (SensorReadings::values is then a prefix of the points). The
// indirect gathers are not cut: they take a fraction of a second per
// thousand points. A second signal ends the process (InterruptGuard.h).
#pragma once

#include "Options.h"
#include "cache/IrradianceCache.h"
#include "core/Scene.h"
#include "core/raytrace/PathTracer.h"
#include "gpu_sampling/SamplerFactory.h"

#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

namespace ml {

class InterruptGuard;

// A sensor: a point and the unit normal of the surface it measures on.
struct SensorPoint {
    Vec3 position{0.0};
    Vec3 normal{0.0, 1.0, 0.0};
};

// --- Reading points ----------------------------------------------------------

// A CSV file with the header x,y,z,nx,ny,nz (normals are normalised; '#'
// lines and blank lines skipped). With `surfaces`, a seventh column
// `surface` may follow, naming the surface each point belongs to; it is
// filled with one name per point ("" when the file has no such column).
// InputError "FILE:LINE: ..." for a bad header, a missing or non-finite
// value or a zero normal.
std::vector<SensorPoint> readSensorCsv(const std::string& path, std::vector<std::string>* surfaces = nullptr);
// RADIANCE's rtrace input: "x y z dx dy dz" a line, white-space separated;
// blank lines and '#' comments skipped. `name` names the stream in errors.
std::vector<SensorPoint> readRadiancePoints(std::istream& in, const std::string& name);

// --- How the irradiance is computed ------------------------------------------

enum class SensorMethod {
    Cache,     // --method jittered|regular|query|exact: direct light per point; indirect from the refined caches
    Raytrace,  // --method raytrace: the jittered sampler's frusta with Embree shadow rays, direct light only
    Path,      // --method path: the path tracer, direct and indirect with their standard errors
};

struct SensorSettings {
    SensorMethod kind = SensorMethod::Cache;
    std::string method;                  // the --method name written in probe's `method` column
    // Cache
    DirectChoice direct;
    CacheSettings cache;
    IndirectChoice indirect;             // decided for the scene by measureSensors
    std::optional<double> seconds;       // refine the caches for at most this long (s); none: until converged
    // Raytrace (its passes and seed are direct.passes, direct.seed)
    DirectSamplerSettings raytrace;
    // Path
    PathTracerSettings path;
    int spp = 1024;                      // directions per point

    // "jittered 64x64, 8 bits/pixel, cv estimator, 1 pass", "path tracer: 1024 samples per point, max depth 8, seed 1"
    std::string describe() const;
};

// Declares --method and every option of the methods (direct, cache,
// indirect, --direct-only, --time, --spp, --max-depth, --threads), as probe
// has them. `defaultSeconds`: --time's default ("20"); none: the caches
// refine until converged unless --time is given (probe).
void declareSensorOptions(Options& options, std::optional<std::string> defaultSeconds = std::nullopt);
// Reads them; `args` (the command line) tells which options the user wrote,
// since an option that does not apply to the chosen method is refused.
SensorSettings readSensorSettings(const Options& options, const std::vector<std::string>& args);

// --- Measuring ----------------------------------------------------------------

// One point's irradiance, W·m⁻², RGB.
struct SensorValue {
    std::vector<Rgb> directPerLight;  // Scene::lights order
    Rgb direct{0.0};                  // their sum
    Rgb indirect{0.0};                // every bounce (SensorReadings::indirect)
    Rgb directError{0.0}, indirectError{0.0};  // standard errors, --method path only
    double seconds = 0;               // time spent on this point's direct light (path: on the whole point)
};

struct SensorReadings {
    std::vector<SensorValue> values;  // the points evaluated, in their order: all, or a prefix when interrupted
    bool indirect = false;            // indirect light was computed (E_indirect columns)
    int samples = 0;                  // estimates per point: passes × lights, or path samples
    bool interrupted = false;         // a signal cut refinement or the points short
    // When interrupted: what was cut, "refinement after 3.2 s" or "the points".
    std::string cut;
};

// Irradiance at `points` (progress on stderr labelled `label`). Decides
// settings.indirect for the scene and prints the reason ("indirect light:
// ...") for the Cache method. `interrupt` may be null (not interruptible).
SensorReadings measureSensors(const Scene& scene, SensorSettings& settings, const std::vector<SensorPoint>& points,
                              const char* label, const InterruptGuard* interrupt);

}  // namespace ml
