#include "SamplerPool.h"

#include "core/Error.h"

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>

namespace ml {

namespace {

// One helper thread and the samplers it made: it runs one task at a time.
class Helper {
public:
    explicit Helper(const SamplerFactory& factory) {
        thread_ = std::thread([this, &factory] { run(factory); });
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [&] { return ready_; });
        if (error_) {
            lock.unlock();
            finish();
            std::rethrow_exception(error_);
        }
    }
    ~Helper() { finish(); }

    WorkerSamplers& samplers() { return samplers_; }
    void post(std::function<void()> task) {
        {
            std::lock_guard<std::mutex> lock(mutex_);
            task_ = std::move(task);
            busy_ = true;
        }
        wake_.notify_all();
    }
    void wait() {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [&] { return !busy_; });
    }

private:
    void run(const SamplerFactory& factory) {
        try {
            samplers_ = factory();
        } catch (...) {
            error_ = std::current_exception();
        }
        {
            std::lock_guard<std::mutex> lock(mutex_);
            ready_ = true;
        }
        wake_.notify_all();
        for (;;) {
            std::function<void()> task;
            {
                std::unique_lock<std::mutex> lock(mutex_);
                wake_.wait(lock, [&] { return busy_ || quit_; });
                if (quit_ && !busy_) break;
                task = std::move(task_);
            }
            task();  // catches its own exceptions (Impl::forEach)
            {
                std::lock_guard<std::mutex> lock(mutex_);
                busy_ = false;
            }
            wake_.notify_all();
        }
        // The samplers (and their GL contexts) die on the thread that made them.
        samplers_ = WorkerSamplers();
    }
    void finish() {
        {
            std::lock_guard<std::mutex> lock(mutex_);
            quit_ = true;
        }
        wake_.notify_all();
        if (thread_.joinable()) thread_.join();
    }

    std::thread thread_;
    std::mutex mutex_;
    std::condition_variable wake_;
    std::function<void()> task_;
    bool ready_ = false, busy_ = false, quit_ = false;
    std::exception_ptr error_;
    WorkerSamplers samplers_;
};

}  // namespace

struct SamplerPool::Impl {
    WorkerSamplers own;  // the calling thread's
    std::vector<std::unique_ptr<Helper>> helpers;

    WorkerSamplers& set(size_t k) { return k == 0 ? own : helpers[k - 1]->samplers(); }
    size_t size() const { return helpers.size() + 1; }

    // f(samplers, i) for every i in [0, count), spread over the threads in
    // increasing i. The failure with the lowest index is rethrown: every
    // index below it was taken by some thread before it, so it is the first
    // failure in request order, whatever the threads.
    void forEach(size_t count, const std::function<void(WorkerSamplers&, size_t)>& f) {
        if (helpers.empty() || count < 2) {
            for (size_t i = 0; i < count; ++i) f(own, i);
            return;
        }
        std::atomic<size_t> next{0};
        std::atomic<bool> failed{false};
        std::mutex failureMutex;
        size_t failedAt = ~size_t(0);
        std::exception_ptr failure;
        auto work = [&](WorkerSamplers& samplers) {
            for (;;) {
                if (failed.load(std::memory_order_relaxed)) return;
                const size_t i = next.fetch_add(1);
                if (i >= count) return;
                try {
                    f(samplers, i);
                } catch (...) {
                    std::lock_guard<std::mutex> lock(failureMutex);
                    if (i < failedAt) failedAt = i, failure = std::current_exception();
                    failed = true;
                }
            }
        };
        for (auto& h : helpers) h->post([&work, &h] { work(h->samplers()); });
        work(own);
        for (auto& h : helpers) h->wait();
        if (failure) std::rethrow_exception(failure);
    }
    // f(samplers) once on every thread, at once (building sources).
    void onEveryThread(const std::function<void(WorkerSamplers&)>& f) {
        std::mutex failureMutex;
        std::exception_ptr failure;
        auto guarded = [&](WorkerSamplers& samplers) {
            try {
                f(samplers);
            } catch (...) {
                std::lock_guard<std::mutex> lock(failureMutex);
                if (!failure) failure = std::current_exception();
            }
        };
        for (auto& h : helpers) h->post([&guarded, &h] { guarded(h->samplers()); });
        guarded(own);
        for (auto& h : helpers) h->wait();
        if (failure) std::rethrow_exception(failure);
    }
};

