#include "RayTracedLightSampler.h"

#include "core/raytrace/PunctualShadow.h"

#include "Jitter.h"
#include "LightFrustum.h"
#include "core/Error.h"
#include "core/raytrace/EmbreeScene.h"
#include "core/reference/Lambert.h"

namespace ml {


RayTracedLightSampler::RayTracedLightSampler(const EmbreeScene& rays, const DirectSamplerSettings& settings)
    : rays_(rays), settings_(settings), sceneSize_(std::max(rays.scene().bounds.diagonal(), 1e-300)),
      emitters_(EmitterTexture::forLights(rays.scene())) {
    settings_.validate();
    if (settings_.method == DirectMethod::OcclusionQuery)
        throw InputError("the ray-traced sampler has no occlusion-query scheme: use jittered or regular");
}

DirectSample RayTracedLightSampler::sample(size_t lightIndex, const Vec3& x, const Vec3& nIn, uint32_t seed) const {
    const Scene& scene = rays_.scene();
    ML_ASSERT(lightIndex < scene.lights.size(), "light ", lightIndex);
    DirectSample result;
    const Light& light = scene.lights[lightIndex];
    const Vec3 n = glm::normalize(nIn);
    if (!isFinite(x) || !isFinite(n)) throw InputError(concat("non-finite receiver point or normal"));
    if (light.punctual()) {
        // One shadow ray is exact (PunctualShadow.h); the "solid angles"
        // become the light's visibility, 1 or 0, as a visible fraction.
        const PunctualSample p = punctualIrradiance(rays_, lightIndex, x, n);
        result.irradiance = p.irradiance;
        result.unoccluded = p.lit ? 1 : 0;
        result.cosineSolidAngle = p.visible ? 1 : 0;
        return result;
    }
    const double lift = samplingEyeLift(light, x, settings_.eyeOffset, sceneSize_);
    const Vec3 eye = x + n * lift;
    const std::vector<Polygon3> pieces = visibleLightPieces(light, eye, n);
    if (pieces.empty()) return result;

    // Lambert at the receiver itself, as the raster sampler's control variate.
    const double exactUnoccluded = unoccludedCosineSolidAngle(light, x, n);

    const std::vector<SamplingFrustum> frusta =
        samplingFrusta(light, pieces, eye, settings_.maxHalfAngleDegrees);
    const double nearDistance = std::max(0.5 * lift, 1e-12 * sceneSize_);
    const double tolerance = settings_.planeTolerance * sceneSize_;
    const bool jitterOn = settings_.method == DirectMethod::Jittered;
    const int bits = jitterOn ? settings_.bits : 1;
    int strataX = 1, strataY = 1;
    jitter::strata(bits, strataX, strataY);
    const int size = settings_.imageSize;
    const bool planar = light.planar;
    const double eyeHeight = glm::dot(light.normal, eye - light.centroid);  // above the light's plane
    RayFilter occluders;
    occluders.skipLight = int(lightIndex);
    RayFilter lightFaces;
    lightFaces.onlyLight = int(lightIndex);
    lightFaces.frontOnly = true;
    const EmitterTexture& texture = emitters_[lightIndex];

    double lightWeight = 0, occludedWeight = 0;
    Rgb texturedLight(0.0), texturedOccluded(0.0);
    for (size_t k = 0; k < frusta.size(); ++k) {
        const SamplingFrustum& f = frusta[k];
        const uint32_t frustumSeed = jitter::hash(seed + uint32_t(k) * 0x9e3779b9u);
        const std::vector<WindowPiece> window = planar ? windowPieces(f, pieces) : std::vector<WindowPiece>{};
        const double pw = (f.rightEdge - f.left) / size, ph = (f.top - f.bottom) / size;
        const double nx = glm::dot(n, f.right), ny = glm::dot(n, f.up), nz = glm::dot(n, f.forward);
        double lightSum = 0, occludedSum = 0;
        Rgb texturedLightSum(0.0), texturedOccludedSum(0.0);
        for (int j = 0; j < size; ++j)
            for (int i = 0; i < size; ++i) {
                const uint32_t pixel = uint32_t(j * size + i);
                for (int bit = 0; bit < bits; ++bit) {
                    float ju, jv;
                    jitter::position(pixel, uint32_t(bit), frustumSeed, strataX, strataY, jitterOn, ju, jv);
                    const double u = f.left + (i + double(ju)) * pw, v = f.bottom + (j + double(jv)) * ph;
                    const Vec3 d = f.direction(u, v);  // depth along the ray = its parameter
                    double tFar = 0;
                    if (planar) {
                        bool on = false;
                        for (const WindowPiece& wp : window)
                            if (wp.contains(u, v)) {
                                on = true;
                                break;
                            }
                        if (!on) continue;
                        // Occluders count up to planeTolerance in front of the light's plane.
                        const double towardsPlane = -glm::dot(light.normal, d);
                        tFar = towardsPlane > 0 ? (eyeHeight - tolerance) / towardsPlane : kInf;
                    } else {
                        RayHit hit;
                        if (!rays_.intersect(eye, d, nearDistance, kInf, hit, lightFaces)) continue;
                        tFar = hit.t;
                    }
                    ++result.lightSamples;
                    const double cosine = nx * u + ny * v + nz;
                    const double r2 = 1.0 + u * u + v * v;
                    const double w = cosine > 0 ? cosine / (r2 * r2) : 0.0;
                    lightSum += w;
                    const Rgb tw = texture.textured() && w > 0 ? w * texture.weightAlong(eye, d) : Rgb(w);
                    texturedLightSum += tw;
                    if (rays_.occluded(eye, d, nearDistance, tFar, occluders)) {
                        occludedSum += w;
                        texturedOccludedSum += tw;
                    } else {
                        ++result.visibleSamples;
                    }
                }
            }
        const double sampleArea = pw * ph / bits;
        lightWeight += lightSum * sampleArea;
        occludedWeight += occludedSum * sampleArea;
        texturedLight += texturedLightSum * sampleArea;
        texturedOccluded += texturedOccludedSum * sampleArea;
    }
    result.frusta = uint32_t(frusta.size());

    double e = 0;
    const bool controlVariate = settings_.estimator == DirectEstimator::ControlVariate && planar;
    if (controlVariate) {
        result.unoccluded = exactUnoccluded;
        e = result.visibleSamples == 0 ? 0.0 : std::max(0.0, exactUnoccluded - occludedWeight);
    } else {
        result.unoccluded = lightWeight;
        e = lightWeight - occludedWeight;
    }
    result.cosineSolidAngle = e;
    result.irradiance = light.radiance * e;
    if (texture.textured())
        result.irradiance = texturedIrradiance(light.radiance, controlVariate, exactUnoccluded, lightWeight,
                                               texturedLight, texturedOccluded, result.visibleSamples > 0);
    return result;
}

}  // namespace ml
