#include "IndirectSolver.h"

#include "core/Error.h"
#include "core/Random.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ml {

namespace {

// A bounce's first pass spends at most `firstPassGathers` full gathers: a
// base of `base` vertices larger than that is gathered at this share of a
// gather's effort each (1: full gathers).
double firstPassEffort(double base, double firstPassGathers, bool firstPass) {
    return firstPass && base > firstPassGathers ? firstPassGathers / base : 1.0;
}

}  // namespace

CacheSettings IndirectSettings::defaultCache() {
    CacheSettings c;
    c.maxEdgeFraction = 1.0 / 8;    // indirect light varies slowly...
    // ...and a gather sees the scene at the voxels' resolution (64 along the
    // longest side by default, a voxel ~1/110 of the diagonal): finer edges
    // would only resolve the voxels' own steps.
    c.minEdgeFraction = 1.0 / 64;
    c.minEdgePixels = 4;
    // Judged against indirect light's own level, which is a part of what
    // the image shows (a third to a half in a room lit from above), so
    // looser than direct light's 1% and 0.5%.
    c.splitTolerance = 0.04;
    c.noiseTolerance = 0.03;
    c.maxSamplesPerVertex = 16;
    c.singleSampleNoise = 0;  // no visibility steps: samples are never partial
    // Cut along contacts (ContactCuts.h): indirect light darkens sharply
    // where a surface hangs close (within the gap's own length),
    // and the gathers' noise hides that from refinement. Direct light's
    // meshes are not cut: the sampler sees a contact's shadow as partial
    // visibility and refinement follows it.
    c.contactCloseness = 0.1;
    c.lightPlaneCuts = false;
    // One 40×40 jittered slice gather in the Cornell box: 0.5–2% relative
    // spread between seeds; assume 3% until the vertices sampled twice
    // measure it (IrradianceCache::sampleNoise: the ray gather measured
    // 5–6% per gather of 256 rays in the Cornell box's first bounce).
    c.sampleNoise = 0.03;
    return c;
}

void IndirectSettings::validate() const {
    if (bounces < 0 || bounces > 256) throw InputError(concat("bounce count ", bounces, " is not in 0..256"));
    if (!(albedo >= 0 && albedo <= 1)) throw InputError(concat("albedo ", albedo, " is not in [0, 1]"));
    if (!(tailAlbedo >= 0 && tailAlbedo <= 1))
        throw InputError(concat("tail albedo ", tailAlbedo, " is not in [0, 1]"));
    if (!(startFraction >= 0 && startFraction <= 1))
        throw InputError(concat("indirect start fraction ", startFraction, " is not in [0, 1]"));
    if (!(startSeconds >= 0)) throw InputError(concat("indirect start seconds ", startSeconds, " is negative"));
    if (!(firstPassGathers >= 1))
        throw InputError(concat("indirect first-pass gathers ", firstPassGathers, " is not at least 1"));
    cache.validate();
}

IndirectSolver::IndirectSolver(const Scene& scene, const IndirectSettings& settings)
    : scene_(scene), settings_(settings) {
    settings_.validate();
    resetPass2();
}

void IndirectSolver::resetPass2() {
    converged_.assign(size_t(settings_.bounces), 0);
    bounceError_.assign(size_t(settings_.bounces), std::numeric_limits<double>::infinity());
}

double IndirectSolver::share(int bounce) const { return std::pow(settings_.albedo, double(bounce - 1)); }

int IndirectSolver::nextBounce() const {
    int best = 1;
    double worst = -1;
    for (int b = 1; b <= settings_.bounces; ++b) {
        const size_t slot = size_t(b - 1);
        if (!converged_[slot] && bounceError_[slot] > worst) best = b, worst = bounceError_[slot];
    }
    return best;
}

IndirectSolver::~IndirectSolver() = default;

