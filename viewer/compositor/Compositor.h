// The compositor of §3.2: a reflectance image rendered from the scene's
// geometry, an irradiance image per cache mesh rendered from that mesh
// (Gouraud-interpolated), combined per sub-pixel as
// Kd/π × (Σ_l w_l E_l + w_ind Σ_b E_b) + Σ_l w_l Le_l, then box-filtered to
// pixels. E_l is light l's direct mesh, E_b bounce b's indirect mesh.
//
// The weights w make light changes free: irradiance is linear in emission,
// so a light switched off, dimmed or tinted scales its own mesh and its own
// emitted radiance exactly, with no new sample. `render` composites with
// every weight 1 and reads the image back; the viewer composites every
// frame into the compositor's own targets (compose), then draws them to the
// window (display, drawWireframe) without a trip through the CPU.
#pragma once

#include "GpuCacheMeshes.h"
#include "core/image/ToneMap.h"
#include "cache/IrradianceCache.h"
#include "core/Camera.h"
#include "core/Scene.h"
#include "core/image/FalseColour.h"
#include "core/image/Image.h"
#include "core/image/Photometry.h"

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

namespace ml {

class EmitterOutlines;
class GlContext;

// What a composited sub-pixel holds (black where no surface is seen).
enum class CompositeQuantity {
    // Kd/π × (Σ_l w_l E_l + w_ind Σ_b E_b) + Σ_l w_l Le_l, W·sr⁻¹·m⁻².
    Radiance,
    // Kd, the diffuse reflectance.
    Reflectance,
    // Illuminance in lux (lm·m⁻²), the same value in all three channels:
    // CompositorSettings::photometry applied to Σ_l w_l E_l + w_ind Σ_b E_b.
    Illuminance,
};

// What a Radiance composite does with the specular pass (SpecularPaths:
// mirrors, glass, Phong highlights), in scenes that have one.
enum class SpecularPart {
    Add,   // Kd/π × E + Le + the specular radiance: the image
    Off,   // Kd/π × E + Le alone (render's diffuse layers)
    Only,  // the specular radiance alone (render's specular layer)
};

struct CompositorSettings {
    int width = 512;      // output pixels
    int height = 512;
    // Sub-pixels per pixel side, typical 4 (16 samples, box filter): an EXR
    // pixel is the average radiance over its area. The viewer uses 1 or 2.
    int supersample = 4;
    // Images averaged by composite() (and so render()), each with the
    // sub-pixel grid shifted by a different fraction of a sub-pixel along
    // both axes (a rook pattern): 16 sub-pixels × 4 passes give an edge 16
    // levels of coverage each way where one pass gives 4. An emitter's
    // outline is where a regular grid errs most against a path tracer's
    // pixel average (tens of per cent on the Cornell box's light: 2.4% of the
    // whole image's relative RMSE at 16 sub-pixels, 0.9% at 256). `render`
    // uses 4, the viewer 1. With several passes, textures are filtered over
    // the samples' spacing, not the sub-pixel's (textureLodShiftFor).
    int passes = 1;
    // Radiance only: passes of the surfaces alone (no cache mesh, so a
    // fraction of a full pass's cost), their grid shifted in a rook pattern
    // of their own, that resolve the emitters' outlines: each pixel an
    // emitter covers in part takes the emission and coverage from them and
    // the rest from the full passes (EmitterOutlines.h). 0: none, the
    // viewer's; render's images take them (--outline-passes).
    int outlinePasses = 0;
    // > 0: the outline passes take about this many seconds at most: the
    // first is timed, and where all of them would take longer the count
    // becomes the most (a power of two, at least one) that fits
    // (outlinePassesWithin). Where emitters span the whole view (the back
    // rooms' glowing walls, 320×180) a pass takes 0.15 s. 0: all of them
    // (an image that must not depend on the machine's speed).
    double outlineSeconds = 0;
    // The image shifted by this many output pixels (x right, y up); set per
    // pass by composite(), 0 otherwise.
    double shiftX = 0, shiftY = 0;
    CompositeQuantity quantity = CompositeQuantity::Radiance;
    // Irradiance to lux, CompositeQuantity::Illuminance only: efficacy and
    // luminance weights (core/image/Photometry.h), RADIANCE's by default.
    Photometry photometry;
    // Radiance only; ignored in scenes without a glossy or specular material.
    SpecularPart specular = SpecularPart::Add;
    void validate() const;
};

// How textures are filtered in a composite of `passes` passes
// (common_textures.glsl). One pass (the viewer): 0, the GL's own filter
// over each sub-pixel's footprint: anisotropic where the GL offers it (not
// llvmpipe), else trilinear at the level of the footprint's longer axis,
// smooth but wider than the footprint. Any filter wider than the pixel's
// own samples adds a blur the path tracer (which reads texels at its hits)
// does not, and a blur is a bias where a texture is an atlas of charts
// without gutters: on the back rooms' floor, seen at a grazing angle, the
// trilinear square reached neighbouring charts and read 1-3% bright. K > 1
// passes, whose rook pattern samples each sub-pixel K times along either
// axis: the level of the footprint's shorter axis, shifted by −½·log2 K − 1
// (half the samples' spacing); what that leaves aliased along the longer
// axis, the passes and sub-pixels average out, as a path tracer's samples
// do. Measured on that floor (render --samples, 4 passes, against the same
// image read from the full-resolution level alone): 1-3% bright with the
// trilinear level, 0.7-0.9% at the samples' spacing, 0.3% at half of it;
// the composite 9% slower than trilinear.
float textureLodShiftFor(int passes);

// The sub-pixel passes `render --subpixel-passes auto` gives its last image,
// and the bench its checkpoints (what `render --time T` would write then):
// what refinement cannot remove is the sub-pixel grid's sampling of edges
// (the Cornell box's light: 0.46% of a 256×256 image with 4 passes, 0.2%
// with 16), so from one the count doubles, up to 64, while the doubled
// count's composite, timed as `onePassSeconds` per pass, takes at most a
// tenth of `refineSeconds`. The emitters' outlines, the largest of those
// edges, have passes of their own (outlinePasses), cheap enough for any
// image.
int subpixelPassesWithin(double onePassSeconds, double refineSeconds);

// render's CompositorSettings::outlinePasses (--outline-passes): 16 passes
// of the surfaces give an emitter's outline S·16 levels of coverage each
// way. The office's 12 panels at 320×180, S = 4, 4 sub-pixel passes: the
// pixels around them err by 6.7% (each against its own value), 5.0% with
// 16 outline passes, 4.5% with 64, and the 64 cost ~0.1 s more per
// composite there, up to seconds where emitters span the whole view.
constexpr int kRenderOutlinePasses = 16;
// The outline passes of `passes` (CompositorSettings::outlineSeconds) that
// fit in `budget` seconds at `onePassSeconds` each: all of them, or the
// most, a power of two, whose time fits; at least one.
int outlinePassesWithin(int passes, double onePassSeconds, double budget);

// Per-mesh RGB factors. A light's factor scales its direct mesh and the
// radiance its emitting faces show; indirect meshes (one per bounce, not
// per light) share one factor.
struct LightWeights {
    std::vector<Rgb> light;  // one per scene light, in the scene's order; 1 = as the scene says
    Rgb indirect{1.0};
    // The mesh many lights share (IrradianceCache::hasSharedMesh): like
    // indirect light, it takes their power-weighted mean weight.
    Rgb shared{1.0};
    // The factor of the radiance each light's emitting faces show, when it
    // is not `light`'s (render's layers: light without emission, emission
    // alone). Empty: `light`.
    std::vector<Rgb> emission;
    static LightWeights unit(size_t lights);
};

// How display() maps the composite to the screen.
struct DisplaySettings {
    // Radiance: multiplied by `exposure`, then `op` and the sRGB curve,
    // exactly as toneMap() does on the CPU (its auto exposure is the
    // caller's: see Compositor::readPixels). Reflectance: the sRGB curve only.
    double exposure = 1.0;
    ToneOperator op = ToneOperator::Aces;
    // Illuminance: falseColour() over [luxMin, luxMax] on a log scale, and
    // optional iso-lux lines at the 1-2-5 values (luxLevelIndex).
    double luxMin = 1.0;
    double luxMax = 1000.0;
    bool contours = false;
};

class Compositor {
public:
    // `scene` must outlive the compositor; `context` current on this thread.
    Compositor(GlContext& context, const Scene& scene);
    ~Compositor();

