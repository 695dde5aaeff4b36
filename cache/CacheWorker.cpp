#include "CacheWorker.h"

#include "SamplerPool.h"

#include "core/Error.h"
#include "core/Random.h"

#include <algorithm>
#include <chrono>

namespace ml {

namespace {
// Direct light's error counts as if it were its estimate over this: the
// worker shares its time as if direct light's error were twice what it
// estimates (see run()). Under a sample budget, direct light's turn while
// its estimated error is at least this share of indirect light's.
constexpr double kDirectWeight = 0.5;
// ...times 1 − this × the share of direct light the mesh the lights share
// holds (LightCoverage.h; see run()).
constexpr double kSharedDiscount = 0.4;
// The least share of the worker's time either part keeps once indirect
// light has started (without a sample budget).
constexpr double kLeastShare = 0.125;
// The longest a direct or indirect round should last once indirect light
// has started (without a sample budget).
constexpr double kRoundSeconds = 1.0;
// The shares count this much of the worker's most recent time (seconds).
constexpr double kShareWindow = 8.0;
// Publishing a snapshot takes at most this share of the worker's time
// (WorkerSettings::publishSeconds), and the image waits at most this share
// of the time since the worker started for a snapshot or an indirect round:
// early, when every round changes the image much, they come often.
constexpr double kPublishShare = 0.1;
}  // namespace

void WorkerSettings::validate() const {
    if (!(publishSeconds >= 0 && publishSeconds <= 3600))
        throw InputError(concat("snapshot interval ", publishSeconds, " s is not in [0, 3600]"));
    if (roundBudget > (size_t(1) << 24)) throw InputError(concat("round budget ", roundBudget, " is above 2^24"));
    if (refinementLevels < 0 || refinementLevels > IrradianceCache::kMaxRefinementLevel)
        throw InputError(concat("refinement levels ", refinementLevels, " is not in 0..",
                                IrradianceCache::kMaxRefinementLevel));
}

CacheWorker::CacheWorker(IrradianceCache& cache, SamplerFactory factory, const WorkerSettings& settings,
                         IndirectSolver* indirect, CausticCache* caustics)
    : cache_(cache),
      factory_(std::move(factory)),
      indirect_(indirect),
      caustics_(caustics && caustics->active() ? caustics : nullptr),
      settings_(settings) {
    settings_.validate();
    ML_ASSERT(factory_, "the cache worker needs a sampler factory");
}

uint64_t CacheWorker::totalSamples() const {
    return cache_.totalSamples() + (indirect_ ? indirect_->totalSamples() : 0);
}

CacheWorker::~CacheWorker() { stop(); }

void CacheWorker::start() {
    ML_ASSERT(!thread_.joinable() && !finished_, "the cache worker starts once");
    thread_ = std::thread([this] { run(); });
}

void CacheWorker::pause() {
    std::lock_guard<std::mutex> lock(mutex_);
    paused_ = true;
}

void CacheWorker::resume() {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        paused_ = false;
    }
    wake_.notify_all();
}

void CacheWorker::stop() {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        stopping_ = true;
    }
    wake_.notify_all();
    if (thread_.joinable()) thread_.join();
}

uint64_t CacheWorker::setCamera(const std::optional<RefinementCamera>& view) {
    uint64_t serial;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        view_ = view;
        viewChanged_ = true;
        serial = ++cameraSerial_;
    }
    wake_.notify_all();
    return serial;
}

void CacheWorker::rethrowIfFailed() const {
    std::lock_guard<std::mutex> lock(mutex_);
    if (failure_) std::rethrow_exception(failure_);
}

bool CacheWorker::waitForVersion(uint64_t version, double timeoutSeconds) {
    std::unique_lock<std::mutex> lock(mutex_);
    return wake_.wait_for(lock, std::chrono::duration<double>(timeoutSeconds),
                          [&] { return published_ >= version || finished_; });
}

