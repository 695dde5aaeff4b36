#include "RadianceProxy.h"

#include "core/Error.h"
#include "core/MeshUtil.h"
#include "core/TangentPlaneFit.h"

#include <algorithm>
#include <cmath>

namespace ml {

// Ericson, Real-Time Collision Detection §5.1.5.
Vec3 closestBarycentric(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) return {1, 0, 0};
    const Vec3 bp = p - b;
    const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) return {0, 1, 0};
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) {
        const double v = d1 / (d1 - d3);
        return {1 - v, v, 0};
    }
    const Vec3 cp = p - c;
    const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) return {0, 0, 1};
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) {
        const double w = d2 / (d2 - d6);
        return {1 - w, 0, w};
    }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return {0, 1 - w, w};
    }
    const double denom = va + vb + vc;
    if (!(std::abs(denom) > 0)) return {1, 0, 0};
    const double v = vb / denom, w = vc / denom;
    return {1 - v - w, v, w};
}

std::vector<Rgb> vertexCurvature(const IrradianceMeshCopy& mesh) {
    const size_t nv = mesh.positions.size();
    std::vector<Rgb> out(nv, Rgb(0.0));
    if (mesh.irradiance.size() != nv || mesh.normals.size() != nv) return out;
    // Each vertex's neighbours, in index order (the sums do not depend on
    // the order faces are listed in).
    std::vector<std::vector<uint32_t>> ring(nv);
    for (const glm::uvec3& t : mesh.triangles)
        for (int k = 0; k < 3; ++k) {
            ring[t[k]].push_back(t[(k + 1) % 3]);
            ring[t[k]].push_back(t[(k + 2) % 3]);
        }
    constexpr double kCrease = 0.866;  // cos 30°
    std::vector<uint32_t> kept;
    std::vector<Vec3> points;
    TangentPlaneFit fit;
    for (size_t v = 0; v < nv; ++v) {
        std::vector<uint32_t>& r = ring[v];
        std::sort(r.begin(), r.end());
        r.erase(std::unique(r.begin(), r.end()), r.end());
        const Vec3 p = mesh.positions[v], n = mesh.normals[v];
        if (!(glm::length(n) > 0.5)) continue;
        kept.clear();
        points.clear();
        double meanSq = 0;
        for (uint32_t u : r) {
            if (glm::dot(mesh.normals[u], n) < kCrease * glm::length(mesh.normals[u]) * glm::length(n)) continue;
            const double d2 = glm::dot(mesh.positions[u] - p, mesh.positions[u] - p);
            if (!(d2 > 0)) continue;
            kept.push_back(u);
            points.push_back(mesh.positions[u]);
            meanSq += d2;
        }
        // The fit at the vertex is c = Σ αu fu, αu = (A⁻¹ rowu).x.
        if (!fitTangentPlane(p, n, points, fit)) continue;
        meanSq /= double(kept.size());
        Rgb value(0.0);
        for (size_t k = 0; k < kept.size(); ++k) value += (fit.inverse * fit.rows[k]).x * mesh.irradiance[kept[k]];
        out[v] = (mesh.irradiance[v] - value) / meanSq;
    }
    return out;
}

MeshIrradianceLookup::MeshIrradianceLookup(const IrradianceMeshCopy& mesh, double cellSize, double tolerance,
                                           Interpolation interpolation)
    : MeshIrradianceLookup(std::vector<const IrradianceMeshCopy*>{&mesh}, cellSize, tolerance, interpolation) {}

