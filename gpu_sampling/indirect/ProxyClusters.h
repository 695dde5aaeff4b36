// The radiance proxy as a GPU triangle mesh, for the gathers that rasterise
// it (TriangleGather), with its triangles grouped into clusters that the CPU
// culls before each view is drawn.
//
// Why clusters: on a CPU rasteriser (llvmpipe) a view costs about as much per
// triangle sent as per pixel filled, and the proxy is large (the Cornell box
// at 64 voxels: 52k triangles, both sides of every open wall). A cluster is
// the triangles of one side of one scene triangle within one block of
// blockVoxels³ voxels: they share a plane orientation, so a cluster whose
// every triangle faces away from the eye (an open surface's other copy), lies
// below the gathering point's horizon or outside a view's frustum is dropped
// whole, from its bounding box, in a few comparisons.
#pragma once

#include "RadianceProxy.h"

#include <memory>
#include <vector>

namespace ml {

class GlContext;

// A plane through the eye: what a view can see lies on the side its normal points to.
struct ViewPlane {
    Vec3 normal{0.0};
};

class ProxyClusters {
public:
    // `blockVoxels`: cluster edge in voxels, typical 4. `context` current on this thread.
    ProxyClusters(GlContext& context, const RadianceProxy& proxy, int blockVoxels = 4);
    ~ProxyClusters();

    // The proxy's vertices and the vertex array that draws them, and the
    // radiance uploads, defined in detail/ProxyClustersGpu.h for the gathers
    // that draw them, so that this header needs no GL.
    struct Gpu;
    const Gpu& gpu() const { return *gpu_; }

    // Appends to `indices` the triangles (3 indices each) of every cluster
    // that may show something to an eye at `eye` (world units) gathering
    // over the hemisphere of unit normal n above the plane through x lifted
    // by `lift`, and lying on the inner side of every plane of `frustum`
    // (planes through the eye). Returns the number of triangles appended.
    // With `near`, clusters whose box comes within `nearDistance` of the eye
    // go there instead, as proxy triangle indices (RadianceProxy::triangles()).
    size_t cull(const Vec3& x, const Vec3& n, double lift, const Vec3& eye, const std::vector<ViewPlane>& frustum,
                std::vector<uint32_t>& indices, double nearDistance = 0, std::vector<uint32_t>* near = nullptr) const;

    size_t clusterCount() const { return clusters_.size(); }
    size_t triangleCount() const { return indices_.size() / 3; }
    size_t memoryBytes() const;

private:
    struct Cluster {
        Vec3 lo{kInf}, hi{-kInf};  // bounds of its triangles
        Vec3 normal{0.0};          // of the side that reflects (shared by its triangles)
        double planeMin = kInf;    // min over its triangles of dot(normal, corner)
        bool closed = false;
        uint32_t first = 0, count = 0;  // range in indices_
    };
    std::vector<Cluster> clusters_;
    std::vector<uint32_t> indices_;     // every triangle, cluster by cluster
    std::vector<uint32_t> triangleOf_;  // the proxy triangle of each, in the same order
    size_t vertexBytes_ = 0;
    std::unique_ptr<Gpu> gpu_;
};

}  // namespace ml
