#include "SamplerOptions.h"

#include "core/Error.h"
#include "gpu_sampling/gl/GlContext.h"

#include <algorithm>

namespace ml {

void declareDirectOptions(Options& o) {
    o.value("method", "NAME", "direct light: jittered, regular, query or exact", std::string("jittered"));
    o.value("estimator", "NAME", "cv (exact unoccluded minus sampled occlusion) or plain", std::string("cv"));
    o.value("image-size", "N", "sampling image side, pixels", std::string("64"));
    o.value("bits", "N", "jittered tests per pixel: 1, 4, 8, 16 or 32", std::string("8"));
    o.value("passes", "K", "estimates averaged per point", std::string("1"));
    o.value("cpu-coverage", "N",
            "a pair whose sampling images hold at most N occluder triangles has its occluded samples decided on the "
            "CPU, not rasterised (cv estimator, planar lights; 0: rasterise them all)",
            concat(DirectChoice::kCpuCoverageTriangles));
    o.value("seed", "N", "random seed; the same seed repeats bit for bit", std::string("1"));
    o.value("gl", "BACKEND", "OpenGL back end: auto, osmesa or egl", std::string("auto"));
}

DirectChoice readDirectOptions(const Options& o) {
    DirectChoice c;
    const std::string method = o.str("method");
    c.exact = method == "exact";
    if (!c.exact) c.sampler.method = parseDirectMethod(method);
    c.sampler.estimator = parseDirectEstimator(o.str("estimator"));
    c.sampler.imageSize = o.integer("image-size", 4, 1024);
    c.sampler.bits = o.integer("bits", 1, 32);
    c.sampler.cpuCoverageTriangles = o.integer("cpu-coverage", 0, 1 << 20);
    c.sampler.validate();
    c.passes = o.integer("passes", 1, 1 << 20);
    c.seed = o.seed("seed");
    c.backend = parseGlBackend(o.str("gl"));
    if (c.backend == GlBackend::Glfw) throw InputError("--gl glfw opens a window: use osmesa, egl or auto");
    return c;
}

void declareIndirectOptions(Options& o) {
    const GatherSettings g;
    const BounceCountSettings b;
    o.value("bounces", "N", "indirect bounces (default: from the albedo light meets, see --indirect-tolerance)");
    o.value("indirect-tolerance", "F", "enough bounces to leave less than F of the radiance missing",
            concat(b.missingFraction));
    o.value("max-bounces", "N", "at most N bounces whatever the albedo", concat(b.maxBounces));
    o.value("indirect-method", "NAME",
            "the hemispherical gather: auto (chosen from the scene, plan says which and why), raytrace "
            "(--gather-size^2/4 Embree rays reading the cache where they land: consistent), slices (the paper's "
            "voxel slices), slice-quads (one quad per slice face), raymarch (the voxels as a 3D texture), "
            "fisheye-triangles, perspective (one 160-degree image), hemicube (the proxy's triangles at --voxels, "
            "image --gather-size), volume (an irradiance volume of SH probes, --probes, --probe-face), lpv (light "
            "propagated through a voxel grid with occlusion, --lpv-cells)"
            "; vpl: virtual point lights with negative lights for their occlusion (--vpls)",
            std::string("auto"));
    o.value("voxels", "N", "voxel slices: N voxels along the scene's longest side (32..128 typical)",
            concat(g.resolution));
    o.value("gather-size", "N", "fish-eye gather image N x N pixels", concat(g.imageSize));
    o.value("indirect-edge", "F",
            "the bounce meshes' base edges at most F x the scene diagonal (default: for raytrace the scene's mean "
            "free path 4V/S over 7.5, within 1/16..1/32, with fewer rays as it is finer; 1/8 for the voxel "
            "gathers); plan says which (cache/README.md)");
    o.value("contact-cuts", "F",
            "the bounce meshes are cut along the edges of surfaces hanging (between 1e-3 of the scene and F x the "
            "edge's length) in front of them, with lines along their penumbra (cache/ContactCuts.h); 0: no cuts",
            concat(IndirectSettings::defaultCache().contactCloseness));
    o.value("near-voxels", "K", "triangles, not slices, within K voxels of the gathering point", concat(g.nearVoxels));
    o.value("slice-supersample", "S", "S x S sub-texels per slice texel", concat(g.sliceSupersample));
    o.value("glow-ratio", "F",
            "area lights dimmer than F x the brightest light's radiance (glowing walls) reach the scene through "
            "bounce 1's ray gather instead of being sampled as lights; 0: sample every light",
            concat(IndirectChoice().glowRatio));
    const IrradianceVolumeSettings v;
    o.value("probes", "N", "volume: N probes along the scene's longest side (4..16 typical)", concat(v.probes));
    o.value("probe-face", "N", "volume: each probe's cube map N x N rays per face", concat(v.faceSize));
    o.value("lpv-cells", "N", "lpv: N cells along the scene's longest side (8..24 typical; finer is slower, not more accurate)",
            concat(PropagationVolumeSettings().cells));
    o.value("vpls", "N", "vpl: N virtual point lights per bounce, and N/2 negative ones (100..1000 typical)",
            concat(VirtualPointLightSettings().lights));
}

IndirectChoice readIndirectOptions(const Options& o) {
    IndirectChoice c;
    c.enabled = !o.isSet("direct-only");
    c.method = o.str("indirect-method");
    std::vector<std::string> names = indirectMethodNames();
    names.insert(names.begin(), "auto");
    if (std::find(names.begin(), names.end(), c.method) == names.end()) {
        std::string list;
        for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
        throw InputError(concat("--indirect-method '", c.method, "': unknown (", list, ")"));
    }
    c.gather.resolution = o.integer("voxels", 4, 512);
    c.gather.imageSize = o.integer("gather-size", 4, 1024);
    c.gatherSizeSet = o.given("gather-size");
    c.gather.nearVoxels = o.integer("near-voxels", 0, 8);
    c.gather.sliceSupersample = o.integer("slice-supersample", 1, 8);
    c.gather.validate();
    c.volume.probes = o.integer("probes", 1, 64);
    c.volume.faceSize = o.integer("probe-face", 2, 128);
    c.volume.validate();
    c.lpv.cells = o.integer("lpv-cells", 2, 128);
    c.lpv.validate();
    c.vpl.lights = o.integer("vpls", 1, 65536);
    c.vpl.validate();
    c.glowRatio = o.number("glow-ratio", 0, 0.999);
    if (o.has("indirect-edge")) c.baseEdge = o.number("indirect-edge", 1e-4, 1.0);
    c.solver.cache.contactCloseness = o.number("contact-cuts", 0, 1);
    c.bounces.missingFraction = o.number("indirect-tolerance", 1e-9, 0.999);
    c.bounces.maxBounces = o.integer("max-bounces", 1, 256);
    if (o.has("bounces")) c.bounces.forced = o.integer("bounces", 0, 256);
    c.bounces.validate();
    return c;
}

}  // namespace ml