CacheSettings bounceCacheSettings(const IndirectSettings& settings, int bounce) {
    CacheSettings c = settings.cache;
    const double share = std::pow(std::max(settings.albedo, 1e-3), bounce - 1);
    c.splitTolerance = std::min(0.5, c.splitTolerance / share);
    c.noiseTolerance = std::min(0.5, c.noiseTolerance / share);
    // Every bounce is smoother than the one before: later bounces keep bounce
    // 1's base mesh (coarser ones would put vertices only in the corners,
    // where indirect light is lowest, and interpolate the walls too dark)
    // but are split at most once.
    if (bounce > 1) c.minEdgeFraction = std::max(c.minEdgeFraction, c.maxEdgeFraction / 2);
    // Once its base is gathered, every bounce is split down to half its
    // base edge whatever the error predicted (CacheSettings::
    // uniformEdgeFraction): indirect light falls towards corners and edges,
    // linear interpolation reads that dark, and the gathers' noise hides
    // the curvature that would ask for the splits. The error compounds:
    // each bounce reflects its predecessor as interpolated. Measured on the
    // office (render office --width 160 --height 90 --time 60 against a
    // 4,096-spp reference, cache/README.md): indirect light 2.5% dark with
    // the base alone, 1.8% once split (the image 3.45% → 3.01%); a base of
    // half the edge from the start, 1.0% dark, 2.93%, but 6.6% at 5 s
    // against 4.0%: starting coarse keeps the first complete image quick.
    c.uniformEdgeFraction = std::max(c.maxEdgeFraction / 2, std::min(c.minEdgeFraction, c.maxEdgeFraction));
    return c;
}

CacheSettings IndirectSolver::settingsFor(int bounce) const { return bounceCacheSettings(settings_, bounce); }

CacheLayout bounceCacheLayout() {
    CacheLayout layout;
    layout.meshes = 1;
    // Sides of open surfaces as for direct light: a side no light
    // reaches gets no copy (and shows black). A gather that keeps a thin
    // surface's sides apart also copies the backs reflected light reaches
    // (IndirectSolver::step).
    layout.backFaces = CacheLayout::BackFaces::LitFromBehind;
    layout.insetBorders = true;
    return layout;
}

CacheLayout bounceCacheLayout(const IndirectEstimator& estimator) {
    CacheLayout layout = bounceCacheLayout();
    layout.borderInset = estimator.borderInset();
    // The back of a luminaire hung under a ceiling too, not the inside of
    // an open box (BackFaceReach.h).
    if (estimator.separatesSides()) layout.backFaces = CacheLayout::BackFaces::ReachedByScene;
    return layout;
}

void IndirectSolver::prepareSource(IndirectEstimator& estimator, int bounce,
                                   const std::function<std::vector<IrradianceMeshCopy>()>& direct, bool firstPass) {
    const size_t slot = size_t(bounce - 1);
    if (sourceBuilt_.size() <= slot) sourceBuilt_.resize(slot + 1, false);
    if (sourceForFirstPass_.size() <= slot) sourceForFirstPass_.resize(slot + 1, false);
    if (sourceBuilt_[slot] && (firstPass || !sourceForFirstPass_[slot])) return;
    const double base = double(caches_.at(slot)->totalVertices());
    const double effort = firstPassEffort(base, settings_.firstPassGathers, firstPass);
    if (bounce == 1)
        estimator.setSource(0, direct(), effort);
    else
        estimator.setSource(slot, {copyMesh(bounce - 1)},
                            effort * std::pow(std::max(settings_.albedo, 1e-3), bounce - 1));
    sourceBuilt_[slot] = true;
    sourceForFirstPass_[slot] = firstPass;
    if (sourceSamples_.size() <= slot) sourceSamples_.resize(slot + 1, 0);
    sourceSamples_[slot] = bounce >= 2 ? caches_[slot - 1]->totalSamples() : 0;
}

void IndirectSolver::releaseSource(IndirectEstimator& estimator, size_t slot) {
    if (slot >= sourceBuilt_.size() || !sourceBuilt_[slot]) return;
    estimator.releaseSource(slot);
    sourceBuilt_[slot] = false;
}

