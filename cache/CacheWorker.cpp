#include "CacheWorker.h"

#include "core/Error.h"

#include <algorithm>
#include <chrono>

namespace ml {

void WorkerSettings::validate() const {
    if (!(publishSeconds >= 0 && publishSeconds <= 3600))
        throw InputError(concat("snapshot interval ", publishSeconds, " s is not in [0, 3600]"));
    if (roundBudget > (size_t(1) << 24)) throw InputError(concat("round budget ", roundBudget, " is above 2^24"));
}

CacheWorker::CacheWorker(IrradianceCache& cache, SamplerFactory factory, const WorkerSettings& settings)
    : cache_(cache), factory_(std::move(factory)), settings_(settings) {
    settings_.validate();
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

uint64_t CacheWorker::setView(const std::optional<RefinementView>& view) {
    uint64_t serial;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        view_ = view;
        viewChanged_ = true;
        serial = ++viewSerial_;
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

void CacheWorker::publish(double seconds, bool converged, const std::optional<RefinementView>& view,
                          uint64_t viewSerial) {
    auto snap = std::make_unique<CacheSnapshot>();
    snap->seconds = seconds;
    for (size_t l = 0; l < cache_.lightCount(); ++l) {
        snap->direct.push_back(cache_.view(l));
        snap->verticesPerMesh.push_back(cache_.vertexCount(l));
    }
    snap->vertices = cache_.totalVertices();
    snap->samples = cache_.totalSamples();
    snap->rounds = cache_.rounds();
    snap->estimatedError = cache_.estimatedError(view);
    snap->converged = converged;
    snap->viewSerial = viewSerial;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        snap->version = ++published_;
    }
    snapshots_.publish(std::move(snap));
    wake_.notify_all();
}

void CacheWorker::run() {
    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();
    auto seconds = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
    try {
        const DirectSampleFn sample = factory_();
        double lastPublish = -1e30;
        bool converged = false;
        std::optional<RefinementView> lastView;
        uint64_t serial = 0;
        for (;;) {
            std::optional<RefinementView> view;
            {
                std::unique_lock<std::mutex> lock(mutex_);
                // Idle while paused, or converged for this view, until told otherwise.
                wake_.wait(lock, [&] { return stopping_ || (!paused_ && (!converged || viewChanged_)); });
                if (stopping_) break;
                if (viewChanged_) converged = false;
                viewChanged_ = false;
                view = view_;
                lastView = view;
                serial = viewSerial_;
            }
            if (settings_.maxSamples && cache_.totalSamples() >= settings_.maxSamples) break;
            size_t budget = settings_.roundBudget;
            if (budget == 0) budget = std::clamp<size_t>(cache_.totalVertices() / 32, 256, 16384);
            if (settings_.maxSamples) {
                // No round takes more than what is left of the sample budget.
                const uint64_t left = settings_.maxSamples - cache_.totalSamples();
                budget = size_t(std::min<uint64_t>(budget, std::max<uint64_t>(left, 1)));
            }
            const RefineReport report = cache_.refine(sample, budget, settings_.seed, view);
            converged = report.converged();
            if (converged || seconds() - lastPublish >= settings_.publishSeconds || published_ == 0) {
                publish(seconds(), converged, view, serial);
                lastPublish = seconds();
            }
        }
        publish(seconds(), converged, lastView, serial);
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