MeshIrradianceLookup::MeshIrradianceLookup(const std::vector<const IrradianceMeshCopy*>& meshes, double cellSize,
                                           double tolerance, Interpolation interpolation)
    : meshes_(meshes), cell_(cellSize), tolerance_(tolerance) {
    ML_ASSERT(meshes_.size() < (size_t(1) << 32), "a lookup of ", meshes_.size(), " meshes");
    if (interpolation == Interpolation::CurvatureCorrected)
        for (const IrradianceMeshCopy* m : meshes_) curvature_.push_back(vertexCurvature(*m));
    Bounds3 b;
    for (const IrradianceMeshCopy* m : meshes_)
        for (const Vec3& p : m->positions) b.extend(p);
    if (b.empty()) return;
    origin_ = b.lo - tolerance;
    for (int a = 0; a < 3; ++a)
        dims_[size_t(a)] = std::clamp(int(std::ceil((b.hi[a] - b.lo[a] + 2 * tolerance) / cell_)) + 1, 1, 1024);
    const size_t binCount = size_t(dims_[0]) * dims_[1] * dims_[2];
    // Each face's range of bins (its bounding box grown by the tolerance),
    // and its record's place: mesh by mesh, then by the bin of the range's
    // lowest corner, then as the mesh orders its faces.
    struct Placed {
        std::array<int, 6> range;
        size_t home;
        uint32_t mesh, triangle;
    };
    std::vector<Placed> placed;
    for (uint32_t m = 0; m < uint32_t(meshes_.size()); ++m) {
        const IrradianceMeshCopy& mesh = *meshes_[m];
        for (size_t t = 0; t < mesh.triangles.size(); ++t) {
            const glm::uvec3 i = mesh.triangles[t];
            const Vec3 &p0 = mesh.positions[i.x], &p1 = mesh.positions[i.y], &p2 = mesh.positions[i.z];
            Placed f{{}, 0, m, uint32_t(t)};
            for (int a = 0; a < 3; ++a) {
                const double mn = std::min({p0[a], p1[a], p2[a]}) - tolerance,
                             mx = std::max({p0[a], p1[a], p2[a]}) + tolerance;
                f.range[size_t(a)] = std::clamp(int((mn - origin_[a]) / cell_), 0, dims_[size_t(a)] - 1);
                f.range[size_t(a) + 3] = std::clamp(int((mx - origin_[a]) / cell_), 0, dims_[size_t(a)] - 1);
            }
            f.home = (size_t(f.range[2]) * dims_[1] + f.range[1]) * dims_[0] + f.range[0];
            placed.push_back(f);
        }
    }
    std::stable_sort(placed.begin(), placed.end(), [](const Placed& x, const Placed& y) {
        return x.mesh != y.mesh ? x.mesh < y.mesh : x.home < y.home;
    });
    // Counted, then filled in the records' order.
    auto eachBin = [&](const std::array<int, 6>& r, auto&& f) {
        for (int z = r[2]; z <= r[5]; ++z)
            for (int y = r[1]; y <= r[4]; ++y)
                for (int x = r[0]; x <= r[3]; ++x) f((size_t(z) * dims_[1] + y) * dims_[0] + x);
    };
    binStart_.assign(binCount + 1, 0);
    for (const Placed& f : placed) eachBin(f.range, [&](size_t bin) { ++binStart_[bin + 1]; });
    for (size_t k = 0; k < binCount; ++k) binStart_[k + 1] += binStart_[k];
    ML_ASSERT(binStart_[binCount] < (size_t(1) << 32), "a lookup's bins list ", binStart_[binCount], " faces");
    binFaces_.resize(binStart_[binCount]);
    std::vector<uint32_t> next(binStart_.begin(), binStart_.end() - 1);
    for (size_t k = 0; k < placed.size(); ++k)
        eachBin(placed[k].range, [&](size_t bin) { binFaces_[next[bin]++] = uint32_t(k); });
    faces_.resize(placed.size());
    for (size_t k = 0; k < placed.size(); ++k) {
        const IrradianceMeshCopy& mesh = *meshes_[placed[k].mesh];
        const glm::uvec3 i = mesh.triangles[placed[k].triangle];
        const Vec3& p0 = mesh.positions[i.x];
        const Vec3 e1 = mesh.positions[i.y] - p0, e2 = mesh.positions[i.z] - p0, n = glm::cross(e1, e2);
        const double nn = glm::dot(n, n);
        // A degenerate face gets a zero normal: the side test skips it.
        const Vec3 unit = nn > 0 ? n / std::sqrt(nn) : Vec3(0.0);
        const Vec3 u = nn > 0 ? glm::cross(e2, n) / nn : Vec3(0.0), v = nn > 0 ? glm::cross(n, e1) / nn : Vec3(0.0);
        Face& f = faces_[k];
        f.a = p0;
        for (int c = 0; c < 3; ++c) {
            f.n[c] = float(unit[c]);
            f.u[c] = float(u[c]);
            f.t[c] = float(v[c]);
            f.corners[c] = i[c];
        }
        f.mesh = placed[k].mesh;
    }
}

size_t MeshIrradianceLookup::memoryBytes() const {
    size_t bytes = faces_.size() * sizeof(Face) + (binStart_.size() + binFaces_.size()) * sizeof(uint32_t);
    for (const std::vector<Rgb>& c : curvature_) bytes += c.size() * sizeof(Rgb);
    return bytes;
}