RefineReport IndirectSolver::step(IndirectEstimator& estimator,
                                  const std::function<std::vector<IrradianceMeshCopy>()>& direct, size_t budget,
                                  uint32_t seed, const std::optional<RefinementCamera>& view) {
    if (settings_.bounces == 0) return {};
    // Pass 1: the next bounce's base mesh, gathered once.
    if (!firstPassDone() && firstPassBounce() == 0) {
        const int bounce = int(caches_.size()) + 1;
        // The previous bounce's source is not needed until pass 2.
        if (bounce > 2) releaseSource(estimator, size_t(bounce - 2));
        // Every bounce lays the same surfaces (bounceCacheSettings changes
        // only tolerances and the smallest edges): cut along contacts once.
        CacheLayout layout = bounceCacheLayout(estimator);
        if (!surfaces_) surfaces_ = std::make_shared<const std::vector<Mesh>>(cacheSurfaces(scene_, settingsFor(1)));
        layout.surfaces = surfaces_;
        caches_.push_back(std::make_unique<IrradianceCache>(scene_, settingsFor(bounce), layout));
        caches_.back()->setInterrupt(interrupt_);
        // Only a tail after bounce 1 reads it: none with one bounce.
        if (bounce == 1 && settings_.bounces > 1) {
            std::optional<std::vector<Rgb>> seen = seenAlbedoOver(estimator, caches_.back()->copyMesh(0), seed);
            std::lock_guard<std::mutex> lock(memoMutex_);
            seenAlbedo_ = seen ? std::move(*seen) : std::vector<Rgb>();
        }
        prepareSource(estimator, bounce, direct, true);
    }
    const bool first = !firstPassDone();
    const int bounce = first ? firstPassBounce() : allFinished() ? 1 : nextBounce();
    const size_t slot = size_t(bounce - 1);
    // A first pass gathered again (restart): only the source it gathers from is kept.
    if (first)
        for (size_t s = 0; s < sourceBuilt_.size(); ++s)
            if (s != slot) releaseSource(estimator, s);
    // Pass 2 refines bounce 1 from direct light as it is now, not as it was
    // when the first pass began.
    if (!first && bounce == 1 && !directRefreshed_) {
        sourceBuilt_.resize(std::max<size_t>(sourceBuilt_.size(), 1), false);
        sourceBuilt_[0] = false;
        directRefreshed_ = true;
    }
    // In pass 2 a later bounce's source follows its predecessor's
    // refinement: built again each time the predecessor's samples have
    // doubled since (a rebuild costs a copy of the mesh, a few
    // hundredths of a second; doubling keeps them to a few per bounce).
    if (!first && bounce >= 2 && slot < sourceBuilt_.size() && sourceBuilt_[slot] && !sourceForFirstPass_[slot] &&
        caches_[slot - 1]->totalSamples() >= 2 * std::max<uint64_t>(sourceSamples_[slot], 1))
        releaseSource(estimator, slot);
    prepareSource(estimator, bounce, direct, first);
    // A first pass of cheap gathers (a base larger than firstPassGathers)
    // measures its noise with probes (IrradianceCache::setNoiseProbes):
    // the level assumed for a full gather (sampleNoise, 3%) read the back
    // rooms' 16-ray gathers as 1.7% of the image's error at 11 s, where
    // the image measured 9.4% against a path-traced reference, all of it
    // the indirect layer's blotches (render ../shared/scenes/backrooms-gltf
    // /scene.gltf --width 320 --height 180 --time 11). Every 64th vertex:
    // 1.6% more gathers, at least 78 probes (kMeasuredNoiseFreedom is 64).
    constexpr size_t kNoiseProbeEvery = 64;
    const double base = double(caches_[slot]->totalVertices());
    const bool cheapPass = firstPassEffort(base, settings_.firstPassGathers, first) < 1;
    caches_[slot]->setNoiseProbes(cheapPass ? kNoiseProbeEvery : 0);
    // The bounce's one mesh is filled by gathers from its source slot.
    struct Gather : VertexSampler {
        IndirectEstimator& estimator;
        size_t slot;
        Gather(IndirectEstimator& e, size_t s) : estimator(e), slot(s) {}
        VertexSample sample(size_t, const Vec3& x, const Vec3& n, uint32_t seed) override {
            return estimator.estimateSample(slot, x, n, seed);
        }
        void sampleBatch(const std::vector<SampleRequest>& requests, std::vector<VertexSample>& results) override {
            estimator.estimateBatch(slot, requests, results);
        }
    } gather(estimator, slot);
    // Each bounce draws its own jitter. While vertices have no sample, a
    // round only samples them (IrradianceCache::refine).
    RefineReport report = caches_[slot]->refine(gather, budget, seedFor(seed, 0x1d1ec7u, uint32_t(bounce)), view);
    if (bounce == 1 && caches_[0]->unsampledCount() == 0) regathering_ = false;
    if (restarted_ && firstPassDone()) restarted_ = false;
    if (!stale_.empty() && !showingStale()) {
        stale_.clear();
        keepStale_ = false;
    }
    if (first) {
        report.candidates = std::max<size_t>(report.candidates, 1);  // the first pass goes on
        return report;
    }
    if (allFinished()) return report;
    if (report.converged()) {
        converged_[slot] = 1;
        // Only bounce 1 keeps refining (for new views): later sources go.
        if (bounce >= 2) releaseSource(estimator, slot);
        // The next bounce gathers from this one as it now is, and its
        // convergence, judged from a source this one has since refined, is
        // judged again.
        if (bounce < settings_.bounces) {
            releaseSource(estimator, slot + 1);
            if (converged_[slot + 1]) {
                converged_[slot + 1] = 0;
                bounceError_[slot + 1] = std::numeric_limits<double>::infinity();
            }
        }
    }
    bounceError_[slot] = report.estimatedError * share(bounce);
    // What the bounces' errors add up to in the image, relative to bounce
    // 1's light (their errors are independent: root of the sum of squares),
    // from the rounds that measured them: what the worker weighs against
    // direct light's error.
    double sum = 0;
    for (double e : bounceError_)
        if (std::isfinite(e)) sum += e * e;
    report.estimatedError = std::sqrt(sum);
    // Not converged while bounces remain.
    report.candidates = allFinished() ? 0 : std::max<size_t>(report.candidates, 1);
    return report;
}

