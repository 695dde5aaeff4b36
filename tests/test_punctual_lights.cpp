// Punctual lights (point, spot, directional): the inverse-square law and
// the glTF spot falloff against their formulas, the shadow ray every sampler
// and the path tracer share, and a closed cube lit by an isotropic point,
// whose mean wall illuminance is known exactly: Φ / (S (1 − ρ)).
#include "TempDirTest.h"
#include "TestSamplers.h"
#include "TestScenes.h"
#include "cache/IndirectSolver.h"
#include "cache/IrradianceCache.h"
#include "cache/LightCoverage.h"
#include "cache/SharedLightSampler.h"
#include "core/Random.h"
#include "core/CandelaTable.h"
#include "core/image/Photometry.h"
#include "core/loaders/LuminaireLayout.h"
#include "core/raytrace/BounceCount.h"
#include "core/raytrace/EmbreeScene.h"
#include "core/raytrace/PathTracer.h"
#include "core/raytrace/PunctualShadow.h"
#include "gpu_sampling/SamplerFactory.h"
#include "gpu_sampling/gl/GlContext.h"
#include "gpu_sampling/indirect/SliceGather.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>

using namespace ml;
using namespace ml::test;

namespace {

// A white isotropic point light of `candela` at p.
Light pointLight(const std::string& name, const Vec3& p, double candela) {
    Light l;
    l.name = name;
    l.kind = LightKind::Point;
    l.emission.position = p;
    l.emission.intensity = Rgb(candela / kRadianceEfficacy);
    return l;
}

// A grey floor (10 × 10 at y = 0, facing up) and the lights given.
Scene floorWith(std::vector<Light> lights, double metresPerUnit = 1, double size = 10) {
    Scene scene;
    scene.name = "floor";
    scene.materials = {Material::diffuse("grey", Rgb(0.5))};
    scene.meshes = {quadMesh("floor", 0, Vec3(-0.5 * size, 0, -0.5 * size), size * kZ, size * kX)};
    scene.metresPerUnit = metresPerUnit;
    scene.lights = std::move(lights);
    scene.finalize();
    return scene;
}

void expectNear(const Vec3& a, const Vec3& b, double tol = 1e-12) {
    EXPECT_LE(glm::length(a - b), tol) << "(" << a.x << ", " << a.y << ", " << a.z << ") vs (" << b.x << ", " << b.y
                                       << ", " << b.z << ")";
}

double lux(const Rgb& e, const char* photometry = "radiance") { return photometryNamed(photometry).luminous(e); }

}  // namespace

// --- The formulas ------------------------------------------------------------------

// The check: 1000 cd at 1 m reads 1000 lx (either luminance
// convention: their weights sum to 1), and off axis E = I cos θ / d².
TEST(PunctualLight, InverseSquareAndCosineInLux) {
    const Scene scene = floorWith({pointLight("bulb", Vec3(0, 1, 0), 1000)});
    ASSERT_EQ(scene.lights.size(), 1u);
    const Light& l = scene.lights[0];
    const PunctualIncidence below = punctualIncidence(l, Vec3(0.0), kY);
    EXPECT_NEAR(lux(below.irradiance), 1000, 1e-9);
    EXPECT_NEAR(lux(below.irradiance, "rec709"), 1000, 1e-9);
    EXPECT_NEAR(below.distance, 1, 1e-15);
    const PunctualIncidence off = punctualIncidence(l, Vec3(1, 0, 0), kY);
    EXPECT_NEAR(lux(off.irradiance), 1000 * (1 / std::sqrt(2.0)) / 2, 1e-9);
    // Behind the receiver: nothing.
    EXPECT_EQ(lux(punctualIncidence(l, Vec3(0.0), -kY).irradiance), 0);
    // Power: 4π I, and flux in lumens 4π × 1000.
    EXPECT_NEAR(photometryNamed("radiance").luminous(l.power()), 4 * kPi * 1000, 1e-9);
}

// A scene in millimetres: the same light 1 m (1000 units) away gives the same lux.
TEST(PunctualLight, MetresPerUnitScalesTheInverseSquareLaw) {
    const Scene mm = floorWith({pointLight("bulb", Vec3(0, 1000, 0), 1000)}, 0.001, 10000);
    EXPECT_NEAR(lux(punctualIncidence(mm.lights[0], Vec3(0.0), kY).irradiance), 1000, 1e-9);
    // Its power stays commensurable with area lights' (W·unit²/m²): watts × 1e6.
    EXPECT_NEAR(mm.lights[0].power().g * 1e-6, 4 * kPi * 1000 / kRadianceEfficacy, 1e-9);
}

