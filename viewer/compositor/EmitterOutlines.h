// Emitters' outlines resolved with more sub-pixel samples than the rest of
// the image.
//
// A pixel an emitter partly covers is its emission times the share it
// covers plus the rest of the pixel: against a path tracer's pixel average,
// a regular sub-pixel grid errs most there, by a coverage step times an
// emitter's radiance, tens of times the surfaces' (the office's panels:
// half the squared error of a 320×180 image at 16 sub-pixels, 22% at 4
// passes of 16). More full passes cost the cache meshes' triangles each
// time; the emitters' coverage needs only the scene's own surfaces. So a
// composite of K full passes (CompositorSettings::passes) can add M passes
// of the surfaces alone, their grid shifted in a rook pattern of M, and
// rebuild each pixel that sees an emitter as
//
//     E_M + c_M · R_K + (1 − c_M) · B_K,
//
// E_M and c_M: the emitted radiance and the emitters' coverage over the M
// passes' sub-pixels; B_K: the mean radiance of the full passes' sub-pixels
// that see no emitter (background counts, as 0); R_K: the mean, over those
// that see one, of their radiance besides the emission (Kd/π × E,
// specular). Where the full passes saw no sub-pixel off the emitters, B is
// pooled from the 3×3 pixels around. Pixels that see no emitter in any pass
// keep the full passes' mean, as before.
#pragma once

#include "core/image/Image.h"
#include "core/Math.h"

#include <vector>

namespace ml {

class EmitterOutlines {
public:
    // A rectangle of sub-pixels in GL's coordinates (rows from the bottom).
    struct Rect {
        int x = 0, y = 0, width = 0, height = 0;
        bool empty() const { return width <= 0 || height <= 0; }
    };
    // Sub-pixels of one pass as the GL reads them back: RGBA floats, rows
    // from the bottom, those of `rect` (empty: the whole width·S × height·S).
    struct SubPixels {
        Rect rect;
        // The compositor's surface target: a = 0 nothing seen, 1 a surface,
        // 2 + l the front of light l.
        std::vector<float> surface;
        // The emission texture's scale of the light's radiance (rgb), in
        // scenes with emission textures; empty: 1.
        std::vector<float> emissionScale;
    };

    // `emission`: what light l's front shows, its radiance times its weight.
    EmitterOutlines(int width, int height, int supersample, std::vector<Rgb> emission);

    // A full pass: its composite's radiance sub-pixels (RGBA, as SubPixels,
    // those of seen.rect) and what each saw. Outside a rect, nothing is
    // counted: right where the pass is black there and within two pixels
    // of its edge inside (Compositor's clipped parts), as the 3×3 pooling
    // of apply() then reads zeros either way.
    void addFullPass(const std::vector<float>& radiance, const SubPixels& seen);
    // A pass of the surfaces alone; `odd`: which half of the passes it is in
    // (the halves' difference is the spread, as Compositor::composite's).
    void addSurfacePass(const SubPixels& seen, bool odd);
    // The sub-pixels the surface passes need to cover: those of the pixels
    // where the full passes saw an emitter and of the pixels around them
    // (an outline the full passes' grid straddles without a sample on the
    // emitter). Empty when they saw none: the surface passes have nothing
    // to do. An emitter thinner than the full passes' sample spacing that
    // none of their samples hit is missed, as it is without the passes.
    Rect emitterBounds() const;
    // Whether `other`'s surface passes would add here exactly what they
    // added there: the same image, sub-pixels and emission per light.
    bool sharesSurfacePasses(const EmitterOutlines& other) const;
    // Takes `other`'s surface passes instead of drawing them again (a part
    // of the same view with the same emission: Compositor::composite of
    // several parts); replaces any this one had. sharesSurfacePasses must
    // hold.
    void copySurfacePasses(const EmitterOutlines& other);
    // Forgets the surface passes added so far.
    void clearSurfacePasses();

    // `image`: the full passes' mean. Every pixel where some pass saw an
    // emitter is rebuilt as the file's comment says; with surface passes in
    // both halves, its `spread` (if given) becomes half the difference of
    // the pixel rebuilt from each half. Returns how many pixels changed.
    size_t apply(ImageRgb& image, ImageRgb* spread = nullptr) const;

private:
    struct Pixel {
        double other[3] = {0, 0, 0};  // full passes: Σ radiance off the emitters
        double otherCount = 0;
        double rest[3] = {0, 0, 0};   // full passes: Σ (radiance − emission) on them
        double restCount = 0;
        double emitted[2][3] = {{0, 0, 0}, {0, 0, 0}};  // surface passes, per half: Σ emission
        double covered[2] = {0, 0};                    // surface passes, per half: sub-pixels on an emitter
    };
    // The emission sub-pixel i shows, and whether it is on an emitter.
    bool emittedAt(const SubPixels& seen, size_t i, Rgb& e) const;
    size_t pixelOf(const Rect& rect, size_t subPixel) const;
    Rect whole() const;

    int width_, height_, supersample_;
    std::vector<Rgb> emission_;
    std::vector<Pixel> pixels_;
    int surfacePasses_[2] = {0, 0};  // per half
};

}  // namespace ml