int IndirectSolver::firstPassBounce() const {
    for (size_t b = 0; b < caches_.size(); ++b)
        if (caches_[b]->unsampledCount() > 0) return int(b) + 1;
    return 0;
}

void IndirectSolver::restart(IndirectEstimator& estimator) {
    if (caches_.empty()) return;
    // Every started bounce: a later bounce's first-pass gathers came from
    // its predecessor as it was from incomplete direct light, and pass 2
    // keeps first-pass samples in its means (they left a 1.6% error in
    // the Cornell box when only bounce 1 was gathered again). Each first
    // pass runs again in order, each from its predecessor gathered anew.
    for (auto& c : caches_) c->resetSamples();
    ++epoch_;
    regathering_ = true;
    restarted_ = true;
    resetPass2();
    directRefreshed_ = true;  // the source about to be built is direct light as it is now
    for (size_t s = 0; s < sourceBuilt_.size(); ++s) releaseSource(estimator, s);
}

void IndirectSolver::setInterrupt(std::function<bool()> interrupted) {
    interrupt_ = std::move(interrupted);
    for (auto& c : caches_) c->setInterrupt(interrupt_);
}

void IndirectSolver::sceneChanged(bool keepOld) {
    std::vector<IrradianceMeshCopy> shown = displayMeshes();
    if (!shown.empty()) stale_ = std::move(shown);
    keepStale_ = keepOld && !stale_.empty();
    caches_.clear();
    {
        std::lock_guard<std::mutex> lock(memoMutex_);
        seenAlbedo_.clear();
    }
    ++epoch_;
    surfaces_.reset();
    resetPass2();
    directRefreshed_ = false;
    regathering_ = false;
    restarted_ = false;
    sourceBuilt_.assign(sourceBuilt_.size(), false);
}

