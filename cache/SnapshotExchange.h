// Hands immutable snapshots from one writer thread to a few reader threads
// without a lock on the readers' side.
//
// The writer publishes a new snapshot by swapping an atomic pointer; the
// old one is retired and deleted once no reader holds it. A reader pins the
// snapshot it reads with a hazard pointer (Michael 2004): it announces the
// pointer in its own slot, then checks it is still the current one, so the
// writer can never delete what a reader is looking at, and a reader never
// sees a half-built snapshot (it is complete before it is published).
// Readers are lock-free and wait-free in practice (they retry only if a
// publish lands between their two loads); the writer's reclamation is
// O(retired × readers).
#pragma once

#include "core/Error.h"

#include <array>
#include <atomic>
#include <memory>
#include <vector>

namespace ml {

template <class T, size_t MaxReaders = 8>
class SnapshotExchange {
public:
    SnapshotExchange() {
        for (auto& h : hazards_) h.store(nullptr);
        for (auto& u : used_) u.store(false);
    }
    ~SnapshotExchange() {
        delete current_.load();
        retired_.clear();
    }
    SnapshotExchange(const SnapshotExchange&) = delete;
    SnapshotExchange& operator=(const SnapshotExchange&) = delete;

    // Writer only. The snapshot must not change after this call.
    void publish(std::unique_ptr<T> snapshot) {
        T* old = current_.exchange(snapshot.release());
        if (old) retired_.emplace_back(old);
        reclaim();
    }

    // One reader thread's handle. A snapshot returned by acquire() stays
    // valid until this reader's next acquire() or release(), or its end.
    class Reader {
    public:
        Reader() = default;
        explicit Reader(SnapshotExchange* owner) : owner_(owner) {
            for (size_t i = 0; i < MaxReaders; ++i) {
                bool expected = false;
                if (owner_->used_[i].compare_exchange_strong(expected, true)) {
                    slot_ = i;
                    return;
                }
            }
            ML_ASSERT(false, "more than ", MaxReaders, " snapshot readers");
        }
        Reader(Reader&& o) noexcept : owner_(o.owner_), slot_(o.slot_) { o.owner_ = nullptr; }
        Reader& operator=(Reader&& o) noexcept {
            if (this != &o) {
                close();
                owner_ = o.owner_, slot_ = o.slot_;
                o.owner_ = nullptr;
            }
            return *this;
        }
        ~Reader() { close(); }

        // The latest published snapshot, or null before the first.
        const T* acquire() {
            std::atomic<T*>& hazard = owner_->hazards_[slot_];
            T* p = owner_->current_.load();
            for (;;) {
                hazard.store(p);
                T* again = owner_->current_.load();
                if (again == p) return p;
                p = again;
            }
        }
        void release() { owner_->hazards_[slot_].store(nullptr); }

    private:
        void close() {
            if (!owner_) return;
            release();
            owner_->used_[slot_].store(false);
            owner_ = nullptr;
        }
        SnapshotExchange* owner_ = nullptr;
        size_t slot_ = 0;
    };

    Reader reader() { return Reader(this); }

    // Writer only: snapshots retired but still held by a reader.
    size_t retiredCount() const { return retired_.size(); }

private:
    void reclaim() {
        std::vector<std::unique_ptr<T>> keep;
        for (auto& r : retired_) {
            bool held = false;
            for (auto& h : hazards_) held = held || h.load() == r.get();
            if (held) keep.push_back(std::move(r));
        }
        retired_ = std::move(keep);  // the others are deleted here
    }

    std::atomic<T*> current_{nullptr};
    std::array<std::atomic<T*>, MaxReaders> hazards_;
    std::array<std::atomic<bool>, MaxReaders> used_;
    std::vector<std::unique_ptr<T>> retired_;  // writer only
};

}  // namespace ml
