// Two rooms side by side, one lit and one that no light path reaches (the
// scene of test_indirect's leak test), and how much light reaches the dark
// one: the indirect meshes of every bounce read on its floor and far wall,
// relative to the lit room's floor. Every indirect method's leak test
// measures it the same way.
#pragma once

#include "TestScenes.h"
#include "cache/IndirectSolver.h"
#include "cache/IrradianceCache.h"
#include "core/raytrace/BounceCount.h"
#include "gpu_sampling/indirect/RadianceProxy.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

namespace ml::test {

// Two rooms, [−2, 0] and [0, 2] × [0, 2] × [0, 2] (metres), each with its
// own floor, ceiling and walls facing in, open where they meet; a thin
// single-sided partition at x = 0 facing the lit room, a lamp under the
// lit room's ceiling. No light path reaches the dark room.
inline Scene twoRooms() {
    Material white;
    white.name = "white";
    white.kd = Rgb(0.7);
    Material lamp = white;
    lamp.name = "lamp";
    lamp.ke = Rgb(10.0);
    Mesh shell;
    shell.name = "shell";
    for (const double x0 : {-2.0, 0.0}) {
        const Vec3 lo(x0, 0, 0);
        addQuad(shell, 0, lo, 2.0 * kZ, 2.0 * kX);                  // floor, facing up
        addQuad(shell, 0, lo + 2.0 * kY, 2.0 * kX, 2.0 * kZ);       // ceiling, facing down
        addQuad(shell, 0, lo, 2.0 * kX, 2.0 * kY);                  // z = 0, facing +z
        addQuad(shell, 0, lo + 2.0 * kZ, 2.0 * kY, 2.0 * kX);       // z = 2, facing −z
        if (x0 < 0) addQuad(shell, 0, lo, 2.0 * kY, 2.0 * kZ);      // x = −2, facing +x
        else addQuad(shell, 0, lo + 2.0 * kX, 2.0 * kZ, 2.0 * kY);  // x = 2, facing −x
    }
    Mesh partition = quadMesh("partition", 0, Vec3(0.0), 2.0 * kZ, 2.0 * kY);    // facing −x
    Mesh light = quadMesh("lamp", 1, Vec3(-1.3, 1.99, 0.7), 0.6 * kX, 0.6 * kZ);  // facing down
    return sceneOf("two rooms", {white, lamp}, {shell, partition, light});
}

// Relative to the lit room's floor (mean indirect irradiance at 36 points).
struct RoomLeak {
    double lit = 0;      // the lit floor's mean indirect irradiance (luminance, W·m⁻²)
    double nearMax = 0;  // worst on the dark floor within 0.4 m of the partition
    double farMax = 0;   // worst beyond, on the floor and the far wall
    double mean = 0;     // mean over the dark room's points
};

// The rooms are [−2, 0] (lit) and [0, 2] (dark) × [0, 2] × [0, 2], the
// partition at x = 0; `bounces` are the solver's indirect meshes.
inline RoomLeak roomLeak(const std::vector<IrradianceMeshCopy>& bounces) {
    std::vector<MeshIrradianceLookup> lookups;
    for (const IrradianceMeshCopy& b : bounces) lookups.emplace_back(b, 0.1, 1e-4);
    auto indirect = [&](const Vec3& x, const Vec3& n) {
        double e = 0;
        for (const MeshIrradianceLookup& l : lookups) e += luminance(l.at(x, n));
        return e;
    };
    RoomLeak leak;
    int litCount = 0;
    for (double x = -1.9; x < -0.1; x += 0.3)
        for (double z = 0.2; z < 2; z += 0.3) leak.lit += indirect(Vec3(x, 0, z), Vec3(0, 1, 0)), ++litCount;
    leak.lit /= litCount;
    if (!(leak.lit > 0)) return leak;
    int count = 0;
    for (double x = 0.05; x < 2; x += 0.15)
        for (double z = 0.2; z < 2; z += 0.4) {
            const double e = indirect(Vec3(x, 0, z), Vec3(0, 1, 0)) / leak.lit;
            double& worst = x < 0.4 ? leak.nearMax : leak.farMax;
            worst = std::max(worst, e);
            leak.mean += e, ++count;
        }
    for (double y = 0.2; y < 2; y += 0.4) {
        const double e = indirect(Vec3(2, y, 1), Vec3(-1, 0, 0)) / leak.lit;
        leak.farMax = std::max(leak.farMax, e);
        leak.mean += e, ++count;
    }
    leak.mean /= count;
    return leak;
}

// Every bounce of the scene's bounce count gathered by `estimator` through
// the cache's solver, to convergence, from `direct`; the leak of its meshes.
inline RoomLeak solvedRoomLeak(const Scene& scene, IndirectEstimator& estimator,
                               const std::vector<IrradianceMeshCopy>& direct) {
    const BounceCount plan = countBounces(scene);
    IndirectSettings is;
    is.bounces = plan.bounces;
    is.albedo = plan.meanAlbedo;
    IndirectSolver solver(scene, is);
    for (int r = 0; r < 4000 && !solver.allFinished(); ++r)
        solver.step(estimator, [&] { return direct; }, 512, 7, std::nullopt);
    EXPECT_TRUE(solver.allFinished());
    return roomLeak(solver.copyMeshes());
}

}  // namespace ml::test