bool IndirectSolver::tighten(IndirectEstimator& estimator) {
    if (!allFinished() || caches_.empty()) return false;
    bool tightened = false;
    for (auto& c : caches_) tightened |= c->tighten();
    if (!tightened) return false;
    resetPass2();
    directRefreshed_ = false;
    for (size_t s = 0; s < sourceBuilt_.size(); ++s) releaseSource(estimator, s);
    return true;
}

std::optional<std::vector<Rgb>> seenAlbedoOver(IndirectEstimator& estimator, const IrradianceMeshCopy& mesh,
                                               uint32_t seed) {
    std::optional<std::vector<Rgb>> seen =
        estimator.seenAlbedo(mesh, 0, mesh.positions.size(), kSeenAlbedoRays, seedFor(seed, 0xa1bed0u));
    if (!seen || seen->size() != mesh.positions.size()) return std::nullopt;
    // Each vertex with its one ring, the ring's vertices as often as they
    // are met (each face it is a corner of adds its other two).
    std::vector<Rgb> sum = *seen;
    std::vector<double> count(sum.size(), 1.0);
    for (const glm::uvec3& t : mesh.triangles)
        for (int k = 0; k < 3; ++k) {
            sum[t[k]] += (*seen)[t[(k + 1) % 3]] + (*seen)[t[(k + 2) % 3]];
            count[t[k]] += 2;
        }
    for (size_t v = 0; v < sum.size(); ++v) sum[v] /= count[v];
    return sum;
}

// A copy's vertex areas: a third of each face a vertex is a corner of.
static std::vector<double> vertexAreas(const IrradianceMeshCopy& mesh) {
    std::vector<double> area(mesh.positions.size(), 0.0);
    for (const glm::uvec3& t : mesh.triangles) {
        const Vec3 a = mesh.positions[t[0]], b = mesh.positions[t[1]], c = mesh.positions[t[2]];
        const double third = glm::length(glm::cross(b - a, c - a)) / 6;
        for (int k = 0; k < 3; ++k) area[t[k]] += third;
    }
    return area;
}

void shapeAsLaterBounces(IrradianceMeshCopy& mesh, int bounce, const std::vector<Rgb>& seenAlbedo) {
    const bool seen = seenAlbedo.size() == mesh.irradiance.size();
    if (bounce != 1 && !(bounce == 2 && seen)) return;
    const std::vector<double> area = vertexAreas(mesh);
    Rgb sum(0.0);
    double total = 0;
    for (size_t v = 0; v < area.size(); ++v) sum += area[v] * mesh.irradiance[v], total += area[v];
    if (!(total > 0)) return;
    const Rgb mean = sum / total;
    if (seen) {
        Rgb seenMean(0.0);
        for (size_t v = 0; v < area.size(); ++v) seenMean += area[v] * seenAlbedo[v];
        seenMean /= total;
        for (size_t v = 0; v < area.size(); ++v)
            for (int c = 0; c < 3; ++c)
                mesh.irradiance[v][c] = seenMean[c] > 0 ? mean[c] * seenAlbedo[v][c] / seenMean[c] : mean[c];
        return;
    }
    for (Rgb& e : mesh.irradiance) e = 0.5 * (e + mean);
}

int IndirectSolver::level() const { return caches_.empty() ? 0 : caches_.front()->level(); }

void fillHiddenVertices(IrradianceMeshCopy& mesh) {
    const size_t n = mesh.positions.size();
    if (n == 0) return;
    std::vector<std::vector<uint32_t>> ring(n);
    for (const glm::uvec3& t : mesh.triangles)
        for (int k = 0; k < 3; ++k) {
            ring[t[k]].push_back(t[(k + 1) % 3]);
            ring[t[k]].push_back(t[(k + 2) % 3]);
        }
    double mean = 0;
    for (const Rgb& e : mesh.irradiance) mean += luminance(e);
    mean /= double(n);
    std::vector<bool> hidden(n, false);
    for (size_t v = 0; v < n; ++v) {
        if (ring[v].empty() || luminance(mesh.irradiance[v]) >= 0.05 * mean) continue;
        double around = 0;
        for (uint32_t u : ring[v]) around += luminance(mesh.irradiance[u]);
        hidden[v] = luminance(mesh.irradiance[v]) < 0.05 * around / double(ring[v].size());
    }
    // Two rings in: a hidden patch a few base triangles across fills in.
    for (int pass = 0; pass < 2; ++pass) {
        std::vector<Rgb> next = mesh.irradiance;
        std::vector<bool> still = hidden;
        for (size_t v = 0; v < n; ++v) {
            if (!hidden[v]) continue;
            Rgb sum(0.0);
            int count = 0;
            for (uint32_t u : ring[v])
                if (!hidden[u]) sum += mesh.irradiance[u], ++count;
            if (count == 0) continue;
            next[v] = sum / double(count);
            still[v] = false;
        }
        mesh.irradiance = std::move(next);
        hidden = std::move(still);
    }
}

