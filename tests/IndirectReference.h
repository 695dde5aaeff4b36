// What the indirect gathers are compared with (test_indirect.cpp,
// test_indirect_methods.cpp): the reference path tracer's first bounce, and
// the hard points at which it is taken beside the point itself.
#pragma once

#include "TestSamplers.h"
#include "cache/IrradianceCache.h"
#include "core/Scene.h"
#include "core/raytrace/EmbreeScene.h"
#include "core/raytrace/PathTracer.h"
#include "core/reference/ExactIrradiance.h"

#include <cstdint>

namespace ml::test {

// A source for a gather: `mesh` (its own vertices and normals) holding
// irradiance `e` everywhere, one sample per vertex.
inline IrradianceMeshCopy uniformIrradiance(const Mesh& mesh, const Rgb& e) {
    IrradianceMeshCopy m;
    m.positions = mesh.positions;
    m.normals = mesh.normals;
    m.triangles = mesh.triangles;
    m.irradiance.assign(mesh.positions.size(), e);
    m.samples.assign(mesh.positions.size(), 1);
    return m;
}

// Indirect irradiance (W·m⁻², RGB) and its standard error.
struct OneBounce {
    Rgb value{0.0}, error{0.0};
};

// The path tracer with direct light and one bounce (maxDepth 2), so that its
// `indirect` is exactly what a gather of direct light estimates. Results
// repeat bit for bit for the same arguments, whatever the thread count.
class OneBounceReference {
public:
    // `scene` must outlive the reference.
    explicit OneBounceReference(const Scene& scene) : rays_(scene), tracer_(rays_, settings()) {}

    // At x on a surface of unit normal n (rays leave x lifted along n), from
    // `samples` paths (in the Cornell box, 2^18 keep the standard error
    // below 1% even in corners); `pointId` decorrelates points.
    OneBounce at(const Vec3& x, const Vec3& n, int samples, uint32_t pointId) const {
        const IrradianceEstimate e = tracer_.irradiance(x, n, samples, pointId);
        return {e.indirect, e.indirectError};
    }

private:
    static PathTracerSettings settings() {
        PathTracerSettings s;
        s.maxDepth = 2;
        return s;
    }
    EmbreeScene rays_;
    PathTracer tracer_;
};

// The direct cache's base mesh, every vertex sampled exactly (ExactDirect):
// the source the gathers are compared on (bench indirect's, before it
// refines). In the Cornell box its 30 mm triangles are within about 1% of
// the true direct light away from contacts and corners.
inline std::vector<IrradianceMeshCopy> exactDirectSource(const Scene& scene) {
    IrradianceCache cache(scene);
    const ExactDirect exact(scene);
    sampleEveryVertex(
        cache, [&](size_t light, const Vec3& x, const Vec3& n, uint32_t) { return exact.irradiance(light, x, n); }, 1,
        1);
    return cache.copyMeshes();
}

// Irradiance E0 everywhere on the inner sides of a one-mesh closed box
// (test::furnaceBox): a source of Lo = Kd/π · E0 on every wall, one
// triangle of the mesh copy per scene triangle.
inline std::vector<IrradianceMeshCopy> uniformSource(const Scene& scene, double e0) {
    IrradianceMeshCopy v;
    const Mesh& m = scene.meshes.front();
    for (size_t t = 0; t < m.triangles.size(); ++t) {
        const uint32_t base = uint32_t(v.positions.size());
        for (int k = 0; k < 3; ++k) {
            v.positions.push_back(m.positions[m.triangles[t][k]]);
            v.normals.push_back(glm::normalize(m.areaNormal(t)));
            v.irradiance.push_back(Rgb(e0));
            v.samples.push_back(1);
        }
        v.triangles.push_back({base, base + 1, base + 2});
    }
    return {v};
}

// A point where a gather's eye meets geometry (in a corner, on an edge, a
// hair off a surface), and the regular point beside it where the path
// tracer gives the reference: 5 mm along the same surface away from the
// edges, or x itself where nothing is in the way (in a corner, the path
// tracer's rays leave x lifted along n only, so many would start outside
// the room).
struct HardPoint {
    const char* what;
    Vec3 x, n;
    Vec3 regular;
    // The least share of the regular point's light the gather must find at
    // x; 0 where x sees (almost) nothing.
    double minShare;
};

}  // namespace ml::test
