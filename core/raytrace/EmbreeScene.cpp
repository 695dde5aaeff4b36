#include "EmbreeScene.h"

#include "core/Error.h"

#include <embree3/rtcore.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace ml {

namespace {

const char* embreeErrorName(RTCError e) {
    switch (e) {
        case RTC_ERROR_NONE: return "no error";
        case RTC_ERROR_UNKNOWN: return "unknown error";
        case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
        case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
        case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
        case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
        case RTC_ERROR_CANCELLED: return "cancelled";
    }
    return "?";
}

// Embree's float ray limits from double ones: tFar = ∞ stays ∞.
float toFloatLimit(double t) {
    if (t >= double(std::numeric_limits<float>::max())) return std::numeric_limits<float>::infinity();
    return float(t);
}

}  // namespace

struct EmbreeScene::Impl {
    const Scene& scene;
    Vec3 origin;        // positions go to Embree relative to this
    double sceneSize;   // bounding diagonal
    RTCDevice device = nullptr;
    RTCScene rtc = nullptr;
    // Per mesh, per triangle: 1 + index of its light, or 0.
    std::vector<std::vector<int32_t>> lightIds;
    // Per mesh: some face's material is a cut-out (Material::alphaMap) and
    // the mesh has texture coordinates; then every query runs the filter.
    std::vector<char> cutOutMeshes;
    bool anyCutOut = false;

    // An intersect context extended with what the filter needs (Embree
    // passes the context pointer back to the filter).
    struct FilterContext {
        RTCIntersectContext context;  // first member: Embree sees only this
        const Impl* impl;
        RayFilter filter;
        Vec3 origin;  // ray origin, in the scene's frame (double)
    };