IndirectSolver::BounceMemo& IndirectSolver::memo(int bounce) const {
    const IrradianceCache& c = *caches_.at(size_t(bounce - 1));
    if (memo_.size() < caches_.size()) memo_.resize(caches_.size());
    BounceMemo& m = memo_[size_t(bounce - 1)];
    const std::array<uint64_t, 4> key = c.changeKey();
    if (m.cache != key || m.epoch != epoch_)
        m = BounceMemo{key, epoch_, std::nullopt, std::nullopt, std::nullopt, std::nullopt};
    return m;
}

const IrradianceMeshCopy& IndirectSolver::rawCopy(int bounce) const {
    BounceMemo& m = memo(bounce);
    if (!m.raw) m.raw = caches_[size_t(bounce - 1)]->copyMesh(0);
    return *m.raw;
}

// The raw copy is kept only where the ratio of displayMeshes asked for it.
const IrradianceMeshCopy& IndirectSolver::filledCopy(int bounce) const {
    BounceMemo& m = memo(bounce);
    if (!m.filled) {
        m.filled = m.raw ? *m.raw : caches_[size_t(bounce - 1)]->copyMesh(0);
        fillHiddenVertices(*m.filled);
    }
    return *m.filled;
}

IrradianceMeshCopy IndirectSolver::copyMesh(int bounce) const {
    std::lock_guard<std::mutex> lock(memoMutex_);
    return filledCopy(bounce);
}

std::vector<IrradianceMeshCopy> IndirectSolver::copyMeshes() const {
    std::lock_guard<std::mutex> lock(memoMutex_);
    std::vector<IrradianceMeshCopy> v;
    for (int b = 1; b <= started(); ++b) v.push_back(filledCopy(b));
    return v;
}

// A bounce being gathered is shown once a sixteenth of its base is (its
// first pass visits vertices in a scattered order and copies fill the rest
// from gathered neighbours, IrradianceCache::copyMesh). Measured on the
// office (render office --width 320 --height 180 --samples N against the
// 2,048-spp reference): bounce 1 shown from a fifth of its base gave 21.4%,
// complete 18.9%; bounce 2 shown from a sixteenth 10.4%, an eighth 9.2%, a
// quarter 8.2%, while not shown the image stayed at 18.9% (the tail scaled
// from bounce 1 puts bounce 1's distribution, too much on the ceiling, into
// every later bounce). A thirty-second gave 14.5%: too few vertices to fill
// from and to measure the bounces' ratio on.
static bool shownOnceGathered(size_t gathered, size_t total) { return 16 * gathered >= total; }

bool IndirectSolver::firstBounceShown() const {
    if (caches_.empty()) return false;
    const IrradianceCache& c = *caches_.front();
    return regathering_ || shownOnceGathered(c.totalVertices() - c.unsampledCount(), c.totalVertices());
}

bool IndirectSolver::firstBounceGathered() const {
    return !caches_.empty() && caches_.front()->unsampledCount() == 0;
}

// The relative error assumed for the tail's ratio r, and the share of the
// distance between its shape and bounce k's own taken as its shape's error
// (displayMeshes).
constexpr double kTailRatioError = 0.05;
constexpr double kTailShapeError = 0.3;