namespace {

class PooledDirect final : public DirectSampler {
public:
    explicit PooledDirect(SamplerPool::Impl& pool) : pool_(pool) {}
    std::string name() const override {
        return concat(pool_.own.direct->name(), pool_.size() > 1 ? concat(", on ", pool_.size(), " threads") : "");
    }
    VertexSample sample(size_t light, const Vec3& x, const Vec3& n, uint32_t seed) override {
        return pool_.own.direct->sample(light, x, n, seed);
    }
    // Blocks of requests, handed out in order, each a batch of its thread's
    // sampler (which may draw several images before reading any back); a
    // batch gives what sample() gives, so the blocks change no result.
    void sampleBatch(const std::vector<SampleRequest>& requests, std::vector<VertexSample>& results) override {
        results.resize(requests.size());
        if (pool_.size() == 1) {
            pool_.own.direct->sampleBatch(requests, results);
            return;
        }
        constexpr size_t kBlock = 16;
        const size_t blocks = (requests.size() + kBlock - 1) / kBlock;
        pool_.forEach(blocks, [&](WorkerSamplers& s, size_t b) {
            const size_t begin = b * kBlock, end = std::min(requests.size(), begin + kBlock);
            const std::vector<SampleRequest> block(requests.begin() + std::ptrdiff_t(begin),
                                                   requests.begin() + std::ptrdiff_t(end));
            std::vector<VertexSample> out;
            try {
                s.direct->sampleBatch(block, out);
            } catch (const SampleBatchError& e) {
                throw SampleBatchError(begin + e.index(), e.what());
            }
            std::copy(out.begin(), out.end(), results.begin() + std::ptrdiff_t(begin));
        });
    }
    bool sampleWithoutGpu(size_t light, const Vec3& x, const Vec3& n, uint32_t seed, VertexSample& out) override {
        return pool_.own.direct->sampleWithoutGpu(light, x, n, seed, out);
    }
    // Blocks over the threads, as sampleBatch: a few microseconds a pair,
    // but a first pass asks for every vertex of every light.
    void sampleBatchWithoutGpu(const std::vector<SampleRequest>& requests, std::vector<VertexSample>& results,
                               std::vector<char>& answered) override {
        results.resize(requests.size());
        answered.assign(requests.size(), 0);
        constexpr size_t kBlock = 256;
        const size_t blocks = (requests.size() + kBlock - 1) / kBlock;
        pool_.forEach(blocks, [&](WorkerSamplers& s, size_t b) {
            const size_t begin = b * kBlock, end = std::min(requests.size(), begin + kBlock);
            sampleEachWithoutGpu(*s.direct, requests, results, answered, begin, end);
        });
    }
    // Every thread's sampler, between batches (when every helper is idle).
    void firstSamples(bool first) override {
        for (size_t k = 0; k < pool_.size(); ++k) pool_.set(k).direct->firstSamples(first);
    }
    // Between batches every helper is idle: its sampler's totals are still.
    DirectPhaseTimes phaseTimes() const override {
        DirectPhaseTimes t;
        for (size_t k = 0; k < pool_.size(); ++k) t += pool_.set(k).direct->phaseTimes();
        return t;
    }

private:
    SamplerPool::Impl& pool_;
};

class PooledIndirect final : public IndirectEstimator {
public:
    explicit PooledIndirect(SamplerPool::Impl& pool) : pool_(pool) {}
    std::string name() const override { return pool_.own.indirect->name(); }
    void setSource(size_t slot, const std::vector<IrradianceMeshCopy>& irradiance, double importance) override {
        pool_.onEveryThread([&](WorkerSamplers& s) { s.indirect->setSource(slot, irradiance, importance); });
    }
    void releaseSource(size_t slot) override {
        pool_.onEveryThread([&](WorkerSamplers& s) { s.indirect->releaseSource(slot); });
    }
    Rgb estimate(size_t slot, const Vec3& x, const Vec3& n, uint32_t seed) override {
        return pool_.own.indirect->estimate(slot, x, n, seed);
    }
    VertexSample estimateSample(size_t slot, const Vec3& x, const Vec3& n, uint32_t seed) override {
        return pool_.own.indirect->estimateSample(slot, x, n, seed);
    }
    VertexSample estimateRequest(size_t slot, const SampleRequest& r) override {
        return pool_.own.indirect->estimateRequest(slot, r);
    }
    double borderInset() const override { return pool_.own.indirect->borderInset(); }
    bool separatesSides() const override { return pool_.own.indirect->separatesSides(); }
    // A share of the vertices on each thread (each builds its own lookup of
    // the whole mesh, so no more parts than threads).
    std::optional<std::vector<Rgb>> seenAlbedo(const IrradianceMeshCopy& mesh, size_t begin, size_t end, int rays,
                                               uint32_t seed) override {
        const size_t parts = std::max<size_t>(1, std::min(pool_.size(), (end - begin) / 256));
        std::vector<std::optional<std::vector<Rgb>>> part(parts);
        pool_.forEach(parts, [&](WorkerSamplers& s, size_t k) {
            part[k] = s.indirect->seenAlbedo(mesh, begin + (end - begin) * k / parts,
                                             begin + (end - begin) * (k + 1) / parts, rays, seed);
        });
        std::vector<Rgb> all;
        all.reserve(end - begin);
        for (const auto& p : part) {
            if (!p) return std::nullopt;
            all.insert(all.end(), p->begin(), p->end());
        }
        return all;
    }
    void estimateBatch(size_t slot, const std::vector<SampleRequest>& requests,
                       std::vector<VertexSample>& results) override {
        results.resize(requests.size());
        pool_.forEach(requests.size(), [&](WorkerSamplers& s, size_t i) {
            const SampleRequest& r = requests[i];
            asBatchRequest(i, [&] { results[i] = s.indirect->estimateRequest(slot, r); });
        });
    }
    // Memory and work of every thread's sources and gathers; build time as
    // the first thread's (the threads build at once).
    IndirectStats stats() const override {
        IndirectStats all = pool_.own.indirect->stats();
        for (size_t k = 1; k < pool_.size(); ++k) {
            const IndirectStats s = pool_.set(k).indirect->stats();
            all.sourceBytes += s.sourceBytes;
            all.estimates += s.estimates;
            all.estimateSeconds += s.estimateSeconds;
        }
        return all;
    }

private:
    SamplerPool::Impl& pool_;
};

}  // namespace


SamplerPool::SamplerPool(const SamplerFactory& factory, int threads) : impl_(std::make_unique<Impl>()) {
    ML_ASSERT(threads >= 1, "a sampler pool of ", threads, " threads");
    impl_->own = factory();
    for (int k = 1; k < threads; ++k) impl_->helpers.push_back(std::make_unique<Helper>(factory));
    direct_ = std::make_unique<PooledDirect>(*impl_);
    if (impl_->own.indirect) indirect_ = std::make_unique<PooledIndirect>(*impl_);
}

SamplerPool::~SamplerPool() {
    indirect_.reset();
    direct_.reset();
    impl_->helpers.clear();  // each helper's samplers die on its thread
    impl_->own = WorkerSamplers();
}

int SamplerPool::threads() const { return int(impl_->size()); }
DirectSampler& SamplerPool::direct() { return *direct_; }
IndirectEstimator* SamplerPool::indirect() { return indirect_.get(); }

}  // namespace ml