// glTF KHR_lights_punctual's spot: t² with t = clamp((cos − cos outer) /
// (cos inner − cos outer)); and the profile's integral, numerically.
TEST(PunctualLight, SpotFalloffIsGltfsAndItsPowerItsIntegral) {
    IntensityProfile p;
    p.shape = IntensityProfile::Shape::Spot;
    const double inner = 0.3, outer = 0.6;
    p.cosInner = std::cos(inner);
    p.cosOuter = std::cos(outer);
    for (double a = 0; a <= kPi; a += 0.01) {
        const double t = std::clamp((std::cos(a) - std::cos(outer)) / (std::cos(inner) - std::cos(outer)), 0.0, 1.0);
        EXPECT_NEAR(p(std::cos(a), 0), t * t, 1e-12) << "at " << a << " rad";
    }
    double integral = 0;
    const int steps = 200000;
    for (int i = 0; i < steps; ++i) {  // ∫ over μ = cos γ, midpoint rule
        const double mu = -1 + 2 * (i + 0.5) / steps;
        integral += p(mu, 0) * 2 / steps;
    }
    EXPECT_NEAR(p.solidAngle(), 2 * kPi * integral, 1e-6);
    IntensityProfile iso;
    EXPECT_NEAR(iso.solidAngle(), 4 * kPi, 1e-15);
}

// A candela table as a profile: relative to its peak, C measured from the
// reference direction around the axis.
TEST(PunctualLight, TableProfileFollowsTheTableAroundTheAxis) {
    auto table = std::make_shared<CandelaTable>();
    table->source = "test";
    table->gamma = {0, 90, 180};
    table->c = {0, 90, 180, 270};
    // I = 100 at nadir, at 90° it depends on C: 40, 20, 40, 20; 0 upward.
    table->candela = {100, 40, 0, 100, 20, 0, 100, 40, 0, 100, 20, 0};
    Light l = pointLight("lum", Vec3(0, 2, 0), 1);
    l.emission.intensity = Rgb(100.0);
    l.emission.axis = Vec3(0, -1, 0);
    l.emission.reference = Vec3(1, 0, 0);
    l.emission.profile.shape = IntensityProfile::Shape::Table;
    l.emission.profile.table = table;
    const Scene scene = floorWith({l});
    const PunctualEmission& e = scene.lights[0].emission;
    EXPECT_NEAR(e.intensityToward(Vec3(0, -1, 0)).r, 100, 1e-12);
    EXPECT_NEAR(e.intensityToward(Vec3(1, 0, 0)).r, 40, 1e-12);   // C0
    EXPECT_NEAR(e.intensityToward(Vec3(-1, 0, 0)).r, 40, 1e-12);  // C180
    EXPECT_NEAR(e.intensityToward(Vec3(0, 0, 1)).r, 20, 1e-12);   // C90 or C270
    EXPECT_NEAR(e.intensityToward(Vec3(0, 1, 0)).r, 0, 1e-12);
    EXPECT_NEAR(scene.lights[0].power().r, table->flux() / 100 * 100, 1e-9);
}

// The singularity (PunctualLight.h): at the light E = 0; a light lying on the
// floor lights the floor edge-on (0); 1e-6 m above it, I/d², huge but finite.
TEST(PunctualLight, AtTheLightAndOnItsSurfaceStayFinite) {
    const Scene on = floorWith({pointLight("on", Vec3(0.0), 1000)});
    EXPECT_EQ(lux(punctualIncidence(on.lights[0], Vec3(0.0), kY).irradiance), 0);
    EXPECT_EQ(lux(punctualIncidence(on.lights[0], Vec3(1, 0, 0), kY).irradiance), 0);
    const Scene near = floorWith({pointLight("near", Vec3(0, 1e-6, 0), 1000)});
    const double e = lux(punctualIncidence(near.lights[0], Vec3(0.0), kY).irradiance);
    EXPECT_TRUE(std::isfinite(e));
    EXPECT_NEAR(e / 1e15, 1, 1e-6);
    // The path tracer and the shadow ray agree there, and nothing hides a
    // light lying on the floor from the floor's own points (they get 0 by
    // the cosine, not by a ray lost in the surface).
    const EmbreeScene rays(near);
    const PunctualSample s = punctualIrradiance(rays, 0, Vec3(0.0), kY);
    EXPECT_TRUE(s.visible);
    EXPECT_NEAR(lux(s.irradiance) / 1e15, 1, 1e-6);
    PathTracerSettings ps;
    ps.maxDepth = 1;
    ps.threads = 1;
    const PathTracer tracer(rays, ps);
    EXPECT_NEAR(lux(tracer.irradiance(Vec3(0.0), kY, 4, 0).direct) / 1e15, 1, 1e-6);
}

