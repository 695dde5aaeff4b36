#include "IrradianceVolume.h"

#include "RadianceProxy.h"
#include "RayGather.h"
#include "TriangleGather.h"
#include "core/Error.h"
#include "core/ParallelFor.h"
#include "core/raytrace/EmbreeScene.h"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace ml {

void IrradianceVolumeSettings::validate() const {
    if (probes < 1 || probes > 64)
        throw InputError(concat("irradiance volume: ", probes, " probes along the longest side is not within 1..64"));
    if (faceSize < 2 || faceSize > 128)
        throw InputError(concat("irradiance volume: cube-map faces of ", faceSize, " texels are not within 2..128"));
    if (threads < 1 || threads > 1024)
        throw InputError(concat("irradiance volume: ", threads, " threads is not within 1..1024"));
}

// --- The grid ------------------------------------------------------------------

ProbeGrid::ProbeGrid(const Bounds3& bounds, int probesAlongLongest) {
    const Vec3 extent = bounds.extent();
    const double longest = std::max({extent.x, extent.y, extent.z});
    const Vec3 base = bounds.empty() ? Vec3(0.0) : bounds.lo;
    // The outer layers stand a little inside the bounds: near a wall there a
    // probe sees what the wall's points see, but not from on it, nor from a
    // gap between the wall and something mounted on it (the Cornell box's
    // light hangs 0.5 mm below its ceiling).
    const double inset = probesAlongLongest > 1 ? kInset * longest / (probesAlongLongest - 1) : 0.0;
    for (int a = 0; a < 3; ++a) {
        if (probesAlongLongest < 2 || !(extent[a] > 2 * inset)) {
            // One probe on this axis, in the middle (a flat scene's plane).
            dims[size_t(a)] = 1;
            lo[a] = base[a] + 0.5 * extent[a];
            cell[a] = 0;
            continue;
        }
        // Cells as near cubes as whole numbers allow.
        const double spacing = longest / (probesAlongLongest - 1);
        const int intervals = std::max(1, int(std::lround(extent[a] / spacing)));
        dims[size_t(a)] = intervals + 1;
        lo[a] = base[a] + inset;
        cell[a] = (extent[a] - 2 * inset) / intervals;
    }
}

void ProbeGrid::corners(const Vec3& x, std::array<size_t, 8>& index, std::array<double, 8>& weight,
                        std::array<Vec3, 8>& position) const {
    std::array<int, 3> i0{0, 0, 0}, i1{0, 0, 0};
    Vec3 t(0.0);
    for (int a = 0; a < 3; ++a) {
        const int n = dims[size_t(a)];
        if (n == 1 || !(cell[a] > 0)) continue;  // one probe on this axis: it takes all the weight
        const double g = (x[a] - lo[a]) / cell[a];
        const int base = std::clamp(int(std::floor(g)), 0, n - 2);
        i0[size_t(a)] = base;
        i1[size_t(a)] = base + 1;
        t[a] = std::clamp(g - base, 0.0, 1.0);
    }
    for (int c = 0; c < 8; ++c) {
        const int i = (c & 1) ? i1[0] : i0[0], j = (c & 2) ? i1[1] : i0[1], k = (c & 4) ? i1[2] : i0[2];
        index[size_t(c)] = this->index(i, j, k);
        position[size_t(c)] = this->position(i, j, k);
        weight[size_t(c)] = ((c & 1) ? t.x : 1 - t.x) * ((c & 2) ? t.y : 1 - t.y) * ((c & 4) ? t.z : 1 - t.z);
    }
}

// --- The cube map's directions ------------------------------------------------------

namespace {

// The solid angle of the part of the plane z = 1 over [0, u] × [0, v]
// (signed), seen from the origin: atan(uv / √(u² + v² + 1)).
double planeCornerSolidAngle(double u, double v) { return std::atan2(u * v, std::sqrt(u * u + v * v + 1)); }

}  // namespace

