// The classical hardware gathers that `bench indirect` compares with the
// voxel slices (§5.2, §6.2): the radiance proxy's triangles rasterised from
// the shading point with their per-corner radiance (Gouraud) and a depth
// test, read back and summed with each pixel's cosine-weighted solid angle.
//
//   Perspective  one wide perspective image facing along the normal (the
//                paper's 160°). Each pixel weighs its exact ∫cosθ dω. The
//                directions beyond the field of view, the grazing ones, are
//                missed: of a uniform sky, the square 160° image sees
//                (4/π)·sin 80°·atan(sin 80°) = 97.5% (a round 160° image
//                would see sin² 80° = 97.0%).
//   Hemicube     five views (a top face N×N, four side faces N×N/2) with
//                the exact delta form factors of their pixels: the whole
//                hemisphere.
//   Fisheye      the fish-eye image of SliceGather (equal projected solid
//                angle per pixel), the triangles projected in the vertex
//                stage (§5.2). A projected edge is straight where the true
//                one is an arc: fine for the proxy's pieces far from the
//                eye, badly wrong near it (in the Cornell box at 16 voxels,
//                points 4 mm from two walls lost 40-50% of their irradiance:
//                the walls' edges along the horizon became chords). So, as
//                the paper does, triangles near the eye are tessellated on
//                the CPU each gather until no edge spans more than
//                `tessellationDegrees`.
//
// The proxy is SliceGather's (RadianceProxy at `resolution` voxels), so the
// methods differ only in how they gather; the proxy is large (both sides of
// every open wall, pieces up to two voxels across: 13k triangles for the
// Cornell box at 32 voxels, 52k at 64), and on a CPU rasteriser a view's cost
// grows with the triangles sent, so each view sends only the clusters of
// triangles it may see (ProxyClusters). The eye is SliceGather's (NearField):
// lifted off the surface, and moved a hair off an edge or a corner, without
// which a point on an edge sees the wall through it edge-on and loses half
// its hemisphere. A gather's seed turns the image about the
// normal (and shifts the fish-eye's pixel grid by up to half a pixel): the
// mean of many gathers converges, where a fixed grid would repeat its error.
#pragma once

#include "GatherSettings.h"
#include "NearField.h"
#include "ProxyClusters.h"
#include "RadianceProxy.h"
#include "SliceGather.h"
#include "cache/IndirectEstimator.h"

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace ml {

class GlContext;

class TriangleGather : public IndirectEstimator {
public:
    // `context` current on this thread for the estimator's lifetime.
    TriangleGather(GlContext& context, const Scene& scene, const TriangleGatherSettings& settings);
    ~TriangleGather() override;

    std::string name() const override { return triangleProjectionName(settings_.projection); }
    // `importance` is not used: every source is gathered at the same image size.
    void setSource(size_t slot, const std::vector<IrradianceMeshCopy>& irradiance, double importance = 1.0) override;
    void releaseSource(size_t slot) override;
    Rgb estimate(size_t slot, const Vec3& x, const Vec3& n, uint32_t seed) override;
    IndirectStats stats() const override;

    const TriangleGatherSettings& settings() const { return settings_; }
    const RadianceProxy& proxy() const { return proxy_; }
    // Of a uniform sky's irradiance, the share the image sees: 1 for the
    // hemicube and the fish-eye, less for the wide perspective plane (above).
    double coverage() const { return coverage_; }
    // Per phase over every gather (nearField: culling and uploading the
    // triangles, CPU); with timePhases the GPU is waited for between phases.
    void setTimePhases(bool on) { timePhases_ = on; }
    const GatherPhaseTimes& phases() const { return phases_; }
    // Triangles sent by the last gather, summed over its views.
    size_t lastTriangles() const { return lastTriangles_; }

private:
    // One image of a gather, in the camera frame (right, up, forward) built
    // from the tangent frame, and where it lies in the atlas.
    struct View {
        int forward = 2;  // 0: r, 1: u, 2: n; negated when `negate`
        bool negate = false;
        double left = -1, right = 1, bottom = -1, top = 1;  // image-plane bounds at distance 1
        int x = 0, y = 0, width = 0, height = 0;            // viewport in the atlas
    };

    size_t memoryBytes() const;
    // Fish-eye: nearTriangles_ into pieces_ (see tessellationDegrees).
    void tessellate(const std::vector<Rgb>& radiance, const Vec3& x, const Vec3& n, double lift, const Vec3& eye);

    GlContext& context_;
    TriangleGatherSettings settings_;
    RadianceProxy proxy_;
    ProxyClusters clusters_;
    NearField eyeRule_;  // only its eye: lifted, and nudged off edges
    std::map<size_t, std::vector<Rgb>> radiance_;  // per slot: one per proxy position
    // Its program, target, index and piece buffers and each slot's radiance
    // buffer, defined in the .cpp so that this header needs no GL.
    struct Gpu;
    std::unique_ptr<Gpu> gpu_;
    std::vector<View> views_;
    int atlasWidth_ = 0, atlasHeight_ = 0;
    std::vector<double> weights_;  // per atlas pixel: ∫cosθ dω (0 where no view draws)
    double coverage_ = 1;
    std::vector<uint32_t> indices_;
    // Fish-eye tessellation: the triangles near the eye and their pieces (one
    // vertex each: position, normal and closed, radiance; Gpu::pieceBuffer).
    double maxProxyEdge_ = 0;
    std::vector<uint32_t> nearTriangles_;
    std::vector<float> pieces_;
    std::vector<float> pixels_;
    GatherPhaseTimes phases_;
    bool timePhases_ = false;
    size_t lastTriangles_ = 0;
    IndirectStats stats_;
};

// ∫∫ cosθ dω over the image-plane rectangle [x0, x1] × [y0, y1] at distance 1
// in front of the eye (facing it): the irradiance weight of a perspective
// pixel, exact (the corner form factor, Howell's catalogue B-3, times π).
double planeRectangleWeight(double x0, double x1, double y0, double y1);
// The same for a rectangle of a plane perpendicular to the surface at
// distance 1 (a hemicube's side face), y across and z ≥ 0 up along the
// normal: ∫∫ z/(1 + y² + z²)² dy dz.
double sideRectangleWeight(double y0, double y1, double z0, double z1);

}  // namespace ml