Rgb MeshIrradianceLookup::at(const Vec3& p, const Vec3& n) const {
    if (faces_.empty()) return Rgb(0.0);
    std::array<int, 3> c{};
    for (int a = 0; a < 3; ++a) {
        const int i = int(std::floor((p[a] - origin_[a]) / cell_));
        if (i < 0 || i >= dims_[size_t(a)]) return Rgb(0.0);
        c[size_t(a)] = i;
    }
    const double none = tolerance_ * tolerance_;
    // A face this near p's plane holds p: the float normal's rounding is
    // about 1e-7 of a bin, so nothing else is nearer by more than that.
    const double onFace = std::min(1e-4 * none, 1e-10 * cell_ * cell_);
    const size_t bin = (size_t(c[2]) * dims_[1] + c[1]) * dims_[0] + c[0];
    const auto dot = [](const float* f, const Vec3& v) { return double(f[0]) * v.x + double(f[1]) * v.y + double(f[2]) * v.z; };
    // Each mesh's nearest face in turn (the bin lists them mesh by mesh),
    // its value added to the sum when the next mesh's faces begin.
    Rgb sum(0.0), result(0.0);
    double best = none;
    uint32_t mesh = 0;
    bool found = false;  // the current mesh has a face holding p: its other faces are passed over
    for (uint32_t k = binStart_[bin]; k < binStart_[bin + 1]; ++k) {
        const Face& f = faces_[binFaces_[k]];
        if (f.mesh != mesh) {
            sum += result;
            result = Rgb(0.0);
            best = none;
            mesh = f.mesh;
            found = false;
        }
        if (found) continue;
        // The other side, or a crease beyond 60°.
        if (dot(f.n, n) < 0.5) continue;
        const Vec3 ap = p - f.a;
        const double plane = dot(f.n, ap);
        if (plane * plane > best) continue;  // no point of the face is nearer than its plane
        const glm::uvec3 i(f.corners[0], f.corners[1], f.corners[2]);
        // p's projection inside the face (within rounding): the plane's
        // distance is the face's.
        const double bv = dot(f.u, ap), bw = dot(f.t, ap);
        constexpr double kSlack = 1e-6;
        if (bv >= -kSlack && bw >= -kSlack && bv + bw <= 1 + kSlack) {
            best = plane * plane;
            result = interpolate(mesh, i, Vec3(1 - bv - bw, bv, bw));
            found = best <= onFace;
            continue;
        }
        // Outside it: at least the violated barycentric over its gradient's
        // length (1/height) from it within the plane; so nearly every face
        // of the bin but the one holding p is passed over here.
        const auto outside = [](double b, double g2) { return b < 0 ? b * b / g2 : 0.0; };
        const Vec3 gu(f.u[0], f.u[1], f.u[2]), gt(f.t[0], f.t[1], f.t[2]);
        const double inPlane = std::max({outside(bv, glm::dot(gu, gu)), outside(bw, glm::dot(gt, gt)),
                                         outside(1 - bv - bw, glm::dot(gu + gt, gu + gt))});
        if (plane * plane + inPlane > best) continue;
        const std::vector<Vec3>& positions = meshes_[mesh]->positions;
        const Vec3 w = closestBarycentric(p, positions[i.x], positions[i.y], positions[i.z]);
        const Vec3 q = w.x * positions[i.x] + w.y * positions[i.y] + w.z * positions[i.z];
        const double d2 = glm::dot(q - p, q - p);
        if (d2 > best) continue;
        best = d2;
        result = interpolate(mesh, i, w);
    }
    return sum + result;
}

Rgb MeshIrradianceLookup::interpolate(uint32_t m, const glm::uvec3& i, const Vec3& b) const {
    const IrradianceMeshCopy& mesh = *meshes_[m];
    const Rgb &e0 = mesh.irradiance[i.x], &e1 = mesh.irradiance[i.y], &e2 = mesh.irradiance[i.z];
    const Rgb linear = b.x * e0 + b.y * e1 + b.z * e2;
    if (curvature_.empty()) return linear;
    const Vec3 &p0 = mesh.positions[i.x], &p1 = mesh.positions[i.y], &p2 = mesh.positions[i.z];
    const std::vector<Rgb>& curvature = curvature_[m];
    const Rgb &k0 = curvature[i.x], &k1 = curvature[i.y], &k2 = curvature[i.z];
    // Σ 4·bi·bj·δij, δij = ¼|eij|²·(κi + κj)/2.
    const auto edge = [](const Vec3& a, const Vec3& c) { return glm::dot(a - c, a - c); };
    const Rgb correction = b.x * b.y * edge(p0, p1) * 0.5 * (k0 + k1) + b.y * b.z * edge(p1, p2) * 0.5 * (k1 + k2) +
                           b.z * b.x * edge(p2, p0) * 0.5 * (k2 + k0);
    const Rgb bound = (e0 + e1 + e2) * (0.1 / 3);
    Rgb out;
    for (int c = 0; c < 3; ++c) out[c] = std::max(0.0, linear[c] + std::clamp(correction[c], -bound[c], bound[c]));
    return out;
}