    explicit Impl(const Scene& s) : scene(s), origin(s.bounds.empty() ? Vec3(0.0) : s.bounds.center()),
                                    sceneSize(std::max(s.bounds.diagonal(), 1e-300)) {
        device = rtcNewDevice(nullptr);
        if (!device) throw std::runtime_error(concat("Embree: cannot create a device: ", embreeErrorName(rtcGetDeviceError(nullptr))));
        rtc = rtcNewScene(device);
        // Robust: watertight traversal, no edge cracks between neighbouring
        // triangles (a reference must not leak light through shared edges).
        rtcSetSceneFlags(rtc, RTCSceneFlags(RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION));
        rtcSetSceneBuildQuality(rtc, RTC_BUILD_QUALITY_HIGH);

        lightIds.resize(scene.meshes.size());
        for (size_t m = 0; m < scene.meshes.size(); ++m)
            lightIds[m].assign(scene.meshes[m].triangles.size(), 0);
        for (size_t l = 0; l < scene.lights.size(); ++l)
            for (uint32_t t : scene.lights[l].triangles) lightIds[scene.lights[l].mesh][t] = int32_t(l + 1);
        cutOutMeshes.assign(scene.meshes.size(), 0);
        for (size_t m = 0; m < scene.meshes.size(); ++m) {
            const Mesh& mesh = scene.meshes[m];
            if (mesh.texcoords.empty()) continue;
            for (uint32_t mi : mesh.materials)
                if (scene.materials[mi].alphaMap) {
                    cutOutMeshes[m] = 1;
                    anyCutOut = true;
                    break;
                }
        }

        for (size_t m = 0; m < scene.meshes.size(); ++m) {
            const Mesh& mesh = scene.meshes[m];
            if (mesh.triangles.empty()) continue;
            RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
            auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                                   3 * sizeof(float), mesh.positions.size()));
            auto* idx = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                        3 * sizeof(uint32_t), mesh.triangles.size()));
            if (!v || !idx) {
                rtcReleaseGeometry(geom);
                throw std::runtime_error(concat("Embree: cannot allocate mesh '", mesh.name, "': ",
                                                embreeErrorName(rtcGetDeviceError(device))));
            }
            for (size_t i = 0; i < mesh.positions.size(); ++i) {
                const glm::vec3 p(mesh.positions[i] - origin);
                v[3 * i] = p.x;
                v[3 * i + 1] = p.y;
                v[3 * i + 2] = p.z;
            }
            for (size_t t = 0; t < mesh.triangles.size(); ++t) {
                idx[3 * t] = mesh.triangles[t].x;
                idx[3 * t + 1] = mesh.triangles[t].y;
                idx[3 * t + 2] = mesh.triangles[t].z;
            }
            rtcCommitGeometry(geom);
            rtcAttachGeometryByID(rtc, geom, unsigned(m));  // geometry id = mesh index
            rtcReleaseGeometry(geom);
        }
        rtcCommitScene(rtc);
        const RTCError e = rtcGetDeviceError(device);
        if (e != RTC_ERROR_NONE) {
            release();
            throw std::runtime_error(concat("Embree: building the BVH failed: ", embreeErrorName(e)));
        }
    }

    ~Impl() { release(); }

    void release() {
        if (rtc) rtcReleaseScene(rtc);
        if (device) rtcReleaseDevice(device);
        rtc = nullptr;
        device = nullptr;
    }

    // Whether the hit at Embree's barycentrics (u, v) of triangle `prim` of
    // mesh `geom` falls where its material's cut-out removes the surface.
    bool cutAway(unsigned geom, unsigned prim, float u, float v) const {
        if (!cutOutMeshes[geom]) return false;
        const Mesh& mesh = scene.meshes[geom];
        const Material& m = scene.materials[mesh.materials[prim]];
        if (!m.alphaMap) return false;
        const glm::uvec3 idx = mesh.triangles[prim];
        const Vec2 t0 = mesh.texcoords[idx.x];
        return m.cutAway(t0 + double(u) * (mesh.texcoords[idx.y] - t0) + double(v) * (mesh.texcoords[idx.z] - t0));
    }

    // Rejects hits the RayFilter excludes, and those a cut-out removes
    // (called by Embree per candidate hit, for closest hits and occlusion alike).
    static void filterHits(const RTCFilterFunctionNArguments* args) {
        const auto* fc = reinterpret_cast<const FilterContext*>(args->context);
        for (unsigned i = 0; i < args->N; ++i) {
            if (args->valid[i] != -1) continue;
            const unsigned geom = RTCHitN_geomID(args->hit, args->N, i);
            const unsigned prim = RTCHitN_primID(args->hit, args->N, i);
            if (fc->impl->cutAway(geom, prim, RTCHitN_u(args->hit, args->N, i), RTCHitN_v(args->hit, args->N, i))) {
                args->valid[i] = 0;
                continue;
            }
            const int32_t id = fc->impl->lightIds[geom][prim];
            const RayFilter& f = fc->filter;
            bool keep = true;
            if (f.skipLight >= 0 && id == f.skipLight + 1) keep = false;
            if (f.onlyLight >= 0 && id != f.onlyLight + 1) keep = false;
            if (keep && f.frontOnly) {
                const Mesh& mesh = fc->impl->scene.meshes[geom];
                const Triangle3 p = mesh.triangle(prim);
                keep = glm::dot(glm::cross(p[1] - p[0], p[2] - p[0]), fc->origin - p[0]) > 0;
            }
            if (!keep) args->valid[i] = 0;
        }
    }

    void initContext(FilterContext& fc, const RayFilter& filter, const Vec3& rayOrigin) const {
        rtcInitIntersectContext(&fc.context);
        fc.context.filter = filter.any() || anyCutOut ? &Impl::filterHits : nullptr;
        fc.impl = this;
        fc.filter = filter;
        fc.origin = rayOrigin;
    }

    static void fillRay(RTCRay& r, const glm::vec3& o, const glm::vec3& d, float tNear, float tFar) {
        r.org_x = o.x;
        r.org_y = o.y;
        r.org_z = o.z;
        r.dir_x = d.x;
        r.dir_y = d.y;
        r.dir_z = d.z;
        r.tnear = tNear;
        r.tfar = tFar;
        r.time = 0;
        r.mask = ~0u;
        r.id = 0;
        r.flags = 0;
    }
};

EmbreeScene::EmbreeScene(const Scene& scene) : impl_(std::make_unique<Impl>(scene)) {}
EmbreeScene::~EmbreeScene() = default;

const Scene& EmbreeScene::scene() const { return impl_->scene; }

