// The reference: a unidirectional path tracer on the CPU (Embree), what
// every approximation of Meshlight is measured against.
//
// Estimator. At every scattering vertex one light is chosen in proportion to
// its power (luminance of π·Le·area), a point uniformly by area on it (a
// triangle by area, then a uniform point of that triangle), and a shadow ray
// is traced (next-event estimation); the BSDF (PhongBsdf.h) draws the next
// direction, and an emitter that this direction hits adds its emission too.
// The two estimates of direct light are combined by multiple importance
// sampling with the power heuristic (Veach 1997), each pdf in solid angle.
// Emitters radiate from their front (counter-clockwise) face only, as in
// core/Scene.h; every other surface reflects on both sides.
//
// Mirrors and glass (core/SmoothSpecular.h, SmoothSpecularBsdf.h). At a
// surface with a smooth layer the path goes on by reflection, refraction or
// the diffuse Kd under the layer, chosen in proportion to their weights
// (unbiased: the throughput is divided by the probability of the choice).
// Next-event estimation sees the diffuse lobe only; an emitter hit after a
// reflection or refraction counts fully (no other strategy can find it),
// and so does one seen from the camera through a chain of them. Shadow rays
// (area and punctual lights alike, PunctualShadow.h) treat mirrors and
// glass as opaque: light that reaches a surface through glass or off a
// mirror is a caustic, which this tracer finds by BSDF sampling alone (so
// caustics of small lights are noisy, but never missing). Refracted rays
// leave from the far side of the surface, and whether a ray enters or
// leaves a closed object is read from the geometric normal's side.
//
// Depth. A path of depth D counts the emission seen directly, the direct
// light at the first surface and D − 1 indirect bounces:
//   D = 1   emission + direct light (what `render --direct-only` computes)
//   D = 2   + one bounce of indirect light, and so on.
// In a closed box of albedo a whose walls all emit Le, the radiance is
// Le·(1 + a + … + a^D) = Le·(1 − a^(D+1))/(1 − a), tending to Le/(1 − a).
// For irradiance at a point (irradiance()), the point itself is the first
// vertex: D = 1 is direct irradiance only, D = 2 adds light that bounced once.
// A reflection or refraction by a smooth layer adds no level: a mirror shows
// at depth D what the scene shows at depth D (as the compositor, which
// follows such rays to the cache, does), up to 256 such bounces a path.
//
// Russian roulette. From the `rouletteDepth`-th scattering vertex on, a path
// survives each bounce with probability q = min(0.95, max channel of its
// throughput) and its throughput is divided by q: unbiased (the expectation
// is that of the depth-D estimator), it only trims paths that carry little.
//
// Determinism. Every pixel sample (and every irradiance sample) draws from
// its own random stream, seeded from (seed, pixel, sample index) with
// core/Random.h's hashing, and each pixel is summed in sample order by one
// thread: the image is bit-identical for a given seed whatever the number of
// threads.
//
// Camera and pixels. The same pinhole model and 1-pixel box filter as the
// compositor (viewer/Compositor.cpp): the vertical field of view spans the
// image height, row 0 is at the top, and each pixel is the mean radiance over
// its area (uniform jitter within the pixel), so a reference and a `render`
// image compare pixel for pixel.
//
// Noise. Samples with even and odd indices form two independent half
// estimates a and b of each pixel; the image is the mean of all samples, and
// its standard error per channel is estimated from the halves as
// |a − b|·√(n_a·n_b)/n (|a − b|/2 for an even sample count): an unbiased
// estimate of the variance with one degree of freedom per pixel, so it is
// noisy pixel by pixel and reliable once pooled over a region.
#pragma once

#include "EmbreeScene.h"
#include "core/Camera.h"
#include "core/EmitterTexture.h"
#include "core/Scene.h"
#include "core/image/Image.h"

#include <atomic>
#include <cstdint>
#include <functional>
#include <vector>

namespace ml {

struct PathTracerSettings {
    // Emission + direct + (maxDepth − 1) indirect bounces (see above); 1..1024,
    // typical 8.
    int maxDepth = 8;
    // Scattering vertices before Russian roulette may end a path; >= 1, typical 3.
    int rouletteDepth = 3;
    // Worker threads; 0 uses every core (std::thread::hardware_concurrency).
    int threads = 0;
    // User seed; the same seed gives the same image bit for bit.
    uint32_t seed = 1;