RadianceProxy::RadianceProxy(const Scene& scene, const VoxelGrid& grid) : grid_(grid) {
    diagonal_ = scene.bounds.diagonal() > 0 ? scene.bounds.diagonal() : 1.0;
    // Uniform subdivision of each triangle into k² pieces, k from its longest
    // edge; a piece is at most about two voxels across: radiance is
    // interpolated linearly between its corners, and slices are filled at
    // twice the voxels' resolution.
    constexpr int kMaxSplit = 256;
    for (size_t mi = 0; mi < scene.meshes.size(); ++mi) {
        const Mesh& m = scene.meshes[mi];
        const bool closed = isClosedMesh(m);
        for (size_t t = 0; t < m.triangles.size(); ++t) {
            const Triangle3 p = m.triangle(t);
            const Vec3 an = m.areaNormal(t);
            if (!(glm::length(an) > 0)) continue;
            const Vec3 n = glm::normalize(an);
            const double longest = std::max({glm::length(p[1] - p[0]), glm::length(p[2] - p[1]), glm::length(p[0] - p[2])});
            const int k = std::clamp(int(std::ceil(longest / (2 * grid_.voxel))), 1, kMaxSplit);
            // The triangle's mean over its texture footprint (Mesh::albedo),
            // or its material's Kd: each piece reflects with it.
            const Rgb kd = scene.albedo(mi, t);
            // The sides to make: the front always, the back for open objects.
            for (int side = 0; side < (closed ? 1 : 2); ++side) {
                const uint32_t base = uint32_t(positions_.size());
                auto index = [&](int i, int j) { return base + uint32_t(i * (2 * k + 3 - i) / 2 + j); };
                for (int i = 0; i <= k; ++i)
                    for (int j = 0; j <= k - i; ++j) {
                        const double u = double(i) / k, v = double(j) / k;
                        positions_.push_back(p[0] + u * (p[1] - p[0]) + v * (p[2] - p[0]));
                        vertexTriangle_.push_back(uint32_t(triangles_.size()));
                    }
                auto add = [&](uint32_t a, uint32_t b, uint32_t c) {
                    ProxyTriangle pt;
                    pt.corners = side == 0 ? glm::uvec3(a, b, c) : glm::uvec3(a, c, b);
                    pt.normal = side == 0 ? n : -n;
                    pt.kd = kd;
                    pt.closed = closed;
                    triangles_.push_back(pt);
                };
                for (int i = 0; i < k; ++i)
                    for (int j = 0; j < k - i; ++j) {
                        add(index(i, j), index(i + 1, j), index(i, j + 1));
                        if (j + 1 < k - i) add(index(i + 1, j), index(i + 1, j + 1), index(i, j + 1));
                    }
            }
        }
    }
    // Bin by voxel: every voxel the triangle's bounding box touches.
    bins_.resize(grid_.count());
    for (size_t t = 0; t < triangles_.size(); ++t) {
        const glm::uvec3 c = triangles_[t].corners;
        Bounds3 b;
        b.extend(positions_[c.x]), b.extend(positions_[c.y]), b.extend(positions_[c.z]);
        const std::array<int, 3> lo = grid_.cell(b.lo), hi = grid_.cell(b.hi);
        for (int z = lo[2]; z <= hi[2]; ++z)
            for (int y = lo[1]; y <= hi[1]; ++y)
                for (int x = lo[0]; x <= hi[0]; ++x)
                    bins_[(size_t(z) * grid_.dims[1] + y) * grid_.dims[0] + x].push_back(uint32_t(t));
    }
}

std::vector<Rgb> RadianceProxy::radianceFrom(const std::vector<IrradianceMeshCopy>& meshes) const {
    std::vector<Rgb> radiance(positions_.size());
    const double tolerance = 1e-5 * diagonal_;
    std::vector<MeshIrradianceLookup> lookups;
    lookups.reserve(meshes.size());
    for (const IrradianceMeshCopy& m : meshes) lookups.emplace_back(m, grid_.voxel, tolerance);
    for (size_t v = 0; v < positions_.size(); ++v) {
        const ProxyTriangle& t = triangles_[vertexTriangle_[v]];
        Rgb e(0.0);
        for (const MeshIrradianceLookup& l : lookups) e += l.at(positions_[v], t.normal);
        radiance[v] = t.kd * e / kPi;
        ML_ASSERT(isFinite(radiance[v]), "non-finite radiance at proxy vertex ", v);
    }
    return radiance;
}

size_t RadianceProxy::memoryBytes() const {
    size_t n = triangles_.size() * sizeof(ProxyTriangle) + positions_.size() * (sizeof(Vec3) + 4);
    for (const auto& b : bins_) n += b.capacity() * sizeof(uint32_t) + sizeof(b);
    return n;
}

}  // namespace ml