void CacheWorker::publish(double seconds, bool converged, const std::optional<RefinementCamera>& view,
                          uint64_t cameraSerial, SamplerPool& samplers) {
    auto snap = std::make_unique<CacheSnapshot>();
    snap->seconds = seconds;
    for (size_t l = 0; l < cache_.meshCount(); ++l) {
        snap->direct.push_back(cache_.copyMesh(l));
        snap->verticesPerMesh.push_back(cache_.vertexCount(l));
    }
    snap->vertices = cache_.totalVertices();
    snap->samples = cache_.totalSamples();
    snap->rounds = cache_.rounds();
    // Only this thread changes the cache while the worker lives: an
    // unchanged cache (IrradianceCache::changeKey) seen from the same camera
    // keeps its score.
    const std::array<uint64_t, 4> key = cache_.changeKey();
    if (!lastDirectError_ || lastDirectError_->cache != key || lastDirectError_->camera != cameraSerial)
        lastDirectError_ = KeptScore{key, cameraSerial, cache_.estimatedError(view)};
    snap->directError = lastDirectError_->error;
    if (indirect_) {
        snap->indirect = indirect_->displayMeshes();
        // While direct light's first pass is incomplete, bounce 1 reflects
        // a direct light partly guessed from neighbours (an early start):
        // its light, and every later bounce's, is assumed off by
        // kGuessedLightError.
        if (cache_.unsampledCount() > 0)
            for (IrradianceMeshCopy& m : snap->indirect) {
                m.predictedError.resize(m.irradiance.size(), Rgb(0.0));
                for (size_t i = 0; i < m.irradiance.size(); ++i)
                    m.predictedError[i] = glm::max(m.predictedError[i], kGuessedLightError * m.irradiance[i]);
            }
        snap->bounces = indirect_->bounces();
        snap->bouncesFinished = indirect_->finished();
        snap->indirectComplete = indirect_->firstPassDone() && !indirect_->showingStale();
        snap->oldIndirectKept = indirect_->keepingStale();
        snap->indirectStale = indirect_->showingStale();
        if (!snap->indirectComplete) snap->bounceMeshes = indirect_->copyMeshes();
        snap->indirectVertices = indirect_->totalVertices();
        snap->indirectSamples = indirect_->totalSamples();
        snap->vertices += snap->indirectVertices;
        snap->samples += snap->indirectSamples;
        snap->indirectError = indirect_->estimatedError(view);
        if (samplers.indirect()) {
            snap->indirectStats = samplers.indirect()->stats();
            snap->bounceLayout = bounceCacheLayout(*samplers.indirect());
        }
    }
    if (caustics_) {
        snap->indirect.push_back(caustics_->copyMesh());
        snap->causticMeshes = 1;
        snap->causticPhotons = caustics_->photonsEmitted();
        snap->causticError = caustics_->estimatedError();
    }
    snap->directPhases = samplers.direct().phaseTimes();
    snap->estimatedError = std::max({snap->directError, snap->indirectError, snap->causticError});
    snap->converged = converged;
    snap->cameraSerial = cameraSerial;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        snap->version = ++published_;
    }
    if (settings_.onPublish) settings_.onPublish(*snap);
    snapshots_.publish(std::move(snap));
    wake_.notify_all();
}