CubeMapDirections::CubeMapDirections(int size) {
    const Vec3 axes[3] = {Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
    for (int axis = 0; axis < 3; ++axis)
        for (const double sign : {1.0, -1.0}) {
            const Vec3 m = sign * axes[axis], u = axes[(axis + 1) % 3], v = axes[(axis + 2) % 3];
            for (int a = 0; a < size; ++a)
                for (int b = 0; b < size; ++b) {
                    const double u0 = -1 + 2.0 * a / size, u1 = -1 + 2.0 * (a + 1) / size;
                    const double v0 = -1 + 2.0 * b / size, v1 = -1 + 2.0 * (b + 1) / size;
                    const double uc = 0.5 * (u0 + u1), vc = 0.5 * (v0 + v1);
                    direction.push_back(glm::normalize(m + uc * u + vc * v));
                    solidAngle.push_back(planeCornerSolidAngle(u1, v1) - planeCornerSolidAngle(u0, v1) -
                                         planeCornerSolidAngle(u1, v0) + planeCornerSolidAngle(u0, v0));
                    // The face's own axis sees the texel as a hemicube's top
                    // face does; the face's u (v) axis as a side face, over
                    // the part of the texel on its positive side.
                    std::array<double, 6> c{};
                    c[size_t(2 * axis + (sign > 0 ? 0 : 1))] = planeRectangleWeight(u0, u1, v0, v1);
                    const auto side = [](double a0, double a1, double b0, double b1, double s) {
                        const double lo = std::max(0.0, std::min(s * a0, s * a1)), hi = std::max(s * a0, s * a1);
                        return hi > lo ? sideRectangleWeight(b0, b1, lo, hi) : 0.0;
                    };
                    const int ua = (axis + 1) % 3, va = (axis + 2) % 3;
                    c[size_t(2 * ua)] = side(u0, u1, v0, v1, 1.0);
                    c[size_t(2 * ua + 1)] = side(u0, u1, v0, v1, -1.0);
                    c[size_t(2 * va)] = side(v0, v1, u0, u1, 1.0);
                    c[size_t(2 * va + 1)] = side(v0, v1, u0, u1, -1.0);
                    axisCosine.push_back(c);
                }
        }
}

// --- The volume -------------------------------------------------------------------------

namespace {

const IrradianceVolumeSettings& validated(const IrradianceVolumeSettings& s) {
    s.validate();
    return s;
}

}  // namespace

IrradianceVolume::IrradianceVolume(const Scene& scene, const IrradianceVolumeSettings& settings)
    : scene_(scene),
      settings_(validated(settings)),
      grid_(scene.bounds, settings.probes),
      rays_(std::make_unique<EmbreeScene>(scene)),
      closed_(closedMeshesOf(scene)) {}

IrradianceVolume::~IrradianceVolume() = default;

std::string IrradianceVolume::name() const { return "volume"; }

void IrradianceVolume::setSource(size_t slot, const std::vector<IrradianceMeshCopy>& irradiance, double importance) {
    const auto start = std::chrono::steady_clock::now();
    if (slot >= sources_.size()) sources_.resize(slot + 1);
    auto source = std::make_unique<Source>();
    // The cache's radiance read where each ray lands, as the ray gather
    // reads it (gatherCachedRadiance): lookup cells of 1/64 of the scene.
    const double diagonal = scene_.bounds.diagonal() > 0 ? scene_.bounds.diagonal() : 1.0;
    std::vector<const IrradianceMeshCopy*> meshes;
    for (const IrradianceMeshCopy& m : irradiance) meshes.push_back(&m);
    const MeshIrradianceLookup lookup(meshes, diagonal / 64, 1e-5 * diagonal);
    source->fields.resize(grid_.count());
    source->residual.assign(grid_.count(), {});
    source->inside.assign(grid_.count(), 0);
    const int faceSize =
        std::max(std::min(8, settings_.faceSize),
                 int(std::lround(settings_.faceSize * std::sqrt(std::clamp(importance, 0.0, 1.0)))));
    const CubeMapDirections& directions = directions_.try_emplace(faceSize, faceSize).first->second;
    const size_t rayCount = directions.direction.size();
    // Each probe on its own (the lookups and the ray scene are read-only),
    // written to its own slot: the same fields for any thread count.
    parallelFor(grid_.count(), settings_.threads, [&](size_t index) {
        const int i = int(index % size_t(grid_.dims[0]));
        const int j = int(index / size_t(grid_.dims[0]) % size_t(grid_.dims[1]));
        const int k = int(index / (size_t(grid_.dims[0]) * size_t(grid_.dims[1])));
        const Capture c = capture(grid_.position(i, j, k), directions, lookup);
        source->fields[index] = c.field;
        if (settings_.axisCorrection)
            for (int a = 0; a < 6; ++a) {
                Vec3 axis(0.0);
                axis[a / 2] = a % 2 ? -1.0 : 1.0;
                source->residual[index][size_t(a)] = c.axisIrradiance[size_t(a)] - c.field.irradiance(axis);
            }
        // Mostly back faces, or a quarter of the sphere of a closed object's
        // inside (which no probe outside it sees at all: a probe inside a
        // block standing on the floor sees the floor below it from the front).
        if (settings_.skipInside && (c.backSolidAngle > 2 * kPi || c.closedBackSolidAngle > kPi))
            source->inside[index] = 1;
    });
    source->insideCount = size_t(std::count(source->inside.begin(), source->inside.end(), 1));
    stats_.source = concat(grid_.dims[0], "x", grid_.dims[1], "x", grid_.dims[2], " probes (", source->insideCount,
                           " inside objects), ", rayCount, " rays each");
    sources_[slot] = std::move(source);
    size_t held = 0;
    for (const auto& s : sources_)
        if (s) held += s->fields.size() * (sizeof(ShRgb) + sizeof(s->residual[0])) + s->inside.size();
    stats_.sourceBytes = held;
    stats_.buildSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

IrradianceVolume::Capture IrradianceVolume::capture(const Vec3& p, const CubeMapDirections& directions,
                                                    const MeshIrradianceLookup& lookup) const {
    Capture c;
    for (size_t r = 0; r < directions.direction.size(); ++r) {
        const Vec3& d = directions.direction[r];
        const double w = directions.solidAngle[r];
        RayHit hit;
        if (!rays_->intersect(p, d, 0.0, kInf, hit)) continue;
        const SurfacePoint y = rays_->surface(hit);
        // The side the ray arrives on; a closed object's inside is black.
        Vec3 side = y.geometricNormal;
        if (glm::dot(side, d) > 0) {
            c.backSolidAngle += w;
            if (closed_[hit.mesh]) {
                c.closedBackSolidAngle += w;
                continue;
            }
            side = -side;
        }
        const Rgb radiance = y.kd(scene_) / kPi * lookup.at(y.position, side);
        c.field.add(d, radiance, w);
        for (size_t a = 0; a < 6; ++a) c.axisIrradiance[a] += directions.axisCosine[r][a] * radiance;
    }
    return c;
}

void IrradianceVolume::releaseSource(size_t slot) {
    if (slot < sources_.size()) sources_[slot].reset();
}

size_t IrradianceVolume::insideProbes(size_t slot) const {
    ML_ASSERT(slot < sources_.size() && sources_[slot], "irradiance volume: source ", slot, " is not built");
    return sources_[slot]->insideCount;
}

bool IrradianceVolume::insideProbe(size_t slot, size_t index) const {
    ML_ASSERT(slot < sources_.size() && sources_[slot], "irradiance volume: source ", slot, " is not built");
    return sources_[slot]->inside.at(index) != 0;
}

const ShRgb& IrradianceVolume::probe(size_t slot, size_t index) const {
    ML_ASSERT(slot < sources_.size() && sources_[slot], "irradiance volume: source ", slot, " is not built");
    return sources_[slot]->fields.at(index);
}

Rgb IrradianceVolume::probeIrradiance(size_t slot, size_t index, const Vec3& n) const {
    const ShRgb& field = probe(slot, index);
    const std::array<Rgb, 6>& residual = sources_[slot]->residual[index];
    Rgb e = field.irradiance(n);
    for (int a = 0; a < 3; ++a) e += (n[a] * n[a]) * residual[size_t(2 * a + (n[a] > 0 ? 0 : 1))];
    return e;
}

Rgb IrradianceVolume::estimate(size_t slot, const Vec3& x, const Vec3& nIn, uint32_t) {
    ML_ASSERT(slot < sources_.size() && sources_[slot], "irradiance volume: source ", slot, " is not built");
    const auto start = std::chrono::steady_clock::now();
    const Source& source = *sources_[slot];
    const Vec3 n = glm::normalize(nIn);
    std::array<size_t, 8> index;
    std::array<double, 8> trilinear;
    std::array<Vec3, 8> position;
    grid_.corners(x, index, trilinear, position);
    // Each probe's weight without visibility (trilinear × facing, 0 inside),
    // then with it.
    std::array<double, 8> open{}, seen{};
    const Vec3 origin = rays_->spawnPoint(x, n, n);
    // On an edge or in a corner the origin lies on another surface's plane
    // too, and a ray leaving it may meet that surface at t ≈ 0: the test
    // starts 1e-5 of the scene out (a wall that near is a contact, not a
    // wall between the point and a probe).
    const double hair = 1e-5 * std::max(scene_.bounds.diagonal(), 1e-30);
    double openSum = 0, seenSum = 0;
    for (size_t c = 0; c < 8; ++c) {
        if (!(trilinear[c] > 0) || source.inside[index[c]]) continue;
        const Vec3 toProbe = position[c] - x;
        const double distance = glm::length(toProbe);
        const double cosine = distance > 0 ? glm::dot(toProbe, n) / distance : 1.0;
        const double facing = 0.25 * (1 + cosine) * (1 + cosine) + 0.05;
        open[c] = trilinear[c] * facing;
        openSum += open[c];
        const Vec3 ray = position[c] - origin;
        const double length = glm::length(ray);
        const bool visible = !settings_.visibility || !(length > hair) ||
                             !rays_->occluded(origin, ray, hair / length, 1.0);
        seen[c] = visible ? open[c] : 0.0;
        seenSum += seen[c];
    }
    const std::array<double, 8>* weights = &seen;
    double sum = seenSum;
    if (!(seenSum > 0)) {
        weights = &open;
        sum = openSum;
        if (openSum > 0) ++unseen_;
        else ++allInside_;
    }
    Rgb blend(0.0);
    if (sum > 0)
        for (size_t c = 0; c < 8; ++c)
            if ((*weights)[c] > 0) blend += ((*weights)[c] / sum) * probeIrradiance(slot, index[c], n);
    const Rgb result = glm::max(blend, Rgb(0.0));
    stats_.estimates++;
    stats_.estimateSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
}

IndirectStats IrradianceVolume::stats() const { return stats_; }

}  // namespace ml