// Bounce k + 1's mean irradiance over its gathered vertices against bounce
// k's over all of its (copies as the caches hold them), each weighed by its
// area: bounce k may be refined already, its new vertices dense where light
// falls into corners and contacts, and a mean over vertices then reads it
// dark and the ratio high (the Cornell box, 256x256, bounce 2 shown and
// bounce 3 not: 2.75% and 2.70% by vertices, 2.63% and 2.49% by area).
// Channel by channel: light off coloured walls changes hue bounce after
// bounce. In the Cornell box's image bounce 2 holds 0.51, 0.47 and 0.38 of
// bounce 1's red, green and blue, and bounces 3 to 8 together 1.03, 0.91
// and 0.62 of bounce 2's (render cornell --bounces 1, 2, 3, 8, their
// indirect layers' means): one ratio for all three, their luminance's
// (0.47), makes the tail after bounce 2 0.88 of it in every channel, red
// 15% too dark and blue 42% too bright. A channel bounce k lacks takes
// the luminance's ratio; nullopt where either has no light.
static std::optional<Rgb> meanRatio(const IrradianceMeshCopy& k, const IrradianceMeshCopy& n) {
    const std::vector<double> areaK = vertexAreas(k), areaN = vertexAreas(n);
    Rgb sumK(0.0), sumN(0.0);
    double totalK = 0, totalN = 0;
    for (size_t v = 0; v < k.irradiance.size(); ++v) sumK += areaK[v] * k.irradiance[v], totalK += areaK[v];
    for (size_t v = 0; v < n.irradiance.size(); ++v)
        if (v < n.samples.size() && n.samples[v] > 0) sumN += areaN[v] * n.irradiance[v], totalN += areaN[v];
    if (!(totalK > 0) || !(totalN > 0) || luminance(sumK) <= 0) return std::nullopt;
    const Rgb meanK = sumK / totalK, meanN = sumN / totalN;
    const double whole = luminance(meanN) / luminance(meanK);
    Rgb r;
    for (int c = 0; c < 3; ++c) r[c] = meanK[c] > 0 ? meanN[c] / meanK[c] : whole;
    return r;
}

std::vector<IrradianceMeshCopy> IndirectSolver::displayMeshes() const {
    std::lock_guard<std::mutex> lock(memoMutex_);
    return displayMeshesLocked();
}