bool EmbreeScene::intersect(const Vec3& origin, const Vec3& direction, double tNear, double tFar, RayHit& hit,
                            const RayFilter& filter) const {
    if (!(tFar > tNear)) return false;
    Impl::FilterContext fc;
    impl_->initContext(fc, filter, origin);
    RTCRayHit rh;
    Impl::fillRay(rh.ray, glm::vec3(origin - impl_->origin), glm::vec3(direction), float(std::max(tNear, 0.0)),
                  toFloatLimit(tFar));
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(impl_->rtc, &fc.context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    hit.mesh = rh.hit.geomID;
    hit.triangle = rh.hit.primID;
    hit.t = rh.ray.tfar;
    hit.b1 = rh.hit.u;
    hit.b2 = rh.hit.v;
    // Faces back to back (a sheet modelled as two triangles facing either
    // way, as SketchUp and other exporters write a double-sided face, and as
    // the glTF loader splits a doubleSided emitter) lie at the same distance,
    // and Embree returns either. The one whose front faces the ray is hit: a
    // hit on a face's back is traced again, front faces only, over the hit's
    // own rounding (rayOffset either side). Without this a path met the back
    // of the back rooms' up-facing light panels as often as the down-facing
    // ones, and the reference lost a tenth of their direct light.
    if (!filter.frontOnly) {
        const Triangle3 p = impl_->scene.meshes[hit.mesh].triangle(hit.triangle);
        if (glm::dot(glm::cross(p[1] - p[0], p[2] - p[0]), direction) > 0) {
            const double length = glm::length(direction);
            const double slack = rayOffset(origin + hit.t * direction) / length;
            RayFilter front = filter;
            front.frontOnly = true;
            RayHit twin;
            if (intersect(origin, direction, std::max(tNear, hit.t - slack), std::min(tFar, hit.t + slack), twin, front))
                hit = twin;
        }
    }
    return true;
}

bool EmbreeScene::occluded(const Vec3& origin, const Vec3& direction, double tNear, double tFar,
                           const RayFilter& filter) const {
    if (!(tFar > tNear)) return false;
    Impl::FilterContext fc;
    impl_->initContext(fc, filter, origin);
    RTCRay ray;
    Impl::fillRay(ray, glm::vec3(origin - impl_->origin), glm::vec3(direction), float(std::max(tNear, 0.0)),
                  toFloatLimit(tFar));
    rtcOccluded1(impl_->rtc, &fc.context, &ray);
    return ray.tfar == -std::numeric_limits<float>::infinity();
}

SurfacePoint EmbreeScene::surface(const RayHit& hit) const {
    const Mesh& mesh = impl_->scene.meshes[hit.mesh];
    const glm::uvec3 idx = mesh.triangles[hit.triangle];
    const Triangle3 p = mesh.triangle(hit.triangle);
    const double b0 = 1.0 - hit.b1 - hit.b2;
    SurfacePoint s;
    // Relative to corner 0, so a tiny triangle far out keeps its digits.
    s.position = p[0] + hit.b1 * (p[1] - p[0]) + hit.b2 * (p[2] - p[0]);
    const Vec3 an = glm::cross(p[1] - p[0], p[2] - p[0]);
    const double len = glm::length(an);
    s.geometricNormal = len > 0 ? an / len : Vec3(0.0, 0.0, 1.0);
    s.shadingNormal = s.geometricNormal;
    if (mesh.normals.size() == mesh.positions.size()) {
        const Vec3 n = b0 * mesh.normals[idx.x] + hit.b1 * mesh.normals[idx.y] + hit.b2 * mesh.normals[idx.z];
        const double nl = glm::length(n);
        if (nl > 0 && std::isfinite(nl)) s.shadingNormal = n / nl;
    }
    s.material = mesh.materials[hit.triangle];
    if (!mesh.texcoords.empty()) {
        const Vec2 t0 = mesh.texcoords[idx.x];
        s.texcoord = t0 + hit.b1 * (mesh.texcoords[idx.y] - t0) + hit.b2 * (mesh.texcoords[idx.z] - t0);
        s.hasTexcoord = true;
    }
    return s;
}

int EmbreeScene::lightOf(uint32_t mesh, uint32_t triangle) const {
    return impl_->lightIds[mesh][triangle] - 1;
}

double EmbreeScene::rayOffset(const Vec3& p) const {
    const Vec3 r = glm::abs(p - impl_->origin);
    return kSceneOffset * impl_->sceneSize + kMagnitudeOffset * std::max(r.x, std::max(r.y, r.z));
}

Vec3 EmbreeScene::spawnPoint(const Vec3& p, const Vec3& n, const Vec3& towards) const {
    const double side = glm::dot(n, towards) >= 0 ? 1.0 : -1.0;
    return p + (side * rayOffset(p)) * n;
}

}  // namespace ml