// --- The shadow ray, in every sampler --------------------------------------------------

namespace {

// The floor, a 1 × 1 occluder at y = 1 over [−0.5, 0.5]², a point light at
// y = 2 above its centre and a directional light coming down at 45° in x.
Scene shadowScene() {
    Scene scene;
    scene.name = "shadow";
    scene.materials = {Material::diffuse("grey", Rgb(0.5))};
    scene.meshes = {quadMesh("floor", 0, Vec3(-5, 0, -5), 10.0 * kZ, 10.0 * kX),
                    quadMesh("occluder", 0, Vec3(-0.5, 1, -0.5), kZ, kX)};
    Light sun;
    sun.name = "sun";
    sun.kind = LightKind::Directional;
    sun.emission.axis = glm::normalize(Vec3(1, -1, 0));
    sun.emission.intensity = Rgb(2.0);
    scene.lights = {pointLight("bulb", Vec3(0, 2, 0), 179), sun};
    scene.finalize();
    return scene;
}

}  // namespace

TEST(PunctualSampler, OneShadowRayIsTheExactAnswerForEveryMethod) {
    const Scene scene = shadowScene();
    ASSERT_EQ(scene.lights.size(), 2u);
    for (bool exact : {false, true}) {
        DirectChoice choice;
        choice.exact = exact;
        choice.backend = GlBackend::OsMesa;
        ConfiguredDirectSampler sampler(scene, choice);
        // Under the occluder's centre the bulb is hidden. The sun comes
        // down at 45° from x < 0: the occluder's shadow falls on x ∈ [0.5,
        // 1.5], so (1, 0, 0) is in it and (3, 0, 0) is not.
        const VertexSample hidden = sampler.sample(0, Vec3(0, 0, 0), kY, 1);
        EXPECT_EQ(hidden.irradiance.g, 0);
        EXPECT_EQ(hidden.visibility, 0);
        EXPECT_FALSE(hidden.partial);
        // Beside it (x = 3): I cos/d² with d² = 9 + 4, cos = 2/√13.
        const VertexSample lit = sampler.sample(0, Vec3(3, 0, 0), kY, 1);
        EXPECT_NEAR(lit.irradiance.g, 1.0 * (2 / std::sqrt(13.0)) / 13, 1e-12);
        EXPECT_EQ(lit.visibility, 1);
        EXPECT_EQ(sampler.sample(1, Vec3(1, 0, 0), kY, 1).irradiance.g, 0);
        EXPECT_NEAR(sampler.sample(1, Vec3(3, 0, 0), kY, 1).irradiance.g, 2 / std::sqrt(2.0), 1e-12);
        // Answered without the GPU, and the same in a batch.
        VertexSample cpu;
        EXPECT_TRUE(sampler.sampleWithoutGpu(0, Vec3(3, 0, 0), kY, 1, cpu));
        EXPECT_EQ(cpu.irradiance, lit.irradiance);
        std::vector<SampleRequest> requests;
        for (int i = 0; i < 20; ++i) requests.push_back({size_t(i % 2), Vec3(-4 + 0.4 * i, 0, 0.1 * i), kY, 7});
        std::vector<VertexSample> batch;
        sampler.sampleBatch(requests, batch);
        for (size_t i = 0; i < requests.size(); ++i)
            EXPECT_EQ(batch[i].irradiance, sampler.sample(requests[i].mesh, requests[i].x, requests[i].n, 7).irradiance)
                << "request " << i;
    }
    // The path tracer's direct light is the same number.
    const EmbreeScene rays(scene);
    PathTracerSettings ps;
    ps.maxDepth = 1;
    ps.threads = 1;
    const PathTracer tracer(rays, ps);
    const IrradianceEstimate e = tracer.irradiance(Vec3(3, 0, 0), kY, 8, 0);
    EXPECT_NEAR(e.directPerLight[0].g, 1.0 * (2 / std::sqrt(13.0)) / 13, 1e-12);
    EXPECT_NEAR(e.directPerLight[1].g, 2 / std::sqrt(2.0), 1e-12);
}

