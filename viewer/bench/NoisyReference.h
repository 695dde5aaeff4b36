// Error against a noisy path-traced reference, for the benches that measure
// full global illumination (bench lights, bench gi): a reference is itself a
// Monte Carlo image, so its noise is taken out of every error in quadrature;
// the path tracer's curve at doubling samples per pixel; and when a curve
// first reaches an error level.
#pragma once

#include "core/Camera.h"
#include "core/image/Image.h"
#include "core/image/ImageMetrics.h"
#include "core/raytrace/PathTracer.h"

#include <optional>
#include <vector>

namespace ml {

class BenchRun;
class EmbreeScene;

// A path-traced reference and its standard error, per pixel and channel.
struct Reference {
    ImageRgb radiance, standardError;
    int spp = 0;
    double seconds = 0;
    double noise = 0;  // relativeRmsError(standardError, radiance), ImageMetrics.h
};

// The path tracer's image of `camera` at `spp` samples per pixel, with its
// standard error, the time it took (on settings.threads) and its noise.
Reference renderReference(const EmbreeScene& rays, const Camera& camera, int width, int height, int spp,
                          const PathTracerSettings& settings);

// A walkthrough's references: renderReference for each camera, view v
// with the stream seedFor(settings.seed, tag, v), one after another (so
// that nothing else runs while they are timed); the progress and a line of
// totals printed through `run`.
struct ViewReferences {
    std::vector<Reference> views;  // by camera
    double seconds = 0;            // all of them
    double noiseMax = 0;           // the largest relative noise
};
ViewReferences renderViewReferences(const BenchRun& run, const EmbreeScene& rays, const std::vector<Camera>& cameras,
                                    int width, int height, int spp, const PathTracerSettings& settings, uint32_t tag);

// The mean of two independent references of the same view (other streams),
// weighted by their samples per pixel; its standard error combined from
// theirs. `seconds` is the sum of theirs.
Reference averageReferences(const Reference& a, const Reference& b);

struct ImageError {
    double raw = 0;        // ml::relativeRmse against the reference
    double corrected = 0;  // the same with the reference's noise taken out
};

// Against a reference r with noise σ, E[(x − r)²] = (x − R)² + σ² for the
// true image R (r's noise is independent of x), so mean((x − r)² − σ²)
// weighted as relativeRmse weighs it estimates the squared error against R.
// Pooled over every pixel and channel it is precise even where σ is
// comparable to the error; it may come out below 0 only where the error is
// far below σ, hence the max. Throws InputError when the sizes differ.
ImageError errorAgainst(const ImageRgb& x, const Reference& ref);

// The path tracer's image at doubling samples per pixel. Each step renders
// as many new samples per pixel as the image already has (the first step
// `firstSpp`), from fresh streams (seedFor(settings.seed, step)), and
// averages: the image at N samples costs one N-sample render and is the same
// estimator. Its variance per pixel and channel is combined from each
// step's halves, for the tracer's own estimate of its error.
// (BenchConvergence.cpp keeps a depth-1 twin measured against an exact image.)
class DoublingPathTracer {
public:
    // `rays` must outlive the tracer; settings.seed is the base of every step's.
    DoublingPathTracer(const EmbreeScene& rays, const Camera& camera, int width, int height,
                       const PathTracerSettings& settings, int firstSpp = 2);

    void step();
    int spp() const { return spp_; }
    // Samples per pixel the next step adds.
    int nextSpp() const { return next_; }
    double seconds() const { return seconds_; }  // wall time of every step so far
    const ImageRgb& image() const { return image_; }
    // Its standard error per pixel and channel.
    ImageRgb standardError() const;
    // Its own relative noise (relativeRmsError), weighted by `reference`.
    double ownNoise(const ImageRgb& reference) const;
    // The image and its standard error as a Reference (seconds: every step's).
    Reference asReference() const;

private:
    const EmbreeScene& rays_;
    Camera camera_;
    int width_, height_;
    PathTracerSettings settings_;
    int next_;
    int spp_ = 0, steps_ = 0;
    double seconds_ = 0;
    ImageRgb image_, variance_;
};

// When a curve of (seconds, error) points, in time order, first reaches
// `level`: interpolated in log-log between the point above it and the first
// at or below it (errors fall as a power of time); the first point's time if
// it is already there. None: not reached.
std::optional<double> timeToLevel(const std::vector<double>& seconds, const std::vector<double>& errors,
                                  double level);

}  // namespace ml
