#include "RayGather.h"

#include "RadianceProxy.h"
#include "core/Error.h"
#include "core/MeshUtil.h"
#include "core/Random.h"
#include "core/ScrambledSobol.h"
#include "core/raytrace/EmbreeScene.h"
#include "core/raytrace/SpecularChain.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>

namespace ml {

void RayGatherSettings::validate() const {
    if (rays < 4 || rays > 65536) throw InputError(concat("ray gather: ", rays, " rays is not within 4..65536"));
}

RayGather::RayGather(const Scene& scene, const RayGatherSettings& settings)
    : scene_(scene), settings_(settings), rays_(std::make_unique<EmbreeScene>(scene)) {
    settings_.validate();
    closed_ = closedMeshesOf(scene);
    emitting_ = emittingFacesOf(scene, settings_.gatheredLights);
}

EmittingFaces emittingFacesOf(const Scene& scene, const std::vector<char>& gatheredLights) {
    EmittingFaces faces;
    for (size_t l = 0; l < scene.lights.size() && l < gatheredLights.size(); ++l) {
        const Light& light = scene.lights[l];
        if (!gatheredLights[l] || light.punctual()) continue;
        if (faces.empty()) {
            faces.resize(scene.meshes.size());
            for (size_t m = 0; m < scene.meshes.size(); ++m) faces[m].assign(scene.meshes[m].triangles.size(), 0);
        }
        for (uint32_t t : light.triangles) faces[light.mesh][t] = 1;
    }
    return faces;
}

std::vector<char> closedMeshesOf(const Scene& scene) {
    std::vector<char> closed;
    for (const Mesh& m : scene.meshes) closed.push_back(isClosedMesh(m) ? 1 : 0);
    return closed;
}

RayGather::~RayGather() = default;

std::string RayGather::name() const { return "raytrace"; }

void RayGather::setSource(size_t slot, const std::vector<IrradianceMeshCopy>& irradiance, double importance) {
    const auto start = std::chrono::steady_clock::now();
    if (slot >= sources_.size()) sources_.resize(slot + 1);
    auto source = std::make_unique<Source>();
    source->meshes = irradiance;
    // Each hit looks up every source mesh (one per light with a mesh
    // there, plus the shared one), all in one grid: with many lights the
    // lookups, not the ray, are what a gather costs (the office's first
    // 100,000 samples: 0.27 ms per gather, 0.45 ms before the lookup passed
    // over faces by their barycentrics instead of finding each one's
    // closest point). Cells of 1/128 of the scene: a lookup still scans a
    // few dozen faces of the refined direct meshes. Under 192 panels
    // (render office:panels=16x12,panelsize=0.4 --width 320 --height 180
    // --time 20), cells of 1/64, 1/128, 1/256: 0.034, 0.032, 0.028 ms per
    // gather, 173, 196, 348 MB held.
    const double diagonal = scene_.bounds.diagonal() > 0 ? scene_.bounds.diagonal() : 1.0;
    std::vector<const IrradianceMeshCopy*> meshes;
    for (const IrradianceMeshCopy& m : source->meshes) {
        meshes.push_back(&m);
        source->bytes += m.positions.size() * (2 * sizeof(Vec3) + sizeof(Rgb) + 4) + m.triangles.size() * 12;
    }
    source->lookup = std::make_unique<MeshIrradianceLookup>(meshes, diagonal / 128, 1e-5 * diagonal,
                                                            MeshIrradianceLookup::Interpolation::CurvatureCorrected);
    source->pointers.push_back(source->lookup.get());
    source->bytes += source->lookup->memoryBytes();
    const double rays = std::max(16.0, settings_.rays * std::clamp(importance, 0.0, 1.0));
    source->strata = std::max(4, int(std::lround(std::sqrt(rays))));
    sources_[slot] = std::move(source);
    stats_.buildSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    size_t held = 0;
    for (const auto& s : sources_)
        if (s) held += s->bytes;
    stats_.sourceBytes = held;
    stats_.source = concat(sources_[slot]->meshes.size(), " meshes looked up, ", sources_[slot]->strata *
                                                                                   sources_[slot]->strata,
                           " rays per gather");
}

void RayGather::releaseSource(size_t slot) {
    if (slot < sources_.size()) sources_[slot].reset();
}

Rgb gatherCachedRadiance(const Scene& scene, const EmbreeScene& rays, const std::vector<char>& closedMeshes,
                         const std::vector<const MeshIrradianceLookup*>& lookups, const Vec3& x, const Vec3& nIn,
                         int strata, const GatherDraw& draw, const EmittingFaces* emitting, double* reach,
                         double* variance) {
    if (emitting && emitting->empty()) emitting = nullptr;
    const Vec3 n = glm::normalize(nIn);
    Vec3 t, b;
    orthonormalBasis(n, t, b);
    Vec3 origin = rays.spawnPoint(x, n, n);
    // On an edge or in a corner a surface meets x's own: rays leaving along
    // it would start on its plane and slip past it. So where a surface faces
    // the point within ε along a tangent, the origin moves ε away from it,
    // into its own surface (as NearField nudges the voxel gathers' eye).
    const double eps = 1e-5 * std::max(scene.bounds.diagonal(), 1e-30);
    RayFilter facing;
    facing.frontOnly = true;
    const Vec3 start = origin;
    for (const Vec3& d : {t, -t, b, -b}) {
        RayHit probe;
        if (rays.intersect(start - eps * d, d, 0.0, 2 * eps, probe, facing)) origin -= eps * d;
    }
    const int s = strata;
    const SpecularChainSettings chain;
    Rgb sum(0.0);
    double lumSum = 0, lumSquares = 0;  // Σ and Σ² of the rays' luminance, for *variance
    double inverseDistances = 0;  // Σ 1/t over first hits (a miss: 0)
    uint32_t state = hash32(draw.seed ^ 0x2545f491u);
    const auto next = [&state] {
        state = hash32(state + 0x9e3779b9u);
        return (state >> 8) * (1.0 / 16777216.0);
    };
    // A stream per ray count: a vertex's first-pass gathers (fewer rays)
    // and later ones each number their own blocks.
    const ScrambledSobol2D sequence(hash32(draw.stream + 0x9e3779b9u * uint32_t(s)));
    uint32_t block = 1;
    while (block < uint32_t(s * s)) block <<= 1;
    const uint32_t first = draw.block * block;
    for (int k = 0; k < s * s; ++k) {
        // Cosine-weighted by Malley's method.
        const std::array<double, 2> u = sequence(first + uint32_t(k));
        const Vec3 w = cosineDirection(n, t, b, u[0], u[1]);
        Rgb ray(0.0);
        // Through mirrors and glass to the diffuse surface behind, each
        // surface on the way read on the side the ray arrives on (a
        // closed object's inside is black); a smooth layer's own Kd too.
        followSpecularChain(rays, closedMeshes, origin, w, chain, next, [&](const ChainVertex& v) {
            // The first surface met, whatever it is: a mirror's
            // reflection changes with x at its distance too. Not nearer
            // than the origin's nudge, which bounds 1/t.
            if (v.layers == 0) inverseDistances += 1 / std::max(v.hit.t, eps);
            Rgb e(0.0);
            for (const MeshIrradianceLookup* lookup : lookups) e += lookup->at(v.surface.position, v.side);
            ray += v.weight * (v.surface.kd(scene) * e);  // the texture's Kd at the hit, as the path tracer takes it
            // A gathered light's face seen from its emitting side: π Le
            // in this sum's units (π/N Σ L).
            if (emitting && (*emitting)[v.hit.mesh][v.hit.triangle] &&
                glm::dot(v.side, v.surface.geometricNormal) > 0)
                ray += v.weight * (kPi * v.surface.ke(scene));
        });
        sum += ray;
        const double y = luminance(ray);
        lumSum += y, lumSquares += y * y;
    }
    // The rays as independent draws: their spread over N(N − 1).
    const double count = double(s * s);
    if (variance) *variance = varianceOfMean(lumSum, lumSquares, count);
    if (reach)
        *reach = inverseDistances > 0 ? double(s * s) / inverseDistances : std::numeric_limits<double>::infinity();
    // Cosine-weighted: E = π/N Σ Lo = π/N Σ Kd/π E = 1/N Σ Kd E.
    return sum / double(s * s);
}

Rgb RayGather::estimate(size_t slot, const Vec3& x, const Vec3& n, uint32_t seed) {
    return estimateSample(slot, x, n, seed).irradiance;
}

VertexSample RayGather::estimateSample(size_t slot, const Vec3& x, const Vec3& n, uint32_t seed) {
    return gather(slot, x, n, GatherDraw(seed));
}

VertexSample RayGather::estimateRequest(size_t slot, const SampleRequest& r) {
    if (!r.numbered) return gather(slot, r.x, r.n, GatherDraw(r.seed));
    return gather(slot, r.x, r.n, GatherDraw(r.seed, r.stream, r.index));
}

VertexSample RayGather::gather(size_t slot, const Vec3& x, const Vec3& n, const GatherDraw& draw) {
    ML_ASSERT(slot < sources_.size() && sources_[slot], "ray gather: source ", slot, " is not built");
    const auto start = std::chrono::steady_clock::now();
    const Source& source = *sources_[slot];
    // Bounce 1 (source 0, direct light) also reads the gathered lights.
    VertexSample result;
    result.irradiance = gatherCachedRadiance(scene_, *rays_, closed_, source.pointers, x, n, source.strata, draw,
                                             slot == 0 ? &emitting_ : nullptr, &result.reach, &result.ownVariance);
    // Its rays: a first pass's cheaper gather (fewer rays) weighs less in a
    // vertex's mean and counts as noisier (VertexStats).
    result.work = double(source.strata) * source.strata;
    stats_.estimates++;
    stats_.estimateSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
}

std::optional<std::vector<Rgb>> RayGather::seenAlbedo(const IrradianceMeshCopy& mesh, size_t begin, size_t end,
                                                      int rays, uint32_t seed) {
    ML_ASSERT(begin <= end && end <= mesh.positions.size(), "seen albedo of vertices ", begin, "..", end, " of ",
              mesh.positions.size());
    IrradianceMeshCopy ones;
    ones.positions = mesh.positions;
    ones.normals = mesh.normals;
    ones.triangles = mesh.triangles;
    ones.irradiance.assign(mesh.positions.size(), Rgb(1.0));
    const double diagonal = scene_.bounds.diagonal() > 0 ? scene_.bounds.diagonal() : 1.0;
    // Linear: a constant needs no curvature.
    const MeshIrradianceLookup lookup(ones, diagonal / 64, 1e-5 * diagonal,
                                      MeshIrradianceLookup::Interpolation::Linear);
    const std::vector<const MeshIrradianceLookup*> lookups{&lookup};
    const int strata = std::max(2, int(std::lround(std::sqrt(double(std::max(rays, 1))))));
    std::vector<Rgb> seen(end - begin, Rgb(0.0));
    for (size_t v = begin; v < end; ++v)
        seen[v - begin] = gatherCachedRadiance(scene_, *rays_, closed_, lookups, mesh.positions[v], mesh.normals[v],
                                               strata, GatherDraw(seedFor(seed, 0x5eeda1bu, uint32_t(v))));
    return seen;
}

IndirectStats RayGather::stats() const { return stats_; }

}  // namespace ml
