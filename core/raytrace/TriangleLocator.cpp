#include "TriangleLocator.h"

#include "core/Error.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

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

namespace {

// One device for every locator: a source's meshes make a dozen locators at a
// time, and a device is Embree's thread pool and settings, not per-mesh
// state. Made on first use (thread-safe static), kept for the process.
RTCDevice locatorDevice() {
    static const RTCDevice device = [] {
        const RTCDevice d = rtcNewDevice(nullptr);
        if (!d) throw std::runtime_error("Embree: cannot create a device for point queries");
        return d;
    }();
    return device;
}

}  // namespace

struct TriangleLocator::Impl {
    const std::vector<Vec3>& positions;
    const std::vector<glm::uvec3>& triangles;
    std::vector<glm::vec3> normals;  // unit, zero for a face without area
    Vec3 centre{0.0};
    double tolerance = 0;
    float radius = 0;  // the query sphere: the tolerance and a float margin
    RTCScene rtc = nullptr;
    size_t bytes = 0;

    // What one query carries into the callback.
    struct Query {
        const Impl* impl;
        Vec3 p, n;
        double best;  // squared distance of the nearest accepted face so far
        uint32_t triangle;
        Vec3 barycentric;
        bool found;
    };

    static bool visit(RTCPointQueryFunctionArguments* args) {
        Query& q = *static_cast<Query*>(args->userPtr);
        const Impl& s = *q.impl;
        const uint32_t t = args->primID;
        const glm::vec3& fn = s.normals[t];
        // The other side, or a crease beyond 60°.
        if (double(fn.x) * q.n.x + double(fn.y) * q.n.y + double(fn.z) * q.n.z < 0.5) return false;
        const glm::uvec3 i = s.triangles[t];
        const Vec3 &a = s.positions[i.x], &b = s.positions[i.y], &c = s.positions[i.z];
        const Vec3 w = closestBarycentric(q.p, a, b, c);
        const Vec3 x = w.x * a + w.y * b + w.z * c;
        const double d2 = glm::dot(x - q.p, x - q.p);
        if (d2 > q.best || (q.found && d2 == q.best && t < q.triangle)) return false;
        q.best = d2;
        q.triangle = t;
        q.barycentric = w;
        q.found = true;
        return false;  // the sphere is kept: it holds a few faces at most
    }

    void release() {
        if (rtc) rtcReleaseScene(rtc);
        rtc = nullptr;
    }
};

TriangleLocator::TriangleLocator(const std::vector<Vec3>& positions, const std::vector<glm::uvec3>& triangles,
                                 double tolerance)
    : impl_(new Impl{positions, triangles, {}, Vec3(0.0), tolerance, 0.f, nullptr, 0}) {
    Impl& s = *impl_;
    if (triangles.empty()) return;
    Bounds3 b;
    for (const Vec3& p : positions) b.extend(p);
    s.centre = b.center();
    double extent = 0;
    for (int a = 0; a < 3; ++a) extent = std::max({extent, std::abs(b.lo[a] - s.centre[a]), std::abs(b.hi[a] - s.centre[a])});
    // Each float coordinate is off by at most half an ulp of the extent; a
    // few of those on the sphere's radius keep every face within the
    // tolerance among the candidates.
    s.radius = float(tolerance + 8 * extent * double(std::numeric_limits<float>::epsilon()));
    s.normals.resize(triangles.size());
    for (size_t t = 0; t < triangles.size(); ++t) {
        const glm::uvec3 i = triangles[t];
        const Vec3 n = glm::cross(positions[i.y] - positions[i.x], positions[i.z] - positions[i.x]);
        const double len = glm::length(n);
        s.normals[t] = len > 0 ? glm::vec3(n / len) : glm::vec3(0.f);
    }
    const RTCDevice device = locatorDevice();
    s.rtc = rtcNewScene(device);
    rtcSetSceneBuildQuality(s.rtc, RTC_BUILD_QUALITY_MEDIUM);
    RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                           3 * sizeof(float), positions.size()));
    auto* idx = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                3 * sizeof(uint32_t), triangles.size()));
    if (!v || !idx) {
        rtcReleaseGeometry(geom);
        s.release();
        throw std::runtime_error("Embree: cannot allocate a mesh for point queries");
    }
    for (size_t i = 0; i < positions.size(); ++i) {
        const glm::vec3 p(positions[i] - s.centre);
        v[3 * i] = p.x;
        v[3 * i + 1] = p.y;
        v[3 * i + 2] = p.z;
    }
    for (size_t t = 0; t < triangles.size(); ++t) {
        idx[3 * t] = triangles[t].x;
        idx[3 * t + 1] = triangles[t].y;
        idx[3 * t + 2] = triangles[t].z;
    }
    rtcCommitGeometry(geom);
    rtcAttachGeometry(s.rtc, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(s.rtc);
    if (rtcGetDeviceError(device) != RTC_ERROR_NONE) {
        s.release();
        throw std::runtime_error("Embree: building a point-query BVH failed");
    }
    // Embree's BVH: some 1.5 nodes of 4 boxes per face, and the buffers.
    s.bytes = triangles.size() * (sizeof(glm::vec3) + 3 * sizeof(uint32_t) + 160) + positions.size() * 3 * sizeof(float);
}

TriangleLocator::~TriangleLocator() {
    if (impl_) impl_->release();
}

TriangleLocator::TriangleLocator(TriangleLocator&&) noexcept = default;

TriangleLocator& TriangleLocator::operator=(TriangleLocator&& other) noexcept {
    if (impl_) impl_->release();
    impl_ = std::move(other.impl_);
    return *this;
}

std::optional<TriangleLocator::Location> TriangleLocator::locate(const Vec3& p, const Vec3& n) const {
    if (!impl_ || !impl_->rtc) return std::nullopt;
    const Impl& s = *impl_;
    const glm::vec3 local(p - s.centre);
    RTCPointQuery query;
    query.x = local.x;
    query.y = local.y;
    query.z = local.z;
    query.time = 0.f;
    query.radius = s.radius;
    RTCPointQueryContext context;
    rtcInitPointQueryContext(&context);
    Impl::Query q{&s, p, n, s.tolerance * s.tolerance, 0, Vec3(0.0), false};
    rtcPointQuery(s.rtc, &query, &context, &Impl::visit, &q);
    if (!q.found) return std::nullopt;
    return Location{q.triangle, q.barycentric};
}

size_t TriangleLocator::memoryBytes() const { return impl_ ? impl_->bytes : 0; }

}  // namespace ml
