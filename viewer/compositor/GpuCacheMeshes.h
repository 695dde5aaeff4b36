// The cache meshes of one snapshot on the GPU, for the compositor, and the
// uploader that copies snapshots there in steps of bounded time.
//
// Each mesh keeps an interleaved float vertex buffer (position relative to
// the scene's centre, irradiance) and an index buffer of its triangles, so
// the compositor draws it with one indexed call. The viewer must not stall
// a frame on a large cache (a million triangles is some 30 MB to convert
// and copy), so CacheMeshUploader fills a back set a slice at a time while
// the front set is drawn, and swaps the two when the copy is complete: a
// frame always shows one whole snapshot, never half of two.
#pragma once

#include "cache/IrradianceCache.h"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace ml {

struct GlApi;

class GpuCacheMeshes {
public:
    // Triangles [first, first + count) of a mesh's index buffer and their
    // bounds (relative to the origin): a part the compositor can skip when
    // the camera does not see it.
    struct Cell {
        glm::vec3 lo{0.0f}, hi{0.0f};
        uint32_t first = 0, count = 0;
    };
    struct Mesh {
        // Its vertex buffer (6 floats per vertex: position − origin,
        // irradiance in W·m⁻²), index buffer (3 uint32 per triangle,
        // counter-clockwise = the sampled side) and the vertex array that
        // reads them, defined in GpuCacheMeshes.cpp so that this header
        // needs no GL.
        struct Gpu;
        std::unique_ptr<Gpu> gpu;
        // The GL name of that vertex array, for the compositor's draws.
        uint32_t vertexArray() const;
        size_t vertexCapacity = 0;  // vertices the buffer has room for
        size_t indexCapacity = 0;   // triangles the buffer has room for
        size_t vertexCount = 0;
        size_t triangleCount = 0;
        // Empty: draw the triangles in the snapshot's order, all at once.
        // Otherwise the triangles sorted into cells of space (Morton order,
        // so neighbouring cells are mostly neighbours in the buffer).
        std::vector<Cell> cells;
        // Boxes (relative to the origin) that together hold every triangle:
        // upload() bins the triangles on a grid of kFootprintCells a side
        // over the mesh's bounds, a box per bin over its triangles' corners
        // (first and count unused). What the compositor clips a part of an
        // image to (render's per-light layers: a light's own mesh covers
        // only the surfaces where it matters). Empty when not known
        // (CacheMeshUploader's copies): the whole image.
        std::vector<Cell> footprint;
    };

    // Meshes with at least this many triangles are sorted into cells by
    // CacheMeshUploader: on llvmpipe a frame's cost is then per triangle
    // (vertex work runs on one thread), and cells out of view cost nothing.
    // Smaller meshes keep the snapshot's order, as upload() does.
    static constexpr size_t kCellMinTriangles = 65536;
    // The footprint's grid: 64 boxes at most, whose corners a part projects
    // per sub-pixel pass (512 points per mesh, nothing against a composite).
    static constexpr int kFootprintCells = 4;

    // `origin` is subtracted from every position (the scene's centre): what
    // goes to the GPU as float stays precise far from the world's origin.
    GpuCacheMeshes(const GlApi& gl, const Vec3& origin);
    GpuCacheMeshes(GpuCacheMeshes&&);
    ~GpuCacheMeshes();

    // The direct meshes (one per light, in the scene's order), then the
    // indirect ones (one per bounce).
    size_t directCount() const { return direct_; }
    size_t indirectCount() const { return meshes_.size() - direct_; }
    const Mesh& direct(size_t light) const { return meshes_[light]; }
    const Mesh& indirect(size_t bounce) const { return meshes_[direct_ + bounce]; }
    size_t triangleCount() const;  // over every mesh

    // Copies `direct` then `indirect` whole (tests, `render`, one-off images).
    void upload(const std::vector<IrradianceMeshCopy>& direct, const std::vector<IrradianceMeshCopy>& indirect);

private:
    friend class CacheMeshUploader;
    // Sizes the set for these meshes: buffers grow (by a quarter more than
    // asked, so a growing cache does not reallocate every snapshot), never shrink.
    void reserve(const std::vector<const IrradianceMeshCopy*>& views, size_t directCount);

    const GlApi* gl_;
    Vec3 origin_;
    std::vector<Mesh> meshes_;
    size_t direct_ = 0;
};

class CacheMeshUploader {
public:
    CacheMeshUploader(const GlApi& gl, const Vec3& origin);

    // Starts copying these meshes into the back set. They must stay valid
    // and unchanged until step() returns true (the viewer keeps its
    // snapshot pinned); a copy in progress is abandoned.
    void start(const std::vector<IrradianceMeshCopy>& direct, const std::vector<IrradianceMeshCopy>& indirect);
    bool busy() const { return !pending_.empty(); }
    // Copies slices for about `seconds` (at least one slice, so a copy
    // always ends; empty meshes take none); returns true when this call
    // completed the copy and the back set became the front set.
    bool step(double seconds);
    // What the compositor draws: the last complete copy (empty at first).
    const GpuCacheMeshes& front() const { return sets_[front_]; }
    // Fraction of the copy in progress done so far, in [0, 1].
    double progress() const;

private:
    // What is being copied of the current mesh: its vertices, then (large
    // meshes) each triangle's cell and the cells' sizes, then the triangles
    // sorted by cell, then the triangles into the index buffer.
    enum class Phase { Vertices, Count, Scatter, Indices };
    void beginMesh();
    bool sorts() const;  // the current mesh is sorted into cells

    GpuCacheMeshes sets_[2];
    int front_ = 0;
    std::vector<const IrradianceMeshCopy*> pending_;  // meshes of the copy in progress
    size_t mesh_ = 0;         // mesh being copied
    size_t offset_ = 0;       // next vertex or triangle of the phase
    Phase phase_ = Phase::Vertices;
    size_t doneElements_ = 0, totalElements_ = 0;
    std::vector<float> staging_;
    // Sorting into cells: the mesh's bounds, each triangle's cell, the
    // cells' next free slots, and the sorted triangles.
    glm::vec3 lo_{0.0f}, hi_{0.0f};
    std::vector<uint16_t> cellOf_;
    std::vector<uint32_t> cellNext_;
    std::vector<glm::uvec3> sorted_;
};

}  // namespace ml