    // Linear radiance, W·sr⁻¹·m⁻², row 0 at the top. `direct` holds one
    // cache mesh per light (IrradianceCache::copyMeshes), in the scene's
    // light order, and then the shared mesh if the cache has one; `indirect`
    // one per bounce (none: direct light only).
    ImageRgb render(const Camera& camera, const std::vector<IrradianceMeshCopy>& direct,
                    const CompositorSettings& settings);
    ImageRgb render(const Camera& camera, const std::vector<IrradianceMeshCopy>& direct,
                    const std::vector<IrradianceMeshCopy>& indirect, const CompositorSettings& settings);

    // `direct` and `indirect` (as render() takes them) copied to the GPU,
    // for compose().
    GpuCacheMeshes upload(const std::vector<IrradianceMeshCopy>& direct,
                          const std::vector<IrradianceMeshCopy>& indirect) const;

    // --- The specular pass (issue 16) ---------------------------------------
    // Mirrors, glass and Phong highlights: traced on the CPU (SpecularPaths)
    // where a scene has a glossy or specular material, and added by the
    // composite (CompositorSettings::specular). render() and composite()
    // trace it themselves; the viewer traces it with traceSpecular() before
    // compose().
    bool hasSpecularPass() const;
    // The cache the specular paths read (copied), as render() takes it;
    // render() sets it itself. Nothing without a specular pass.
    void setSpecularCache(const std::vector<IrradianceMeshCopy>& direct,
                          const std::vector<IrradianceMeshCopy>& indirect);
    // Traces the specular image of the view compose() makes with these
    // arguments, a value per `reduction`² sub-pixels (1: every sub-pixel),
    // and keeps it for the composites that follow. Nothing is traced when
    // the image kept is of this view (camera, weights, settings, cache) at
    // `reduction` or finer. False when nothing was traced.
    bool traceSpecular(const Camera& camera, const LightWeights& weights, const CompositorSettings& settings,
                       int reduction = 1);
    // The viewer's full-resolution image: traced on a thread of its own,
    // unless the image kept or the one under way is it already (a trace
    // under way for another view is cancelled). collectSpecular() keeps it
    // once done, if it is still of the view kept; true when it did.
    void requestSpecular(const Camera& camera, const LightWeights& weights, const CompositorSettings& settings);
    bool collectSpecular();
    bool specularPending() const;
    // Seconds spent tracing the specular pass on this thread so far (render's summary).
    double specularSeconds() const;