// An area light and a point light in one batch: each request answered as
// sample() answers it, the area light by the GPU sampler.
TEST(PunctualSampler, BatchesMixAreaAndPunctualLights) {
    Scene scene;
    scene.name = "mixed";
    scene.materials = {Material::diffuse("lamp", Rgb(0.0), Rgb(5.0)), Material::diffuse("grey", Rgb(0.5))};
    scene.meshes = {unitLight(), floorMesh(), quadMesh("occluder", 1, Vec3(-0.2, 0.5, -0.2), 0.4 * kZ, 0.4 * kX)};
    scene.lights = {pointLight("bulb", Vec3(0.7, 0.8, 0.1), 500)};
    scene.finalize();
    ASSERT_EQ(scene.lights.size(), 2u);
    EXPECT_EQ(scene.lights[0].kind, LightKind::Area);
    EXPECT_EQ(scene.lights[1].kind, LightKind::Point);
    DirectChoice choice;
    choice.backend = GlBackend::OsMesa;
    ConfiguredDirectSampler sampler(scene, choice);
    std::vector<SampleRequest> requests;
    for (int i = 0; i < 24; ++i) requests.push_back({size_t(i % 3 == 0), Vec3(-0.6 + 0.05 * i, 0, 0.02 * i), kY, uint32_t(i)});
    std::vector<VertexSample> batch;
    sampler.sampleBatch(requests, batch);
    ASSERT_EQ(batch.size(), requests.size());
    for (size_t i = 0; i < requests.size(); ++i) {
        const VertexSample one = sampler.sample(requests[i].mesh, requests[i].x, requests[i].n, requests[i].seed);
        EXPECT_EQ(batch[i].irradiance, one.irradiance) << "request " << i;
    }
}

// --- A closed cube lit by an isotropic point -----------------------------------------

namespace {


}  // namespace

// The check: a closed cube of reflectance ρ, an isotropic point of
// flux Φ at its centre. All the light ends on the walls, each reflection
// returns ρ of it, so the mean wall illuminance is Φ / (S (1 − ρ)), S the
// walls' area; direct illuminance at a wall's centre is I/h² exactly.
// Tolerance 2% (the issue's): the bounce count leaves < 1% of the reflected
// light out, and the slice gather of smooth walls errs by about 0.5% (the
// furnace tests); linear interpolation of the direct mesh's I cos/d² (it
// varies ×5 from centre to corner) over cache triangles of 1/16 of a wall
// adds well under 0.5%.
TEST(PunctualCube, MeanWallIlluminanceIsFluxOverAreaTimesOneOverOneMinusRho) {
    const double rho = 0.5, candela = 1000;
    Scene scene = furnaceBox(rho, 0.0);
    scene.lights = {pointLight("bulb", Vec3(0.0), candela)};
    scene.finalize();
    ASSERT_EQ(scene.lights.size(), 1u);
    const double I = candela / kRadianceEfficacy, flux = 4 * kPi * I, area = 6 * 4.0;
    const double expected = flux / (area * (1 - rho));

    const EmbreeScene rays(scene);
    // Direct light at a wall's centre: I/h², h = 1.
    EXPECT_NEAR(punctualIrradiance(rays, 0, Vec3(0, -1, 0), kY).irradiance.g, I, 1e-12);

    CacheSettings cs;
    cs.maxEdgeFraction = 1.0 / 32;
    IrradianceCache direct(scene, cs);
    sampleEveryVertex(direct, [&](size_t l, const Vec3& x, const Vec3& n, uint32_t) {
        return punctualIrradiance(rays, l, x, n).irradiance;
    }, 1, 1);
    Rgb directSum(0.0);
    for (const IrradianceMeshCopy& m : direct.copyMeshes()) directSum += integrate(m);
    EXPECT_NEAR(directSum.g / area, flux / area, 0.005 * flux / area) << "direct light alone: Φ/S";
    const BounceCount plan = countBounces(scene, BounceCountSettings{});
    EXPECT_NEAR(plan.meanAlbedo, rho, 1e-9);
    auto context = createHeadlessContext(GlBackend::OsMesa);
    GatherSettings gs;
    gs.resolution = 32;
    SliceGather gather(*context, scene, gs);
    IndirectSettings is;
    is.bounces = plan.bounces;
    is.albedo = plan.meanAlbedo;
    IndirectSolver solver(scene, is);
    for (int r = 0; r < 4000 && !solver.allFinished(); ++r)
        solver.step(gather, [&] { return direct.copyMeshes(); }, 256, 7, std::nullopt);
    ASSERT_TRUE(solver.allFinished());
    Rgb total = directSum;
    for (const IrradianceMeshCopy& m : solver.copyMeshes()) total += integrate(m);
    EXPECT_NEAR(total.g / area, expected, 0.02 * expected)
        << plan.bounces << " bounces; direct " << directSum.g / area << ", expected total " << expected;

    // The path tracer, at area-uniform points of one wall (every wall is
    // alike): the same mean within 2% (its noise over 16 × 16 points × 64
    // paths is about 0.3%).
    PathTracerSettings ps;
    ps.maxDepth = 24;
    ps.threads = 0;
    const PathTracer tracer(rays, ps);
    double sum = 0;
    const int side = 16;
    for (int i = 0; i < side; ++i)
        for (int j = 0; j < side; ++j) {
            const Vec3 x(-1 + 2 * (i + 0.5) / side, -1, -1 + 2 * (j + 0.5) / side);
            const IrradianceEstimate e = tracer.irradiance(x, kY, 64, uint32_t(i * side + j));
            sum += e.direct.g + e.indirect.g;
        }
    EXPECT_NEAR(sum / (side * side), expected, 0.02 * expected);
    std::printf("cube: expected %.5f, cache %.5f (direct %.5f, %d bounces), path tracer %.5f\n", expected,
                total.g / area, directSum.g / area, plan.bounces, sum / (side * side));
}