    void validate() const;  // InputError naming the bad value
};

// A rendered reference.
struct ReferenceImage {
    ImageRgb radiance;       // linear, W·sr⁻¹·m⁻²: mean of every sample of each pixel
    ImageRgb standardError;  // per channel, of the mean, from the two halves (see above)
    // Mean over pixels with positive luminance of SE(luminance)/luminance,
    // SE of the luminance estimated from the halves like the channels.
    double meanRelativeError = 0;
    size_t litPixels = 0;    // pixels that entered meanRelativeError
    uint64_t paths = 0;      // camera paths in the images (width × height × samplesPerPixel)
    double seconds = 0;      // wall time of the render
    // Samples in every pixel: the spp asked for, or fewer whole passes when
    // stopped early (0: stopped before the first pass ended; images black).
    int samplesPerPixel = 0;
    bool cancelled = false;  // stopped early by RenderControl::stop: fewer samples than asked for
};

// Progress and cancellation of a render.
struct RenderControl {
    // Called on the calling thread, about ten times a second and once at the
    // end of each pass, with camera paths done and in all.
    std::function<void(uint64_t done, uint64_t total)> progress;
    // When set and true, workers stop after their current tile and the pass
    // under way is dropped: the images hold the passes done before.
    const std::atomic<bool>* stop = nullptr;
    // Samples per pixel a pass adds to every pixel, even, typical 2 (0: one
    // pass of all). The last pass may be shorter; the image is bit for bit
    // the same whatever the pass size.
    int passSamples = 0;
};

// Irradiance at a point, split by origin (W·m⁻², RGB).
struct IrradianceEstimate {
    std::vector<Rgb> directPerLight;  // from each light, Scene::lights order, unoccluded parts only
    Rgb direct{0.0};                  // Σ of directPerLight
    Rgb indirect{0.0};                // light that reflected at least once
    Rgb directError{0.0};             // standard error of `direct`, from the samples' variance
    Rgb indirectError{0.0};           // standard error of `indirect`
    uint64_t samples = 0;
};

class PathTracer {
public:
    // `rays` (and its scene) must outlive the tracer.
    PathTracer(const EmbreeScene& rays, const PathTracerSettings& settings);

    const PathTracerSettings& settings() const { return settings_; }

    // A width × height image from `camera` with `samplesPerPixel` samples
    // (>= 2: the halves estimate the noise), in passes (RenderControl).
    // Throws InputError for bad sizes.
    ReferenceImage render(const Camera& camera, int width, int height, int samplesPerPixel,
                          const RenderControl& control = {}) const;

    // Irradiance at x on a surface of unit normal n (the upper hemisphere of
    // n), from `samples` cosine-weighted directions combined with one sample
    // of every light each (MIS, power heuristic). Rays leave from x lifted
    // by EmbreeScene::rayOffset along n. `pointId` decorrelates points
    // (use the point's index): sample k draws from (seed, pointId, k).
    // Spread over the settings' threads, deterministic like render().
    IrradianceEstimate irradiance(const Vec3& x, const Vec3& n, int samples, uint32_t pointId) const;

private:
    const EmbreeScene& rays_;
    const Scene& scene_;
    PathTracerSettings settings_;
    // Light selection by power, and triangle selection by area per light.
    std::vector<double> lightCdf_;                   // cumulative, last = 1 (empty: no light emits)
    std::vector<double> lightProbability_;           // per light
    std::vector<std::vector<double>> triangleCdf_;   // per light, cumulative area fraction
    std::vector<EmitterTexture> emitters_;           // per light: L / L̄ of a textured light

    struct Vertex;
    struct Stream;
    static Vertex vertexAt(const SurfacePoint& s, const Vec3& incoming, const Scene& scene);
    Rgb scattered(const Vertex& first, Stream& rng, int depth) const;
    Rgb sampleLight(const Vertex& v, Stream& rng) const;
    // A point y of `light` (by area) with its normal and radiance there.
    bool lightPoint(size_t light, double u0, double u1, double u2, Vec3& y, Vec3& normal, Rgb& radiance) const;
    Rgb radiance(const Vec3& origin, const Vec3& direction, Stream& rng) const;
    int threadCount() const;
};

}  // namespace ml