    // --- Interactive frames -------------------------------------------------
    // Composites `settings.quantity` into the compositor's own targets
    // (width·s × height·s sub-pixels, kept between calls of one size).
    void compose(const Camera& camera, const GpuCacheMeshes& meshes, const LightWeights& weights,
                 const CompositorSettings& settings);
    // Draws the last composite, box-filtered to pixels on the GPU, into
    // `framebuffer` (a GL framebuffer name; 0: the window's back buffer)
    // over the viewport (0, 0, width, height), mapped as `display` says;
    // leaves `framebuffer` bound.
    void display(uint32_t framebuffer, const DisplaySettings& display);
    // Draws the edges of every cache mesh over `framebuffer`, where that
    // mesh's surface is the one the last composite saw, mesh i in colour
    // colours[i % size] (alpha-blended, about a pixel wide).
    void drawWireframe(uint32_t framebuffer, const GpuCacheMeshes& meshes, const std::vector<Rgb>& colours);
    // The last composite box-filtered to pixels on the GPU, as display()
    // shows it (auto exposure, the illuminance range). Row 0 at the top.
    ImageRgb readPixels();
    // The illuminance (lux) at pixel (x, y), row 0 at the top: the mean over
    // its sub-pixels that see a surface, whatever share of the pixel they
    // cover; none off every surface.
    std::optional<double> readIlluminance(int x, int y);
    // Illuminance per pixel (`render --quantity lux`): `settings.quantity`
    // is taken as CompositeQuantity::Illuminance; each pixel holds the mean
    // lux of its sub-pixels that see a surface and the share they cover, as
    // display() maps them.
    LuxImage renderIlluminance(const Camera& camera, const std::vector<IrradianceMeshCopy>& direct,
                               const std::vector<IrradianceMeshCopy>& indirect, CompositorSettings settings);
    // The last composite box-filtered on the CPU exactly as render() does:
    // for images that must equal render's output bit for bit.
    ImageRgb readImage();
    // compose() and readImage() `settings.passes` times, the sub-pixel grid
    // shifted each time, averaged: what render() returns. The specular
    // pass, if any, is traced for each shifted grid from the cache last
    // given to setSpecularCache (none given: no specular pass). With
    // `spread` and two passes or more, it receives each pixel's standard
    // error of that average over the passes (their sample standard
    // deviation over √K): how far the sub-pixel grid's sampling leaves the
    // pixel from its area's mean (ImageErrorEstimate.h); zero with one pass.
    ImageRgb composite(const Camera& camera, const GpuCacheMeshes& meshes, const LightWeights& weights,
                       const CompositorSettings& settings, ImageRgb* spread = nullptr);
    // composite() of each part of one view (render's EXR layers: the same
    // meshes, camera and settings, weights differing), each image exactly
    // what composite() returns for it. The emitters' outline passes
    // (CompositorSettings::outlinePasses) depend only on the view and the
    // emission the weights give: they are drawn for the first part of each
    // emission and taken from it by the rest (every light layer has none:
    // 16 passes saved per layer). Each distinct emission keeps its
    // EmitterOutlines (120 bytes per pixel) until the call returns: render's
    // layers have two.
    // Each part is composited only where it can be non-zero: a part without
    // emission (a light's layer) only over the screen bounds of the meshes
    // it adds (GpuCacheMeshes::Mesh::footprint, two pixels wider), read
    // back as zeros outside. Where lights share a mesh, their own meshes
    // cover only the surfaces where they matter: the 48-panel office's
    // layers (320×180, 4 passes) took 11.5 s, 6.0 s clipped, bit for bit
    // the same file.
    std::vector<ImageRgb> composite(const Camera& camera, const GpuCacheMeshes& meshes,
                                    const std::vector<LightWeights>& parts, const CompositorSettings& settings);
    // The share of the image's sub-pixels that composite() of these parts
    // composites for each (1: the whole image), from the unshifted grid:
    // about what each costs against a whole composite.
    std::vector<double> partShares(const Camera& camera, const GpuCacheMeshes& meshes,
                                   const std::vector<LightWeights>& parts, const CompositorSettings& settings) const;
    // Cache triangles the last compose drew: large meshes' cells out of
    // view are skipped (GpuCacheMeshes::Cell).
    size_t drawnTriangles() const;

private:
    // composite(), taking the outlines' surface passes from `drawn` where
    // one there has this part's emission, and adding its own there if not
    // (null: drawn, not kept).
    ImageRgb composite(const Camera& camera, const GpuCacheMeshes& meshes, const LightWeights& weights,
                       const CompositorSettings& settings, ImageRgb* spread, std::vector<EmitterOutlines>* drawn);
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace ml