// --- Photometric luminaires (IES, a layout file) ----------------------------------------

namespace {

// I(γ, C) = i0 cos γ (1 + 0.3 sin² γ cos 2C) below the horizon, 0 above
// (radians): one value at the nadir, brighter across C0–C180.
double intensity(double i0, double g, double c) {
    return std::max(0.0, i0 * std::cos(g) * (1 + 0.3 * std::sin(g) * std::sin(g) * std::cos(2 * c)));
}

// An IES LM-63-2002 file of intensity() (the file stops at 90°),
// quadrant-symmetric, every 2.5° in γ and 15° in C, rated at its own flux
// π i0 (the cos 2C term integrates to zero).
std::string cosineIes(double i0) {
    std::ostringstream f;
    f.precision(12);
    f << "IESNA:LM-63-2002\n[TEST] cosine downlight\n[LUMINAIRE] Cosine\nTILT=NONE\n";
    const int nv = 37, nh = 7;
    f << "1 " << kPi * i0 << " 1 " << nv << " " << nh << " 1 2 0.2 0.2 0\n1 1 20\n";
    for (int v = 0; v < nv; ++v) f << 2.5 * v << (v + 1 < nv ? " " : "\n");
    for (int h = 0; h < nh; ++h) f << 15.0 * h << (h + 1 < nh ? " " : "\n");
    for (int h = 0; h < nh; ++h) {
        for (int v = 0; v < nv; ++v) {
            const double g = 2.5 * v * kPi / 180, c = 15.0 * h * kPi / 180;
            f << intensity(i0, g, c) << (v + 1 < nv ? " " : "\n");
        }
    }
    return f.str();
}

class Luminaires : public TempDirTest {};

// A floor 10 m below the luminaire (so the scene has a size), nothing else.
Scene luminaireScene(const std::string& layout) {
    Scene scene;
    scene.name = "luminaires";
    scene.materials = {Material::diffuse("grey", Rgb(0.5))};
    scene.meshes = {quadMesh("floor", 0, Vec3(-10, -10, -10), 20.0 * kZ, 20.0 * kX)};
    scene.finalize();
    addLuminaireLayout(scene, layout);
    return scene;
}

}  // namespace

