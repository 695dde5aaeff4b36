// What a cache mesh needs from whatever fills it: one irradiance estimate at
// a vertex. Direct light (DirectSampler) and the indirect solver's gathers
// both fill cache meshes through this interface.
#pragma once

#include "core/Math.h"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace ml {

// One irradiance estimate at a vertex, with what the sampler saw of the light.
struct VertexSample {
    Rgb irradiance{0.0};  // W·m⁻²
    // Visible fraction of the light's cosine-weighted solid angle, in [0, 1]
    // (1 where nothing occludes the light).
    double visibility = 1;
    // Some but not all of the light's samples were visible: a penumbra.
    bool partial = false;
    // How near the surfaces are that the estimate saw: the harmonic mean of
    // its rays' distances to what they hit (Ward's R; a miss counts as
    // infinitely far). Irradiance may change by its own order over about
    // this distance (a contact's shadow, a corner), so an edge longer than
    // it may hold a step the plane fit cannot predict. Infinity where the
    // sampler does not know (direct light: its penumbrae say where it steps).
    double reach = std::numeric_limits<double>::infinity();
    // What the estimate cost, in the sampler's own units (a ray gather's
    // rays): its variance goes as the inverse, so a vertex's mean weighs
    // its samples by it (VertexStats), and a first pass's cheap gather
    // counts for what it is against a full one. 1 where every estimate of
    // a cache costs the same.
    double work = 1;
    // The variance of this estimate's luminance, (W·m⁻²)², as its own parts
    // scatter: a gather's rays taken as independent draws. Its rays are
    // stratified, which makes the true variance smaller by a factor that
    // differs from place to place and that the cache measures where it
    // resamples (detail::NoiseModel). What it tells is where one estimate
    // is likely off: a vertex whose few rays found a bright patch among
    // dark ones. < 0 where the sampler does not measure it (direct light's
    // samplers, the voxel gathers).
    double ownVariance = -1;
};

// One estimate to take: what sample() takes, for a batch.
struct SampleRequest {
    size_t mesh = 0;
    Vec3 x{0.0}, n{0.0, 0.0, 1.0};
    uint32_t seed = 0;
    // Where `numbered` (a cache vertex's sample): the vertex's own stream
    // and this sample's number in it (0 for its first). A sampler that
    // draws its points from a sequence (ScrambledSobol2D) takes block
    // `index` of stream `stream`, so that a vertex's samples together
    // stratify its integral more finely with every one. `seed` differs for
    // every sample; `stream` does not. Not numbered: `seed` alone.
    bool numbered = false;
    uint32_t stream = 0;
    uint32_t index = 0;
};

// Thrown by sampleBatch: which request failed, and why.
class SampleBatchError : public std::runtime_error {
public:
    SampleBatchError(size_t index, const std::string& what) : std::runtime_error(what), index_(index) {}
    size_t index() const { return index_; }

private:
    size_t index_;
};

class VertexSampler {
public:
    virtual ~VertexSampler() = default;
    // An estimate of mesh `mesh`'s irradiance at x (unit normal n), drawing
    // its randomness from `seed`: the mean over seeds is the sampler's answer.
    // Throws on failure; the cache adds where it happened.
    virtual VertexSample sample(size_t mesh, const Vec3& x, const Vec3& n, uint32_t seed) = 0;
    // Every request's estimate, results[i] for requests[i], each exactly
    // what sample() returns for it (so a batch may be spread over threads
    // without changing any result). A failure throws SampleBatchError naming
    // the first failing request; InputError passes through as it is.
    virtual void sampleBatch(const std::vector<SampleRequest>& requests, std::vector<VertexSample>& results);

    // sample()'s estimate where it takes no GPU work (a light below the
    // receiver's horizon, nothing in the way: a closed form), bit for bit
    // what sample() returns; false, `out` untouched, where it needs more.
    // The cache's first pass takes these before the others: a few
    // microseconds each, they put most of the light in the image at once.
    // The default answers none.
    virtual bool sampleWithoutGpu(size_t mesh, const Vec3& x, const Vec3& n, uint32_t seed, VertexSample& out);
    // The same for every request: answered[i] says whether results[i] holds
    // request i's estimate. Errors as for sampleBatch.
    virtual void sampleBatchWithoutGpu(const std::vector<SampleRequest>& requests, std::vector<VertexSample>& results,
                                       std::vector<char>& answered);
    // Whether the requests that follow are a first pass's (every vertex the
    // cache was laid with, once: the first complete image), until called
    // again with false. The cache says so before and after, the same on
    // every thread and machine. A sampler may then skip work that pays off
    // only over a point's later samples and its refined neighbours
    // (SharedLightSampler's asking which lights it can answer exactly), so
    // that the first image comes sooner. Both estimates must be unbiased;
    // the default ignores the hint.
    virtual void firstSamples(bool first) { (void)first; }
};

// firstSamples(true) for as long as it lives, then false.
class FirstSamples {
public:
    explicit FirstSamples(VertexSampler& sampler) : sampler_(sampler) { sampler_.firstSamples(true); }
    ~FirstSamples() { sampler_.firstSamples(false); }
    FirstSamples(const FirstSamples&) = delete;
    FirstSamples& operator=(const FirstSamples&) = delete;

private:
    VertexSampler& sampler_;
};

// Runs f() for request i of a batch: a failure other than an InputError (a
// user's mistake, passed as it is) becomes a SampleBatchError naming i.
void asBatchRequest(size_t i, const std::function<void()>& f);

// The one-at-a-time loop behind sampleBatch, for implementations that
// spread a batch: samples requests [begin, end) with `sampler.sample`.
void sampleEach(VertexSampler& sampler, const std::vector<SampleRequest>& requests, std::vector<VertexSample>& results,
                size_t begin, size_t end);
// sampleBatchWithoutGpu's loop over sampleWithoutGpu, for requests [begin, end).
void sampleEachWithoutGpu(VertexSampler& sampler, const std::vector<SampleRequest>& requests,
                          std::vector<VertexSample>& results, std::vector<char>& answered, size_t begin, size_t end);

// A VertexSampler from a callable, for closed forms in tests and benches:
// `f(mesh, x, n, seed)` returns a VertexSample, or an Rgb irradiance (then
// visibility 1, never partial).
template <class F>
class FunctionSampler final : public VertexSampler {
public:
    explicit FunctionSampler(F f) : f_(std::move(f)) {}
    VertexSample sample(size_t mesh, const Vec3& x, const Vec3& n, uint32_t seed) override {
        if constexpr (std::is_same_v<decltype(f_(mesh, x, n, seed)), VertexSample>)
            return f_(mesh, x, n, seed);
        else
            return VertexSample{f_(mesh, x, n, seed), 1.0, false};
    }

private:
    F f_;
};
template <class F>
FunctionSampler<F> samplerOf(F f) {
    return FunctionSampler<F>(std::move(f));
}

}  // namespace ml
