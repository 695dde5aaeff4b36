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
    : mesh_(mesh), cell_(cellSize), tolerance_(tolerance) {
    if (interpolation == Interpolation::CurvatureCorrected) curvature_ = vertexCurvature(mesh);
    Bounds3 b;
    for (const Vec3& p : mesh.positions) b.extend(p);
    if (b.empty()) return;
    origin_ = b.lo - tolerance;
    for (int a = 0; a < 3; ++a)
        dims_[size_t(a)] = std::clamp(int(std::ceil((b.hi[a] - b.lo[a] + 2 * tolerance) / cell_)) + 1, 1, 1024);
    const size_t binCount = size_t(dims_[0]) * dims_[1] * dims_[2];
    // Each face's range of bins (its bounding box grown by the tolerance).
    std::vector<std::array<int, 6>> ranges(mesh.triangles.size());
    binStart_.assign(binCount + 1, 0);
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        const glm::uvec3 i = mesh.triangles[t];
        const Vec3 &p0 = mesh.positions[i.x], &p1 = mesh.positions[i.y], &p2 = mesh.positions[i.z];
        std::array<int, 6>& r = ranges[t];
        for (int a = 0; a < 3; ++a) {
            const double mn = std::min({p0[a], p1[a], p2[a]}) - tolerance, mx = std::max({p0[a], p1[a], p2[a]}) + tolerance;
            r[size_t(a)] = std::clamp(int((mn - origin_[a]) / cell_), 0, dims_[size_t(a)] - 1);
            r[size_t(a) + 3] = std::clamp(int((mx - origin_[a]) / cell_), 0, dims_[size_t(a)] - 1);
        }
    }
    // Counted, then filled in face order.
    auto eachBin = [&](const std::array<int, 6>& r, auto&& f) {
        for (int z = r[2]; z <= r[5]; ++z)
            for (int y = r[1]; y <= r[4]; ++y)
                for (int x = r[0]; x <= r[3]; ++x) f((size_t(z) * dims_[1] + y) * dims_[0] + x);
    };
    for (const auto& r : ranges) eachBin(r, [&](size_t bin) { ++binStart_[bin + 1]; });
    for (size_t k = 0; k < binCount; ++k) binStart_[k + 1] += binStart_[k];
    binFaces_.resize(binStart_[binCount]);
    std::vector<uint32_t> next(binStart_.begin(), binStart_.end() - 1);
    for (size_t t = 0; t < ranges.size(); ++t) eachBin(ranges[t], [&](size_t bin) { binFaces_[next[bin]++] = uint32_t(t); });
    faces_.resize(mesh.triangles.size());
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        const glm::uvec3 i = mesh.triangles[t];
        const Vec3& p0 = mesh.positions[i.x];
        const Vec3 e1 = mesh.positions[i.y] - p0, e2 = mesh.positions[i.z] - p0, n = glm::cross(e1, e2);
        const double nn = glm::dot(n, n);
        // A degenerate face gets a zero normal: the side test skips it.
        const Vec3 unit = nn > 0 ? n / std::sqrt(nn) : Vec3(0.0);
        const Vec3 u = nn > 0 ? glm::cross(e2, n) / nn : Vec3(0.0), v = nn > 0 ? glm::cross(n, e1) / nn : Vec3(0.0);
        Face& f = faces_[t];
        f.a = p0;
        for (int k = 0; k < 3; ++k) {
            f.n[k] = float(unit[k]);
            f.u[k] = float(u[k]);
            f.t[k] = float(v[k]);
            f.corners[k] = i[k];
        }
    }
}

Rgb MeshIrradianceLookup::at(const Vec3& p, const Vec3& n) const {
    if (faces_.empty()) return Rgb(0.0);
    std::array<int, 3> c{};
    for (int a = 0; a < 3; ++a) {
        const int i = int(std::floor((p[a] - origin_[a]) / cell_));
        if (i < 0 || i >= dims_[size_t(a)]) return Rgb(0.0);
        c[size_t(a)] = i;
    }
    double best = tolerance_ * tolerance_;
    // A face this near p's plane holds p: the float normal's rounding is
    // about 1e-7 of a bin, so nothing else is nearer by more than that.
    const double onFace = std::min(1e-4 * best, 1e-10 * cell_ * cell_);
    Rgb result(0.0);
    const size_t bin = (size_t(c[2]) * dims_[1] + c[1]) * dims_[0] + c[0];
    const auto dot = [](const float* f, const Vec3& v) { return double(f[0]) * v.x + double(f[1]) * v.y + double(f[2]) * v.z; };
    for (uint32_t k = binStart_[bin]; k < binStart_[bin + 1]; ++k) {
        const Face& f = faces_[binFaces_[k]];
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
            result = interpolate(i, Vec3(1 - bv - bw, bv, bw));
            if (best <= onFace) break;
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
        const Vec3 w = closestBarycentric(p, mesh_.positions[i.x], mesh_.positions[i.y], mesh_.positions[i.z]);
        const Vec3 q = w.x * mesh_.positions[i.x] + w.y * mesh_.positions[i.y] + w.z * mesh_.positions[i.z];
        const double d2 = glm::dot(q - p, q - p);
        if (d2 > best) continue;
        best = d2;
        result = interpolate(i, w);
    }
    return result;
}

Rgb MeshIrradianceLookup::interpolate(const glm::uvec3& i, const Vec3& b) const {
    const Rgb &e0 = mesh_.irradiance[i.x], &e1 = mesh_.irradiance[i.y], &e2 = mesh_.irradiance[i.z];
    const Rgb linear = b.x * e0 + b.y * e1 + b.z * e2;
    if (curvature_.empty()) return linear;
    const Vec3 &p0 = mesh_.positions[i.x], &p1 = mesh_.positions[i.y], &p2 = mesh_.positions[i.z];
    const Rgb &k0 = curvature_[i.x], &k1 = curvature_[i.y], &k2 = curvature_[i.z];
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