// The checks: on a sphere of 5 m around the luminaire, E r² (lux ×
// m²) equals the file's I(γ, C) at every tabulated direction (0.5%; exact
// up to rounding here), through the cache's direct sampler; the flux over
// the sphere equals the file's lumens within 1% (midpoint quadrature of
// 90 × 180 cells of the bilinear table: its error is O(1°²)).
TEST_F(Luminaires, CandelaTableReproducesItselfOnASphereAndItsFlux) {
    const double i0 = 1000;
    write("cosine.ies", cosineIes(i0));
    // Aimed down, C0 along +x (no rotation).
    const Scene scene = luminaireScene(write("layout.csv", "# test\nfile,x,y,z\ncosine.ies,0,0,0\n"));
    ASSERT_EQ(scene.lights.size(), 1u);
    const Light& l = scene.lights[0];
    EXPECT_EQ(l.name, "cosine#0");
    EXPECT_EQ(l.group, "cosine");
    DirectChoice choice;
    choice.backend = GlBackend::OsMesa;
    ConfiguredDirectSampler sampler(scene, choice);
    const Photometry photometry;
    const double r = 5;
    // The direction of (γ, C): nadir −y, C0 +x, C90 = axis × C0 (right-handed about the axis).
    const Vec3 axis(0, -1, 0), c0(1, 0, 0), c90 = glm::cross(axis, c0);
    auto direction = [&](double gammaDeg, double cDeg) {
        const double g = gammaDeg * kPi / 180, c = cDeg * kPi / 180;
        return std::cos(g) * axis + std::sin(g) * (std::cos(c) * c0 + std::sin(c) * c90);
    };
    for (int v = 0; v <= 36; ++v)
        for (int h = 0; h < 24; ++h) {  // C every 15° around the circle: the quadrant mirrored
            const double g = 2.5 * v, c = 15.0 * h;
            const Vec3 w = direction(g, c);
            const double e = photometry.luminous(sampler.sample(0, r * w, -w, 1).irradiance);
            const double expected = intensity(i0, g * kPi / 180, c * kPi / 180);
            EXPECT_NEAR(e * r * r, expected, 0.005 * i0) << "gamma " << g << ", C " << c;
        }
    // Above the horizon the file says nothing: zero, on the sphere and on the ceiling side.
    EXPECT_EQ(sampler.sample(0, r * direction(120, 30), -direction(120, 30), 1).irradiance.g, 0);
    double flux = 0;
    const int ng = 90, nc = 180;
    for (int i = 0; i < ng; ++i)
        for (int j = 0; j < nc; ++j) {
            const double g = (i + 0.5) * 180.0 / ng, c = (j + 0.5) * 360.0 / nc;
            const Vec3 w = direction(g, c);
            const double dA = r * r * std::sin(g * kPi / 180) * (kPi / ng) * (2 * kPi / nc);
            flux += photometry.luminous(sampler.sample(0, r * w, -w, 1).irradiance) * dA;
        }
    EXPECT_NEAR(flux, kPi * i0, 0.01 * kPi * i0);
    EXPECT_NEAR(photometry.luminous(l.power()), flux, 0.01 * flux) << "the light's power is the table's flux";
}

// Aim and rotation: aimed along +x, the default C0 half-plane is the scene's
// +z (+x lies along the aim); turned 90° about the aim it becomes aim × z.
TEST_F(Luminaires, AimAndRotationTurnTheDistribution) {
    write("cosine.ies", cosineIes(100));
    const Scene scene = luminaireScene(write("layout.csv",
                                             "name,file,x,y,z,aim_x,aim_y,aim_z,rotation,multiplier,group\n"
                                             "a,cosine.ies,0,0,0,1,0,0,0,2,g1\n"
                                             "b,cosine.ies,0,0,0,1,0,0,90,1,g1\n"));
    ASSERT_EQ(scene.lights.size(), 2u);
    const PunctualEmission& a = scene.lights[0].emission;
    const PunctualEmission& b = scene.lights[1].emission;
    EXPECT_EQ(scene.lights[0].group, "g1");
    expectNear(a.axis, Vec3(1, 0, 0));
    expectNear(a.reference, Vec3(0, 0, 1));
    expectNear(b.reference, glm::cross(Vec3(1, 0, 0), Vec3(0, 0, 1)));  // turned 90° about the aim
    // 45° off the aim in the C0 plane: i0 cos 45° (1 + 0.3 sin² 45°), times the
    // multiplier; in the C90 plane (1 − 0.3 sin² 45°).
    const Vec3 w = glm::normalize(Vec3(1, 0, 1));
    EXPECT_NEAR(a.intensityToward(w).g * kRadianceEfficacy, 2 * 100 * std::cos(kPi / 4) * 1.15, 1e-9);
    EXPECT_NEAR(b.intensityToward(w).g * kRadianceEfficacy, 100 * std::cos(kPi / 4) * 0.85, 1e-9);
}

