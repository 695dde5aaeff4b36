#include "GpuCacheMeshes.h"

#include "core/Error.h"
#include "gpu_sampling/gl/GlObjects.h"

#include <algorithm>
#include <chrono>
#include <limits>

namespace ml {

namespace {

constexpr size_t kFloatsPerVertex = 6;
// Vertices or triangles converted and copied between two looks at the clock:
// about 0.2 ms of work, small against a frame, large against the call.
constexpr size_t kSlice = 16384;

static_assert(sizeof(glm::uvec3) == 3 * sizeof(uint32_t), "triangles are copied to the GPU as they are");

std::vector<const IrradianceMeshCopy*> pointers(const std::vector<IrradianceMeshCopy>& direct,
                                                const std::vector<IrradianceMeshCopy>& indirect) {
    std::vector<const IrradianceMeshCopy*> all;
    for (const IrradianceMeshCopy& m : direct) all.push_back(&m);
    for (const IrradianceMeshCopy& m : indirect) all.push_back(&m);
    return all;
}

// Converts vertices [begin, end) of `view` to floats and copies them into the buffer.
void copyVertices(const GlApi& gl, const Vec3& origin, const IrradianceMeshCopy& view, GLuint buffer, size_t begin,
                  size_t end, std::vector<float>& staging) {
    staging.resize((end - begin) * kFloatsPerVertex);
    float* out = staging.data();
    for (size_t v = begin; v < end; ++v) {
        const Vec3 p = view.positions[v] - origin;
        const Rgb& e = view.irradiance[v];
        *out++ = float(p.x), *out++ = float(p.y), *out++ = float(p.z);
        *out++ = float(e.r), *out++ = float(e.g), *out++ = float(e.b);
    }
    gl.NamedBufferSubData(buffer, GLintptr(begin * kFloatsPerVertex * sizeof(float)),
                          GLsizeiptr(staging.size() * sizeof(float)), staging.data());
}

void copyTriangles(const GlApi& gl, const IrradianceMeshCopy& view, GLuint buffer, size_t begin, size_t end) {
    gl.NamedBufferSubData(buffer, GLintptr(begin * sizeof(glm::uvec3)), GLsizeiptr((end - begin) * sizeof(glm::uvec3)),
                          &view.triangles[begin]);
}

// Mesh::footprint of `view`'s triangles.
std::vector<GpuCacheMeshes::Cell> footprintOf(const IrradianceMeshCopy& view, const Vec3& origin) {
    if (view.triangles.empty()) return {};
    constexpr int n = GpuCacheMeshes::kFootprintCells;
    auto local = [&](uint32_t v) { return glm::vec3(view.positions[v] - origin); };
    glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
    for (const glm::uvec3& t : view.triangles)
        for (int k = 0; k < 3; ++k) {
            lo = glm::min(lo, local(t[k]));
            hi = glm::max(hi, local(t[k]));
        }
    const glm::vec3 extent = glm::max(hi - lo, glm::vec3(1e-30f));
    std::vector<GpuCacheMeshes::Cell> bins(size_t(n * n * n));
    std::vector<bool> used(bins.size(), false);
    for (const glm::uvec3& t : view.triangles) {
        const glm::vec3 a = local(t.x), b = local(t.y), c = local(t.z);
        const glm::ivec3 cell = glm::clamp(glm::ivec3(((a + b + c) / 3.0f - lo) / extent * float(n)), 0, n - 1);
        const size_t i = size_t((cell.z * n + cell.y) * n + cell.x);
        GpuCacheMeshes::Cell& box = bins[i];
        if (!used[i]) {
            box.lo = box.hi = a;
            used[i] = true;
        }
        box.lo = glm::min(glm::min(box.lo, a), glm::min(b, c));
        box.hi = glm::max(glm::max(box.hi, a), glm::max(b, c));
    }
    std::vector<GpuCacheMeshes::Cell> footprint;
    for (size_t i = 0; i < bins.size(); ++i)
        if (used[i]) footprint.push_back(bins[i]);
    return footprint;
}

}  // namespace

struct GpuCacheMeshes::Mesh::Gpu {
    GlBuffer vertices, indices;
    GlVertexArray vao;
};

uint32_t GpuCacheMeshes::Mesh::vertexArray() const { return gpu ? gpu->vao.id() : 0; }

GpuCacheMeshes::GpuCacheMeshes(const GlApi& gl, const Vec3& origin) : gl_(&gl), origin_(origin) {}
GpuCacheMeshes::GpuCacheMeshes(GpuCacheMeshes&&) = default;
GpuCacheMeshes::~GpuCacheMeshes() = default;

size_t GpuCacheMeshes::triangleCount() const {
    size_t n = 0;
    for (const Mesh& m : meshes_) n += m.triangleCount;
    return n;
}

void GpuCacheMeshes::reserve(const std::vector<const IrradianceMeshCopy*>& views, size_t directCount) {
    const GlApi& gl = *gl_;
    meshes_.resize(views.size());
    direct_ = directCount;
    for (size_t i = 0; i < views.size(); ++i) {
        const IrradianceMeshCopy& v = *views[i];
        ML_ASSERT(v.irradiance.size() == v.positions.size(), v.irradiance.size(), " irradiance values for ",
                  v.positions.size(), " vertices");
        Mesh& m = meshes_[i];
        if (!m.gpu) {
            m.gpu = std::make_unique<Mesh::Gpu>();
            Mesh::Gpu& g = *m.gpu;
            g.vertices = makeBuffer(gl, 0, nullptr, GL_DYNAMIC_DRAW);
            g.indices = makeBuffer(gl, 0, nullptr, GL_DYNAMIC_DRAW);
            g.vao = makeVertexArray(gl);
            for (GLuint a = 0; a < 2; ++a) {
                gl.EnableVertexArrayAttrib(g.vao.id(), a);
                gl.VertexArrayAttribFormat(g.vao.id(), a, 3, GL_FLOAT, GL_FALSE, GLuint(3 * a * sizeof(float)));
                gl.VertexArrayAttribBinding(g.vao.id(), a, 0);
            }
            gl.VertexArrayVertexBuffer(g.vao.id(), 0, g.vertices.id(), 0, GLsizei(kFloatsPerVertex * sizeof(float)));
            gl.VertexArrayElementBuffer(g.vao.id(), g.indices.id());
        }
        // Re-specifying a buffer keeps its name, so the vertex array stays valid.
        if (v.positions.size() > m.vertexCapacity) {
            m.vertexCapacity = v.positions.size() + v.positions.size() / 4;
            gl.NamedBufferData(m.gpu->vertices.id(), GLsizeiptr(m.vertexCapacity * kFloatsPerVertex * sizeof(float)),
                               nullptr, GL_DYNAMIC_DRAW);
        }
        if (v.triangles.size() > m.indexCapacity) {
            m.indexCapacity = v.triangles.size() + v.triangles.size() / 4;
            gl.NamedBufferData(m.gpu->indices.id(), GLsizeiptr(m.indexCapacity * sizeof(glm::uvec3)), nullptr,
                               GL_DYNAMIC_DRAW);
        }
        m.vertexCount = v.positions.size();
        m.triangleCount = v.triangles.size();
        m.footprint.clear();  // not known until upload() sets it
    }
}

void GpuCacheMeshes::upload(const std::vector<IrradianceMeshCopy>& direct,
                            const std::vector<IrradianceMeshCopy>& indirect) {
    const std::vector<const IrradianceMeshCopy*> views = pointers(direct, indirect);
    reserve(views, direct.size());
    std::vector<float> staging;
    for (size_t i = 0; i < views.size(); ++i) {
        if (!views[i]->positions.empty())
            copyVertices(*gl_, origin_, *views[i], meshes_[i].gpu->vertices.id(), 0, views[i]->positions.size(), staging);
        if (!views[i]->triangles.empty())
            copyTriangles(*gl_, *views[i], meshes_[i].gpu->indices.id(), 0, views[i]->triangles.size());
        meshes_[i].cells.clear();
        meshes_[i].footprint = footprintOf(*views[i], origin_);
    }
}

CacheMeshUploader::CacheMeshUploader(const GlApi& gl, const Vec3& origin)
    : sets_{GpuCacheMeshes(gl, origin), GpuCacheMeshes(gl, origin)} {}

namespace {

constexpr int kCellBits = 4;  // 16 cells a side, 4,096 in all
constexpr int kCellsPerSide = 1 << kCellBits;

// The Morton code of a cell: its coordinates' bits interleaved.
uint16_t mortonCell(int x, int y, int z) {
    uint16_t code = 0;
    for (int b = 0; b < kCellBits; ++b)
        code |= uint16_t((((x >> b) & 1) << (3 * b)) | (((y >> b) & 1) << (3 * b + 1)) | (((z >> b) & 1) << (3 * b + 2)));
    return code;
}

}  // namespace

bool CacheMeshUploader::sorts() const {
    return pending_[mesh_]->triangles.size() >= GpuCacheMeshes::kCellMinTriangles;
}

void CacheMeshUploader::beginMesh() {
    offset_ = 0;
    phase_ = Phase::Vertices;
    lo_ = glm::vec3(std::numeric_limits<float>::max());
    hi_ = glm::vec3(-std::numeric_limits<float>::max());
}

void CacheMeshUploader::start(const std::vector<IrradianceMeshCopy>& direct,
                              const std::vector<IrradianceMeshCopy>& indirect) {
    pending_ = pointers(direct, indirect);
    GpuCacheMeshes& back = sets_[1 - front_];
    back.reserve(pending_, direct.size());
    mesh_ = 0;
    beginMesh();
    doneElements_ = 0;
    totalElements_ = 0;
    for (const IrradianceMeshCopy* v : pending_)
        totalElements_ += v->positions.size() +
                          v->triangles.size() * (v->triangles.size() >= GpuCacheMeshes::kCellMinTriangles ? 3 : 1);
    if (pending_.empty()) pending_.push_back(nullptr);  // a snapshot without meshes still swaps in
}

double CacheMeshUploader::progress() const {
    if (!busy()) return 1;
    return totalElements_ ? double(doneElements_) / double(totalElements_) : 0;
}

bool CacheMeshUploader::step(double seconds) {
    if (!busy()) return false;
    using Clock = std::chrono::steady_clock;
    const auto deadline = Clock::now() + std::chrono::duration<double>(std::max(seconds, 0.0));
    GpuCacheMeshes& back = sets_[1 - front_];
    const GlApi& gl = *back.gl_;
    const Vec3 origin = back.origin_;
    for (;;) {
        if (mesh_ >= pending_.size() || !pending_[mesh_]) {
            pending_.clear();
            front_ = 1 - front_;
            return true;
        }
        const IrradianceMeshCopy& view = *pending_[mesh_];
        GpuCacheMeshes::Mesh& target = back.meshes_[mesh_];
        const bool sorted = sorts();
        const size_t count = phase_ == Phase::Vertices ? view.positions.size() : view.triangles.size();
        const size_t end = std::min(count, offset_ + kSlice);
        const glm::vec3 extent = glm::max(hi_ - lo_, glm::vec3(1e-30f));
        auto local = [&](uint32_t v) { return glm::vec3(view.positions[v] - origin); };
        switch (phase_) {
            case Phase::Vertices:
                if (end > offset_) copyVertices(gl, origin, view, target.gpu->vertices.id(), offset_, end, staging_);
                if (sorted)
                    for (size_t v = offset_; v < end; ++v) {
                        const glm::vec3 p(view.positions[v] - origin);
                        lo_ = glm::min(lo_, p);
                        hi_ = glm::max(hi_, p);
                    }
                break;
            case Phase::Count:
                if (offset_ == 0) {
                    cellOf_.resize(view.triangles.size());
                    cellNext_.assign(size_t(1) << (3 * kCellBits), 0);
                }
                for (size_t t = offset_; t < end; ++t) {
                    const glm::uvec3 tri = view.triangles[t];
                    const glm::vec3 c = (local(tri.x) + local(tri.y) + local(tri.z)) / 3.0f;
                    const glm::ivec3 cell =
                        glm::clamp(glm::ivec3((c - lo_) / extent * float(kCellsPerSide)), 0, kCellsPerSide - 1);
                    cellOf_[t] = mortonCell(cell.x, cell.y, cell.z);
                    ++cellNext_[cellOf_[t]];
                }
                break;
            case Phase::Scatter:
                if (offset_ == 0) {
                    // Counts to first slots, and the cells in buffer order.
                    sorted_.resize(view.triangles.size());
                    target.cells.clear();
                    uint32_t first = 0;
                    for (uint32_t& next : cellNext_) {
                        const uint32_t n = next;
                        next = first;
                        GpuCacheMeshes::Cell cell;
                        cell.first = first;
                        cell.count = n;
                        cell.lo = glm::vec3(std::numeric_limits<float>::max());
                        cell.hi = glm::vec3(-std::numeric_limits<float>::max());
                        target.cells.push_back(cell);
                        first += n;
                    }
                }
                for (size_t t = offset_; t < end; ++t) {
                    const glm::uvec3 tri = view.triangles[t];
                    GpuCacheMeshes::Cell& cell = target.cells[cellOf_[t]];
                    sorted_[cellNext_[cellOf_[t]]++] = tri;
                    for (int k = 0; k < 3; ++k) {
                        const glm::vec3 p = local(tri[k]);
                        cell.lo = glm::min(cell.lo, p);
                        cell.hi = glm::max(cell.hi, p);
                    }
                }
                break;
            case Phase::Indices:
                if (end > offset_) {
                    gl.NamedBufferSubData(target.gpu->indices.id(), GLintptr(offset_ * sizeof(glm::uvec3)),
                                          GLsizeiptr((end - offset_) * sizeof(glm::uvec3)),
                                          sorted ? &sorted_[offset_] : &view.triangles[offset_]);
                }
                break;
        }
        const bool copies = end > offset_;
        doneElements_ += end - offset_;
        offset_ = end;
        if (offset_ >= count) {
            offset_ = 0;
            switch (phase_) {
                case Phase::Vertices: phase_ = sorted ? Phase::Count : Phase::Indices; break;
                case Phase::Count: phase_ = Phase::Scatter; break;
                case Phase::Scatter: phase_ = Phase::Indices; break;
                case Phase::Indices:
                    if (sorted) {
                        // Only the cells that hold triangles.
                        std::vector<GpuCacheMeshes::Cell> cells;
                        for (const GpuCacheMeshes::Cell& c : target.cells)
                            if (c.count) cells.push_back(c);
                        target.cells = std::move(cells);
                    } else {
                        target.cells.clear();
                    }
                    ++mesh_;
                    if (mesh_ < pending_.size() && pending_[mesh_]) beginMesh();
                    break;
            }
        }
        // Empty parts cost nothing: only work counts against the time.
        if (copies && Clock::now() >= deadline) return false;
    }
}

}  // namespace ml