void CacheWorker::run() {
    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();
    auto seconds = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
    try {
        const int threads =
            settings_.threads > 0 ? settings_.threads : int(std::max(1u, std::thread::hardware_concurrency()));
        SamplerPool pool(factory_, threads);
        DirectSampler& sample = pool.direct();
        IndirectEstimator* estimator = pool.indirect();
        ML_ASSERT(!indirect_ || estimator, "indirect light needs an estimator from the sampler factory");
        // What bounce 1 reflects: direct light and, with it, the caustics.
        const auto directMeshes = [&] {
            std::vector<IrradianceMeshCopy> m = cache_.copyMeshes();
            if (caustics_) m.push_back(caustics_->copyMesh());
            return m;
        };
        // A stop ends the round under way between two of its batches
        // (IrradianceCache::setInterrupt), not after it: a round of the back
        // rooms' direct light took 25 s, and render --time 15 ran to 42 s.
        // The bounces' gathers are cut the same way (a round of them lasts
        // up to kRoundSeconds); what else a round does (scoring, a bounce's
        // source built) is not: the Cornell box's block moved in bench
        // dynamic --quick still waited up to 0.2-0.3 s for its worker's loop.
        // Not under a sample budget (or repeatable), whose rounds no clock
        // may decide: a stop then waits for the round.
        struct InterruptWhileHere {
            IrradianceCache& cache;
            IndirectSolver* indirect;
            ~InterruptWhileHere() {
                cache.setInterrupt({});
                if (indirect) indirect->setInterrupt({});
            }
        } interruptible{cache_, indirect_};
        if (!settings_.maxSamples && !settings_.repeatable) {
            const auto stopping = [this] { return stopping_.load(); };
            cache_.setInterrupt(stopping);
            if (indirect_) indirect_->setInterrupt(stopping);
        }
        double lastPublish = -1e30, publishCost = 0;
        bool converged = false, directConverged = false, indirectStarted = false, sourceIncomplete = false;
        double directRate = 0;  // direct samples per second in the last round
        // Gathers per second in the last indirect round, and whether that
        // round was in a first pass (whose gathers may be far cheaper).
        double gatherRate = 0;
        bool gatherRateFirstPass = true;
        double lastDirectError = 1, lastIndirectError = 1;
        // What indirect light's error is worth against direct light's
        // (bounce 1's light over direct light's), measured every 16th
        // indirect round.
        double indirectWeight = 0;
        double directWeight = kDirectWeight;  // kDirectWeight, less for the light the lights share
        uint64_t indirectWeightRounds = 0;
        uint64_t rounds = 0, causticWaits = 0;
        double directSeconds = 0, indirectSeconds = 0;  // each part's rounds since indirect light started
        bool indirectIdle = false;  // its last step found it converged at its last level: nothing to share
        std::optional<RefinementCamera> lastView;
        uint64_t serial = 0;
        for (;;) {
            std::optional<RefinementCamera> view;
            {
                std::unique_lock<std::mutex> lock(mutex_);
                // Idle while paused, or converged for this view, until told otherwise.
                wake_.wait(lock, [&] { return stopping_ || (!paused_ && (!converged || viewChanged_)); });
                if (stopping_) break;
                if (viewChanged_) converged = directConverged = false;
                viewChanged_ = false;
                view = view_;
                lastView = view;
                serial = cameraSerial_;
            }
            // No round takes more than what is left of the sample budget.
            const auto capped = [&](size_t budget) {
                if (!settings_.maxSamples) return budget;
                const uint64_t left = settings_.maxSamples - totalSamples();
                return size_t(std::min<uint64_t>(budget, std::max<uint64_t>(left, 1)));
            };
            if (settings_.maxSamples && totalSamples() >= settings_.maxSamples) break;
            // A sample budget, or a caller asking for it, makes the schedule
            // one of rounds, read from no clock (WorkerSettings::repeatable).
            const bool byRounds = settings_.maxSamples || settings_.repeatable;
            // Once indirect light is under way, the two share the worker's
            // time by their errors e_d and e_i (both relative to direct
            // light): direct light takes e_d² / (e_d² + (w·e_i)²) of it,
            // w = kDirectWeight, each part at least kLeastShare so neither
            // stalls. Both errors fall as the root of the time spent on
            // them, e² = c / t; the least total c_d/t_d + c_i/t_i for a given
            // time has t_d / t_i = e_d²/e_i². With w = 1 that lost on the
            // offices with many lights (48 panels at 16 s: 4.1% against
            // 3.5%), whose direct light errs by more than it estimates; w =
            // ½ keeps the equilibrium of the rule before ("direct light's
            // turn while its error is at least half of indirect light's",
            // e_d = e_i / 2) and only makes the share smooth. What changed
            // the back rooms is the weight of indirect light's error (below)
            // and rounds of at most kRoundSeconds: the rule before
            // gave direct light 87.5% of their worker, in rounds of 5 s,
            // while the image showed the first pass's noise in indirect
            // light (their render at 20 s: 10.0% relative RMSE, 8.05% now;
            // cache/README.md). The shares count the last kShareWindow
            // seconds (the first passes' long turns do not decide a minute
            // later).
            // The share is of time: a direct round (up to 16,384 samples,
            // ~0.4 s in a 48-panel office) lasts a hundred indirect ones (a
            // later bounce's 512 gathers of 16 rays, a few ms). Under a
            // sample budget (or WorkerSettings::repeatable) it is of rounds,
            // which no clock decides (the same cache on any machine, loaded
            // or not): direct light's turn while its
            // error is at least kDirectWeight of indirect light's, and one
            // round in eight regardless; both share one round while direct
            // light's turn lasts.
            // Where the lights share a mesh (LightCoverage.h), w shrinks
            // with the share φ of direct light that mesh holds, w = ½ (1 −
            // kSharedDiscount·φ): its estimates, K lights drawn among
            // hundreds, err by more than the cache's estimate says (most
            // likely as their noise hides structure from the residuals,
            // which count only beyond twice it). Under 192 panels (φ =
            // 0.91) at 16 s direct light estimated 2.0% against indirect
            // light's 6.6%, and so took a quarter of the time, while the
            // image's error was half direct light's (2.5 %² of 6.1); the
            // 12-panel office (φ = 0.25) read 1.9% against 4.0% for 0.6 %²
            // of 3.0. Measured (render office:panels=16x12,panelsize=0.4
            // --width 320 --height 180 --time 20): 2.48% relative RMSE on
            // average over four runs with w = ½, 2.40% over seven with this
            // (each run within ±0.1%); the 12 panels at 10 s 2.17, 2.17%
            // against 2.24, 2.13%; the back rooms (φ = 0.003) and the
            // Cornell box (no shared mesh) keep w = ½. Measured when that
            // mesh drew K pairs; with its shadow rays (SharedLightSampler)
            // its error is a quarter of what it was, and the discount is
            // neutral (192 panels at 20 s: 1.93, 1.93% with it, 1.96, 1.85%
            // with w = ½), so it stays until a measurement says otherwise.
            // Bounce 1's first pass, once started, runs without direct
            // rounds between: until it is gathered the image lacks all
            // indirect light (a room's ceiling is black), which is more than
            // what the rest of direct light's first pass adds.
            const bool firstBounceDue = indirectStarted && !indirect_->firstBounceGathered();
            const double shared = directSeconds + indirectSeconds;
            bool directTurn = !indirectStarted, indirectTurn = true;
            if (indirectStarted && !firstBounceDue) {
                if (byRounds) {
                    directTurn = lastDirectError >= directWeight * lastIndirectError || ++rounds % 8 == 0;
                } else {
                    const double d2 = lastDirectError * lastDirectError, i2 = lastIndirectError * lastIndirectError;
                    const double w2 = directWeight * directWeight;
                    const double share = std::clamp(d2 / std::max(d2 + w2 * i2, 1e-300), kLeastShare, 1 - kLeastShare);
                    directTurn = indirectIdle || directSeconds < share * shared;
                    indirectTurn = !directTurn || directConverged;
                }
            }
            if (!directConverged && directTurn) {
                size_t budget = settings_.roundBudget;
                if (budget == 0) budget = std::clamp<size_t>(cache_.totalVertices() / 32, 256, 16384);
                // Once the two parts share the worker, a direct round lasts
                // at most kRoundSeconds at the last round's rate: the
                // share is kept between rounds, and where a pair costs
                // milliseconds (the back rooms: 3,768 samples took 5 s) a
                // round in vertices would hold indirect light off for
                // seconds at a time. Not under a sample budget, whose
                // rounds no clock may decide.
                if (indirectStarted && !byRounds && directRate > 0)
                    budget = std::min(budget, std::max<size_t>(64, size_t(directRate * kRoundSeconds)));
                const double before = seconds();
                const RefineReport report = cache_.refine(sample, capped(budget), settings_.seed, view);
                const double took = seconds() - before;
                if (indirectStarted) directSeconds += took;
                // Direct samples per second in the last round, for when to
                // start indirect light. Not smoothed over rounds: the first
                // pass's first round takes every pair that needs no GPU, a
                // hundred times faster than the rest will go.
                if (report.estimates > 0 && took > 0) directRate = double(report.estimates) / took;
                directConverged = report.converged();
                lastDirectError = report.estimatedError;
            }
            if (directSeconds + indirectSeconds > kShareWindow) {
                const double f = kShareWindow / (directSeconds + indirectSeconds);
                directSeconds *= f, indirectSeconds *= f;
            }
            bool indirectConverged = true;
            if (indirect_) {
                // Indirect light starts once direct light is nearly right,
                // then alternates with it round by round.
                const size_t unsampled = cache_.unsampledCount();
                const double firstPass = 1 - double(unsampled) / double(std::max<size_t>(cache_.totalVertices(), 1));
                const double left = directRate > 0 ? double(unsampled) / directRate : 1e30;
                const IndirectSettings& is = indirect_->settings();
                // After a scene change the image shows the old indirect light
                // until bounce 1 is gathered again: it starts at once, from
                // direct light as far as it is (gathered again when complete).
                // With a stand-in for it in the image, it waits for direct
                // light's first pass instead (WorkerSettings::indirectStandIn).
                // A sample budget makes the same cache on any machine, loaded
                // or not: the rate, a wall-clock measure, does not decide the
                // start then, and indirect light waits for the first pass.
                const bool slow = !byRounds && left > is.startSeconds;
                const bool early = indirect_->showingStale() || (firstPass >= is.startFraction && slow);
                // Bounce 1 also reflects the caustics (light off mirrors and
                // through glass: a lamp under a mirror ceiling lights the
                // floor with nothing else), whose photons start once direct
                // light's first pass is complete: it is not gathered from
                // their mesh before its first round (it would hold none of
                // that light and, its first-pass samples staying in its
                // means, keep too little of it), but after it, a round later.
                const bool causticsTraced = !caustics_ || caustics_->photonsEmitted() > 0;
                if (!indirectStarted && ((causticsTraced && (directConverged || unsampled == 0)) ||
                                         (early && !settings_.indirectStandIn))) {
                    indirectStarted = true;
                    sourceIncomplete = unsampled > 0 || !causticsTraced;
                }
                // Bounce 1 reflected an incomplete first pass (or caustics
                // not traced yet): gather every bounce again now that direct
                // light is complete and the caustics have their first round.
                if (indirectStarted && sourceIncomplete && unsampled == 0 && causticsTraced) {
                    indirect_->restart(*estimator);
                    sourceIncomplete = false;
                }
                indirectConverged = false;
                if (indirectStarted && indirectTurn && !(settings_.maxSamples && totalSamples() >= settings_.maxSamples)) {
                    const bool firstPassRound = !indirect_->firstPassDone();
                    size_t budget = settings_.indirectBudget;
                    if (budget == 0) {
                        const size_t vertices = indirect_->started() ? indirect_->cache(indirect_->started()).totalVertices()
                                                                     : cache_.totalVertices() / std::max<size_t>(cache_.lightCount(), 1);
                        // An eighth of the bounce's vertices, as many as
                        // kRoundSeconds allow at the last round's rate (a
                        // tenth of the time since the start, early on): a
                        // round also scores the bounce's mesh, which cost
                        // the back rooms' 72,000-vertex bounce 65 ms a
                        // round, against 25 ms for 512 gathers of 16 rays,
                        // so rounds of at most 512 spent most of indirect
                        // light's share scoring (their render at 20 s:
                        // 8.2% relative RMSE, 5.0-5.1% with this; the 48-
                        // panel office at 16 s 3.5-3.7%, the same). Under a sample
                        // budget at most 512, as before: no clock decides.
                        budget = std::clamp<size_t>(vertices / 8, 16, byRounds ? 512 : 16384);
                        if (!byRounds) {
                            const bool rateHolds = gatherRate > 0 && gatherRateFirstPass == firstPassRound;
                            const double roundSeconds = std::clamp(kPublishShare * seconds(), 0.25, kRoundSeconds);
                            budget = std::min(budget, rateHolds ? std::max<size_t>(512, size_t(gatherRate * roundSeconds))
                                                                : size_t(512));
                        }
                    }
                    const double before = seconds();
                    const RefineReport r = indirect_->step(*estimator, directMeshes, capped(budget), settings_.seed, view);
                    const double took = seconds() - before;
                    indirectSeconds += took;
                    if (r.estimates > 0 && took > 0) {
                        gatherRate = double(r.estimates) / took;
                        gatherRateFirstPass = firstPassRound;
                    }
                    indirectConverged = r.converged();
                    if (indirect_->firstPassDone()) {
                        // The bounces' error is relative to bounce 1's light;
                        // the image's share of that light is what the caches
                        // hold: bounce 1's integral over direct light's.
                        // The albedo light meets is that ratio in a closed
                        // room without glowing surfaces; where these
                        // (GatheredLights) put their light into bounce 1, or
                        // light leaves the scene, it is not: the back
                        // rooms' view shows indirect light at 0.48 of direct
                        // light, 3.4 times their albedo, and weighed by
                        // that, indirect light waited while its first
                        // pass's noise was what the image showed.
                        // Counted in rounds, not seconds: under a sample
                        // budget no clock may decide whose turn it is.
                        if (indirectWeightRounds++ % 16 == 0) {
                            const double d = cache_.integratedLuminance();
                            const double b = indirect_->cache(1).integratedLuminance();
                            indirectWeight = d > 0 && b > 0 ? b / d : indirect_->settings().albedo;
                            const double phi = d > 0 ? std::clamp(cache_.sharedLuminance() / d, 0.0, 1.0) : 0.0;
                            directWeight = kDirectWeight * (1 - kSharedDiscount * phi);
                        }
                        lastIndirectError = r.estimatedError * indirectWeight;
                    }
                }
            }
            // A round of photons once direct light's first pass is complete
            // (the image needs that first), until the caustics are under
            // their tolerance; it shares the worker by errors as direct and
            // indirect light do: while the caustics' relative noise is at
            // least half the larger of the other two errors, and every
            // fourth round regardless.
            bool causticConverged = true;
            if (caustics_ && !caustics_->converged()) {
                causticConverged = false;
                const bool turn = caustics_->estimatedError() >= 0.5 * std::max(lastDirectError, lastIndirectError) ||
                                  ++causticWaits % 4 == 0;
                if (cache_.unsampledCount() == 0 && turn) caustics_->round(seedFor(settings_.seed, 0xca057u));
            }
            // A part converged at its level is tightened one level and goes
            // on, whatever the others do: the rounds are shared by the
            // parts' errors (above), so a part whose tolerances were met
            // early (indirect light in a room lit mostly indirectly, whose
            // direct light needs many more rounds at the same tolerance)
            // keeps getting closer instead of idling until the others
            // converge while its error is what the image shows.
            if (directConverged && cache_.level() < settings_.refinementLevels && cache_.tighten())
                directConverged = false;
            if (indirect_ && indirectConverged && estimator && indirect_->level() < settings_.refinementLevels &&
                indirect_->tighten(*estimator))
                indirectConverged = false;
            if (caustics_ && causticConverged && caustics_->level() < settings_.refinementLevels &&
                caustics_->tighten())
                causticConverged = false;
            if (indirect_ && indirectTurn && indirectStarted) indirectIdle = indirectConverged;
            converged = directConverged && indirectConverged && causticConverged;
            // Snapshots copy and score every mesh: in the back rooms and the
            // 48-panel office (10^5 vertices and more) one took 0.13-0.22 s,
            // and at one every 0.25 s (or after each longer round) they
            // took 22% of the worker's time. Not sooner than the last one's
            // cost over kPublishShare, then, unless a tenth of the time since
            // the start is sooner: early every round changes the image much
            // (with snapshots up to 2 s apart from the start, `bench lights`'
            // walkthrough took 12.2 s instead of 9.3 s, and its 48-panel
            // office reached 10% at 6.3 s instead of 4.2 s).
            const double interval =
                settings_.publishSeconds > 0
                    ? std::max(settings_.publishSeconds, std::min(publishCost / kPublishShare, kPublishShare * seconds()))
                    : 0.0;
            if (converged || seconds() - lastPublish >= interval || published_ == 0) {
                const double before = seconds();
                publish(before, converged, view, serial, pool);
                lastPublish = seconds();
                publishCost = lastPublish - before;
            }
        }
        publish(seconds(), converged, lastView, serial, pool);
    } catch (...) {
        std::lock_guard<std::mutex> lock(mutex_);
        failure_ = std::current_exception();
    }
    {
        std::lock_guard<std::mutex> lock(mutex_);
        finished_ = true;
    }
    wake_.notify_all();
}

}  // namespace ml