// Hard cases from the issue: luminaires from 1e-3 to 1e6 lm in one scene,
// one lying on the floor and one 1e-6 m above it: every value finite, each
// light's irradiance its own alone, and the path tracer agrees.
TEST_F(Luminaires, FluxesFromAMilliLumenToAMegaLumenAndLightsOnTheFloor) {
    write("cosine.ies", cosineIes(1000 / kPi));  // 1000 lm
    const Scene scene = luminaireScene(write("layout.csv",
                                             "file,x,y,z,multiplier\n"
                                             "cosine.ies,0,0,0,1e-6\n"
                                             "cosine.ies,1,0,0,1e3\n"
                                             "cosine.ies,2,-10,0,1\n"
                                             "cosine.ies,3,-9.999999,0,1\n"));
    ASSERT_EQ(scene.lights.size(), 4u);
    const Photometry photometry;
    EXPECT_NEAR(photometry.luminous(scene.lights[0].power()), 1e-3, 2e-5);
    EXPECT_NEAR(photometry.luminous(scene.lights[1].power()), 1e6, 2e4);
    DirectChoice choice;
    choice.backend = GlBackend::OsMesa;
    ConfiguredDirectSampler sampler(scene, choice);
    const EmbreeScene rays(scene);
    PathTracerSettings ps;
    ps.maxDepth = 1;
    ps.threads = 1;
    const PathTracer tracer(rays, ps);
    for (const Vec3& x : {Vec3(0, -10, 0), Vec3(1, -10, 0.5), Vec3(2, -10, 0), Vec3(2.5, -10, 0), Vec3(3, -10, 0)}) {
        const IrradianceEstimate pt = tracer.irradiance(x, kY, 4, 0);
        for (size_t l = 0; l < scene.lights.size(); ++l) {
            const Rgb e = sampler.sample(l, x, kY, 1).irradiance;
            ASSERT_TRUE(std::isfinite(e.g)) << "light " << l;
            EXPECT_EQ(e, punctualIrradiance(rays, l, x, kY).irradiance);
            EXPECT_NEAR(pt.directPerLight[l].g, e.g, 1e-9 * std::max(1.0, e.g)) << "light " << l;
        }
    }
    // On the floor the lying light gives nothing (edge-on); 1e-6 m above, 1000/π cd / 1e-12 m².
    EXPECT_EQ(sampler.sample(2, Vec3(2.5, -10, 0), kY, 1).irradiance.g, 0);
    EXPECT_NEAR(photometry.luminous(sampler.sample(3, Vec3(3, -10, 0), kY, 1).irradiance) / (1000 / kPi / 1e-12), 1, 1e-4);
}

