// One OSMesa context per test binary: created on first use, destroyed by a
// gtest environment before exit (after every sampler made in it).
#pragma once

#include "gpu_sampling/gl/GlContext.h"

#include <gtest/gtest.h>

#include <functional>
#include <memory>
#include <vector>

namespace ml::test {

class GlTestEnvironment : public ::testing::Environment {
public:
    // The context, made current on the calling thread.
    static GlContext& context() {
        if (!context_) context_ = createHeadlessContext(GlBackend::OsMesa);
        context_->makeCurrent();
        return *context_;
    }
    // Runs before the context goes: frees what lives in it.
    static void beforeTearDown(std::function<void()> f) { cleanups_.push_back(std::move(f)); }
    void TearDown() override {
        for (auto& f : cleanups_) f();
        cleanups_.clear();
        context_.reset();
    }

private:
    static inline std::unique_ptr<GlContext> context_;
    static inline std::vector<std::function<void()>> cleanups_;
};

inline const auto* const kGlEnvironment = ::testing::AddGlobalTestEnvironment(new GlTestEnvironment);

inline GlContext& glContext() { return GlTestEnvironment::context(); }

}  // namespace ml::test