std::vector<IrradianceMeshCopy> IndirectSolver::displayMeshesLocked() const {
    if (showingStale()) return stale_;
    // The bounces whose first pass is complete, bounce 1 from a sixteenth
    // of it on; a bounce 1 being gathered again (restart) counts, its copies
    // showing old values until new ones.
    int complete = firstBounceShown() ? 1 : 0;
    // After restart() every started bounce shows its old values until
    // gathered again (IrradianceCache::resetSamples keeps them).
    while (complete > 0 && complete < started() &&
           (restarted_ || caches_[size_t(complete)]->unsampledCount() == 0))
        ++complete;
    // The bounce being gathered after them, once a sixteenth of its base is
    // (as bounce 1 is shown): its first pass visits vertices in a scattered
    // order and its copies fill the rest from gathered neighbours, whose
    // predicted error (kGuessedLightError) the estimate carries.
    // The ratio reads the copies before their hidden vertices are filled.
    std::optional<Rgb> ratio;
    int shown = complete;
    if (gatheredEnoughToShow(complete)) {
        ratio = meanRatio(rawCopy(complete), rawCopy(complete + 1));
        if (ratio) ++shown;
    }
    std::vector<IrradianceMeshCopy> v;
    for (int b = 1; b <= shown; ++b) v.push_back(filledCopy(b));
    complete = shown;
    if (complete == 0 || complete >= settings_.bounces) return v;
    // The bounces still to come, each r times the one before: Σ_{j=1..N−k} r^j
    // times the last bounce shown, k. r is measured once bounce k is shown
    // while gathered: its mean over the gathered vertices against bounce
    // k − 1's over its base. Until then, BounceCount::bounceRatio (by rays:
    // the area-weighted albedo overrates a room that light leaves). The
    // Cornell box (open in front), 64x64 after 12,000 samples of one
    // thread, bounce 1 complete and bounce 2 half gathered, measured 15%
    // with bounce 1 and an area-albedo tail, 9% with r measured, 2.5% with
    // bounce 2 shown as well (test_image_error).
    const Rgb a = glm::clamp(ratio.value_or(Rgb(settings_.tailAlbedo)), Rgb(0.0), Rgb(0.999));
    Rgb tail(0.0), term(1.0);
    for (int j = 1; j <= settings_.bounces - complete; ++j) tail += term *= a;
    IrradianceMeshCopy rest = v.back();
    shapeAsLaterBounces(rest, complete, seenAlbedo_);
    for (Rgb& e : rest.irradiance) e *= tail;
    // The tail is a model, not a measurement: its error is assumed to be
    // how far its shape may be off, kTailShapeError of the distance between
    // the shape shown and bounce k's own (none after bounce 3), and
    // kTailRatioError of it for its ratio r. With the tail shaped by the
    // albedo its vertices see, measured (the estimate against the path
    // tracer's error, net of the reference's noise), before bounce 2 is
    // shown: test_image_error's Cornell box 4.11% against 4.16% and small
    // office 8.42% against 7.13%; render cornell --width 256 --height 256
    // --samples 8000 5.95% against 4.50%; render office --width 320
    // --height 180 --samples 84000 10.3% against 8.88%. The whole distance
    // (as for the half-and-half shape before, whose own distance was half
    // as large) read 10.6%, 16.7%, and 2.5 and 1.9 times the error.
    rest.predictedError.resize(rest.irradiance.size());
    rest.predictedNoise.clear();  // a model's error: none of it is noise
    for (size_t i = 0; i < rest.irradiance.size(); ++i) {
        const Rgb shape = kTailShapeError * glm::abs(rest.irradiance[i] - tail * v.back().irradiance[i]);
        const Rgb scale = kTailRatioError * rest.irradiance[i];
        rest.predictedError[i] = glm::sqrt(shape * shape + scale * scale);
    }
    v.push_back(std::move(rest));
    return v;
}

bool IndirectSolver::gatheredEnoughToShow(int bounce) const {
    if (bounce < 1 || bounce >= started()) return false;
    const IrradianceCache& last = *caches_[size_t(bounce - 1)];
    const IrradianceCache& next = *caches_[size_t(bounce)];
    const size_t gathered = next.totalVertices() - next.unsampledCount();
    return last.level() == 0 && shownOnceGathered(gathered, next.totalVertices()) && last.totalVertices() > 0;
}


size_t IndirectSolver::totalVertices() const {
    size_t n = 0;
    for (const auto& c : caches_) n += c->totalVertices();
    return n;
}

uint64_t IndirectSolver::totalSamples() const {
    uint64_t n = 0;
    for (const auto& c : caches_) n += c->totalSamples();
    return n;
}

size_t IndirectSolver::memoryBytes() const {
    size_t n = 0;
    for (const auto& c : caches_) n += c->memoryBytes();
    return n;
}

double IndirectSolver::estimatedError(const std::optional<RefinementCamera>& view) const {
    if (settings_.bounces == 0) return 0;
    if (!firstPassDone()) return 1;
    std::lock_guard<std::mutex> lock(memoMutex_);
    const auto sameView = [](const std::optional<RefinementCamera>& a, const std::optional<RefinementCamera>& b) {
        if (!a || !b) return !a && !b;
        const Camera &x = a->camera, &y = b->camera;
        return x.position == y.position && x.target == y.target && x.up == y.up && x.fovYDegrees == y.fovYDegrees &&
               a->width == b->width && a->height == b->height;
    };
    double worst = 0;
    for (size_t b = 0; b < caches_.size(); ++b) {
        BounceMemo& m = memo(int(b) + 1);
        if (!m.error || !sameView(m.view, view)) m.error = caches_[b]->estimatedError(view), m.view = view;
        worst = std::max(worst, *m.error * share(int(b) + 1));
    }
    return worst;
}

}  // namespace ml