TEST_F(Luminaires, LayoutErrorsNameTheFileLineAndColumn) {
    write("cosine.ies", cosineIes(100));
    Scene base = luminaireScene(write("empty.csv", "file,x,y,z\n"));
    auto error = [&](const std::string& text) {
        Scene scene = base;
        try {
            addLuminaireLayout(scene, write("bad.csv", text));
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        ADD_FAILURE() << "no error for:\n" << text;
        return std::string();
    };
    EXPECT_NE(error("file,x,y\ncosine.ies,0,0\n").find("bad.csv:1: the header has no column 'z'"), std::string::npos);
    EXPECT_NE(error("file,x,y,z,colour\n").find("bad.csv:1: unknown column 'colour'"), std::string::npos);
    EXPECT_NE(error("# c\nfile,x,y,z\ncosine.ies,0,nan,0\n").find("bad.csv:3: column 'y': 'nan' is not a finite number"),
              std::string::npos);
    EXPECT_NE(error("file,x,y,z\ncosine.ies,0,0\n").find("bad.csv:2: 3 values, the header names 4 columns"), std::string::npos);
    EXPECT_NE(error("file,x,y,z\nmissing.ies,0,0,0\n").find("missing.ies"), std::string::npos);
    EXPECT_NE(error("file,x,y,z,aim_x,aim_y,aim_z\ncosine.ies,0,0,0,0,0,0\n").find("bad.csv:2: the aim is the zero vector"),
              std::string::npos);
    EXPECT_NE(error("file,x,y,z,multiplier\ncosine.ies,0,0,0,-1\n").find("is negative"), std::string::npos);
    write("broken.ies", "IESNA:LM-63-2002\nTILT=NONE\n1 100 1 x\n");
    EXPECT_NE(error("file,x,y,z\nbroken.ies,0,0,0\n").find("broken.ies:3"), std::string::npos);
}

// A hard case from the issue: a spot aimed edge-on along the floor, 1 mm
// above it. The floor sees it at grazing angles only: finite, tiny next to
// what faces it, zero behind the light, and the path tracer agrees.
TEST(PunctualLight, SpotAimedEdgeOnAtTheFloor) {
    Light spot = pointLight("spot", Vec3(0, 0.001, 0), 1000);
    spot.emission.axis = Vec3(1, 0, 0);
    spot.emission.profile.shape = IntensityProfile::Shape::Spot;
    spot.emission.profile.cosInner = std::cos(0.2);
    spot.emission.profile.cosOuter = std::cos(0.4);
    const Scene scene = floorWith({spot});
    const EmbreeScene rays(scene);
    DirectChoice choice;
    choice.backend = GlBackend::OsMesa;
    ConfiguredDirectSampler sampler(scene, choice);
    PathTracerSettings ps;
    ps.maxDepth = 1;
    ps.threads = 1;
    const PathTracer tracer(rays, ps);
    for (double x : {-2.0, 0.0, 0.5, 1.0, 3.0}) {
        const Vec3 p(x, 0, 0);
        const Rgb e = sampler.sample(0, p, kY, 1).irradiance;
        ASSERT_TRUE(std::isfinite(e.g)) << "x " << x;
        // I cos θ / d² with cos θ = 1 mm / d, inside the inner cone (ahead of the light).
        const double d = std::hypot(x, 0.001);
        const double expected = x > 0 ? (1000 / kRadianceEfficacy) * (0.001 / d) / (d * d) : 0.0;
        EXPECT_NEAR(e.g, expected, 1e-9 * std::max(1.0, expected)) << "x " << x;
        EXPECT_NEAR(tracer.irradiance(p, kY, 2, 0).direct.g, e.g, 1e-9 * std::max(1.0, e.g)) << "x " << x;
    }
}

TEST(PunctualLights, ManySharedPointLightsAreDrawnWithOneExactShadowRayEach) {
    // 48 bulbs 2 m over a floor, a 2 × 2 m table top at 1 m hiding some of
    // them from the points under its edge. The lights share a mesh where each
    // gives under 10%, and the shared estimate draws 256 shadow rays among
    // them (more are left than its 16 pairs would take): one ray is a point
    // light's exact visibility, so the estimate's only noise is which lights
    // were drawn. Over 1024 seeds its mean is within 4 of its standard errors
    // (measured from the same estimates) of the exact sum, that standard
    // error under 0.5% of it; where nothing is in the way it is exact for
    // every seed.
    std::vector<Light> bulbs;
    for (int i = 0; i < 8; ++i)
        for (int k = 0; k < 6; ++k)
            bulbs.push_back(pointLight(concat("bulb", i, "_", k), Vec3(-3.5 + i, 2.0, -2.5 + k), 200));
    Scene scene;
    scene.name = "bulbs over a table";
    scene.materials = {Material::diffuse("grey", Rgb(0.5))};
    scene.meshes = {quadMesh("floor", 0, Vec3(-5, 0, -5), 10.0 * kZ, 10.0 * kX),
                    quadMesh("table", 0, Vec3(-1, 1, -1), 2.0 * kZ, 2.0 * kX)};
    scene.lights = std::move(bulbs);
    scene.finalize();
    const EmbreeScene rays(scene);
    const auto exact = [&](size_t l, const Vec3& x, const Vec3& n, uint32_t) {
        const PunctualSample s = punctualIrradiance(rays, l, x, n);
        return VertexSample{s.irradiance, s.visible ? 1.0 : 0.0, false};
    };
    auto coverage = std::make_shared<const LightCoverage>(scene, 0.1);
    ASSERT_TRUE(coverage->sharing());
    SharedLightSampler sampler(scene, coverage, std::make_unique<FunctionDirectSampler<decltype(exact)>>(exact));
    const size_t lights = scene.lights.size();
    for (const Vec3& p : {Vec3(0.9, 0.0, 0.3), Vec3(-1.2, 0.0, 0.8), Vec3(4.8, 0.0, 4.8)}) {
        Rgb truth(0.0), open(0.0);
        for (size_t l = 0; l < lights; ++l) {
            const double w = coverage->weight(l, p);
            truth += (1 - w) * punctualIrradiance(rays, l, p, kY).irradiance;
            open += (1 - w) * punctualIncidence(scene.lights[l], p, kY).irradiance;
        }
        ASSERT_GT(truth.g, 0.0);
        const bool shaded = truth.g < 0.99 * open.g;
        EXPECT_EQ(shaded, p.x < 2) << "the table hides some bulbs from the points under its edges, none from a "
                                      "corner of the floor";
        constexpr int kSeeds = 1024;
        double sum = 0, squares = 0;
        for (int k = 0; k < kSeeds; ++k) {
            const double e = sampler.sample(lights, p, kY, seedFor(3, uint32_t(k))).irradiance.g;
            sum += e, squares += e * e;
            if (!shaded) {
                EXPECT_NEAR(e, truth.g, 1e-12 * truth.g);
            }
        }
        const double mean = sum / kSeeds;
        const double standardError = std::sqrt((squares - sum * sum / kSeeds) / (kSeeds - 1) / kSeeds);
        EXPECT_NEAR(mean, truth.g, 4 * standardError + 1e-12 * truth.g) << "at " << p.x << ", " << p.z;
        EXPECT_LT(standardError, 0.005 * truth.g) << "at " << p.x << ", " << p.z;
    }
}
