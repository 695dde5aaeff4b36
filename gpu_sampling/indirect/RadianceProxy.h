// The surfaces indirect gathers see, with the radiance they reflect.
//
// The scene's triangles, cut until no edge is longer than two voxels, one
// copy per side for open objects (each side reflects its own irradiance),
// carry at every corner the exitant radiance Lo = Kd/π · ΣE, where E is
// interpolated from the cache meshes given (every light's direct mesh, or a
// bounce's indirect mesh). Every gather method (voxel slices, triangles,
// ray march) draws from this one proxy, so they differ only in how they
// gather. Triangles are also binned by voxel, for the near field.
#pragma once

#include "VoxelGrid.h"
#include "cache/IrradianceCache.h"
#include "core/Scene.h"

#include <array>

#include <vector>

namespace ml {

struct ProxyTriangle {
    glm::uvec3 corners{0};     // indices into RadianceProxy::positions()
    Vec3 normal{0.0};          // unit, the side that reflects
    Rgb kd{0.0};
    // The back of this triangle is the inside of a closed object: seen
    // from behind it is black and opaque. Open objects' triangles come in
    // pairs instead, one per side, each seen from its front only.
    bool closed = false;
};

class RadianceProxy {
public:
    RadianceProxy(const Scene& scene, const VoxelGrid& grid);

    const VoxelGrid& grid() const { return grid_; }
    const std::vector<ProxyTriangle>& triangles() const { return triangles_; }
    const std::vector<Vec3>& positions() const { return positions_; }
    // Exitant radiance at each position, W·sr⁻¹·m⁻², when the surfaces
    // receive the sum of these meshes' irradiance.
    std::vector<Rgb> radianceFrom(const std::vector<IrradianceMeshCopy>& meshes) const;
    // Triangles overlapping voxel (i, j, k).
    const std::vector<uint32_t>& inVoxel(int i, int j, int k) const {
        return bins_[(size_t(k) * grid_.dims[1] + j) * grid_.dims[0] + i];
    }
    size_t memoryBytes() const;

private:
    VoxelGrid grid_;
    double diagonal_ = 1;
    std::vector<ProxyTriangle> triangles_;
    std::vector<Vec3> positions_;
    std::vector<uint32_t> vertexTriangle_;  // a triangle each position belongs to (for its normal and Kd)
    std::vector<std::vector<uint32_t>> bins_;
};

// The point of triangle (a, b, c) closest to p, as barycentrics.
Vec3 closestBarycentric(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

// Each vertex's curvature κ of the irradiance a mesh holds, per channel,
// W·m⁻² per m²: its value less the value at it of the plane fitted (least
// squares, in its tangent plane) to its neighbours' values, over their mean
// squared distance. Neighbours across a crease (normals more than 30° apart)
// are left out; zero where fewer than three are left or they lie on a line.
// For f = ½c·|x|² about the vertex on a symmetric ring, κ = −c/2, and
// ¼|e|²·κ = −c|e|²/8 is exactly what linear interpolation misses at the
// midpoint of an edge e (f(mid) − (f(a) + f(b))/2).
std::vector<Rgb> vertexCurvature(const IrradianceMeshCopy& mesh);

// Point location in a cache mesh: the irradiance a mesh holds at a point of
// the scene's surfaces, from the mesh triangle nearest to it among those
// facing the same side (normals within 60°), linearly interpolated; zero
// where no such triangle lies within `tolerance` (the mesh does not cover
// that side, e.g. the back of a wall no light reaches).
//
// With `Interpolation::CurvatureCorrected`, the linear interpolation is
// corrected by the curvature the vertices' values show (vertexCurvature):
// linear interpolation of a curved signal misses it inside every face by
// Σ 4·bi·bj·δij, δij the miss at edge ij's midpoint, about ¼|eij|²·κ for a
// curvature κ (the residual against the plane fitted to the neighbours'
// values, over their mean squared distance). Irradiance over a room is
// mostly concave (highest mid-wall, falling to the corners), so the linear
// reading runs dark, and a gather reading it passes the deficit on, bounce
// after bounce (the office's second bounce read 1.6% dark from bounce-1
// meshes of 16 cm edges). The correction is bounded to a tenth of the
// face's mean value (a step, where the fit is no curvature, is left to the
// mesh's refinement) and the result to non-negative values.
class MeshIrradianceLookup {
public:
    enum class Interpolation { Linear, CurvatureCorrected };
    MeshIrradianceLookup(const IrradianceMeshCopy& mesh, double cellSize, double tolerance,
                         Interpolation interpolation = Interpolation::Linear);
    // Several meshes in one grid: at() is the sum of each one's value, each
    // from its own nearest face, in the meshes' order (what summing one
    // lookup per mesh gives). A bounce-1 gather reads every light's direct
    // mesh at each ray's end, 193 of them under 192 panels, each covering
    // the few surfaces where its light matters. Looked up one by one, most
    // found nothing there, and at() took 28% of a 20-s render's CPU time
    // (perf); in one grid, whose bins list only the meshes with a face
    // there, 15% (gpu_sampling/README.md).
    MeshIrradianceLookup(const std::vector<const IrradianceMeshCopy*>& meshes, double cellSize, double tolerance,
                         Interpolation interpolation = Interpolation::Linear);
    Rgb at(const Vec3& p, const Vec3& n) const;
    // The records and bins (not the meshes, which the caller keeps).
    size_t memoryBytes() const;

private:
    // What a lookup reads of a face: a gather looks up the meshes at each
    // ray's end and is bound by memory, so each face is one record: its
    // first corner a, unit normal and dual edge vectors u and t. The
    // barycentrics (v, w) of a point's projection are (u·(p − a), t·(p − a)):
    // a point on the face (a ray's end, nearly always) is placed by three
    // dot products, and the faces beside it are passed over by the bound
    // those give on their distance, without a closest-point search. The
    // records lie mesh by mesh, and within a mesh by the bin their bounding
    // box starts in, so a mesh's faces in a bin are mostly neighbours in
    // memory.
    struct Face {
        Vec3 a;
        float n[3], u[3], t[3];
        uint32_t corners[3];
        uint32_t mesh;
    };
    // The value at barycentrics b of face corners i of mesh m, linear or
    // corrected.
    Rgb interpolate(uint32_t m, const glm::uvec3& i, const Vec3& b) const;

    std::vector<const IrradianceMeshCopy*> meshes_;
    std::vector<Face> faces_;
    std::vector<std::vector<Rgb>> curvature_;  // per mesh, per vertex (vertexCurvature); empty: linear
    Vec3 origin_{0.0};
    double cell_ = 1, tolerance_ = 0;
    std::array<int, 3> dims_{1, 1, 1};
    // The faces of bin b: binFaces_[binStart_[b], binStart_[b + 1]), in
    // the records' order (so mesh by mesh).
    std::vector<uint32_t> binStart_, binFaces_;
};

}  // namespace ml
