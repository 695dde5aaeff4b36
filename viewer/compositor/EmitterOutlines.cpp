#include "EmitterOutlines.h"

#include "core/Error.h"

#include <algorithm>
#include <cmath>

namespace ml {

EmitterOutlines::EmitterOutlines(int width, int height, int supersample, std::vector<Rgb> emission)
    : width_(width), height_(height), supersample_(supersample), emission_(std::move(emission)),
      pixels_(size_t(width) * size_t(height)) {
    ML_ASSERT(width > 0 && height > 0 && supersample > 0, "outline image ", width, "x", height, " at ", supersample);
}

EmitterOutlines::Rect EmitterOutlines::whole() const {
    return {0, 0, width_ * supersample_, height_ * supersample_};
}

size_t EmitterOutlines::pixelOf(const Rect& rect, size_t subPixel) const {
    const size_t h = size_t(height_) * size_t(supersample_);
    const size_t x = size_t(rect.x) + subPixel % size_t(rect.width),
                 y = h - 1 - (size_t(rect.y) + subPixel / size_t(rect.width));  // GL rows start at the bottom
    return y / size_t(supersample_) * size_t(width_) + x / size_t(supersample_);
}

EmitterOutlines::Rect EmitterOutlines::emitterBounds() const {
    int x0 = width_, y0 = height_, x1 = -1, y1 = -1;  // pixels, rows from the top
    for (int y = 0; y < height_; ++y)
        for (int x = 0; x < width_; ++x)
            if (pixels_[size_t(y) * size_t(width_) + size_t(x)].restCount > 0)
                x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
    if (x1 < 0) return {};
    x0 = std::max(0, x0 - 1), y0 = std::max(0, y0 - 1);
    x1 = std::min(width_ - 1, x1 + 1), y1 = std::min(height_ - 1, y1 + 1);
    const int s = supersample_;
    return {x0 * s, (height_ - 1 - y1) * s, (x1 - x0 + 1) * s, (y1 - y0 + 1) * s};
}

bool EmitterOutlines::emittedAt(const SubPixels& seen, size_t i, Rgb& e) const {
    const float a = seen.surface[i * 4 + 3];
    if (!(a >= 2.0f) || emission_.empty()) return false;
    e = emission_[std::min(size_t(a) - 2, emission_.size() - 1)];
    if (!seen.emissionScale.empty())
        e *= Rgb(seen.emissionScale[i * 4], seen.emissionScale[i * 4 + 1], seen.emissionScale[i * 4 + 2]);
    return true;
}

void EmitterOutlines::addFullPass(const std::vector<float>& radiance, const SubPixels& seen) {
    const Rect r = seen.rect.empty() ? whole() : seen.rect;
    const size_t n = size_t(r.width) * size_t(r.height);
    ML_ASSERT(r.x >= 0 && r.y >= 0 && r.x + r.width <= width_ * supersample_ &&
                  r.y + r.height <= height_ * supersample_ && radiance.size() == 4 * n && seen.surface.size() == 4 * n,
              "a full pass of ", radiance.size() / 4, " and ", seen.surface.size() / 4, " sub-pixels for ", n);
    for (size_t i = 0; i < n; ++i) {
        Pixel& p = pixels_[pixelOf(r, i)];
        Rgb e;
        if (emittedAt(seen, i, e)) {
            for (int c = 0; c < 3; ++c) p.rest[c] += double(radiance[i * 4 + c]) - e[c];
            p.restCount += 1;
        } else {
            for (int c = 0; c < 3; ++c) p.other[c] += radiance[i * 4 + c];
            p.otherCount += 1;
        }
    }
}

void EmitterOutlines::addSurfacePass(const SubPixels& seen, bool odd) {
    const Rect r = seen.rect.empty() ? whole() : seen.rect;
    const size_t n = size_t(r.width) * size_t(r.height);
    ML_ASSERT(r.x >= 0 && r.y >= 0 && r.x + r.width <= width_ * supersample_ &&
                  r.y + r.height <= height_ * supersample_ && seen.surface.size() == 4 * n,
              "a surface pass of ", seen.surface.size() / 4, " sub-pixels for ", n);
    const int half = odd ? 1 : 0;
    for (size_t i = 0; i < n; ++i) {
        Rgb e;
        if (!emittedAt(seen, i, e)) continue;
        Pixel& p = pixels_[pixelOf(r, i)];
        for (int c = 0; c < 3; ++c) p.emitted[half][c] += e[c];
        p.covered[half] += 1;
    }
    ++surfacePasses_[half];
}

bool EmitterOutlines::sharesSurfacePasses(const EmitterOutlines& other) const {
    return width_ == other.width_ && height_ == other.height_ && supersample_ == other.supersample_ &&
           emission_ == other.emission_;
}

void EmitterOutlines::copySurfacePasses(const EmitterOutlines& other) {
    ML_ASSERT(sharesSurfacePasses(other), "surface passes of other outlines");
    for (size_t i = 0; i < pixels_.size(); ++i) {
        Pixel& p = pixels_[i];
        const Pixel& q = other.pixels_[i];
        for (int h = 0; h < 2; ++h) {
            for (int c = 0; c < 3; ++c) p.emitted[h][c] = q.emitted[h][c];
            p.covered[h] = q.covered[h];
        }
    }
    surfacePasses_[0] = other.surfacePasses_[0], surfacePasses_[1] = other.surfacePasses_[1];
}

void EmitterOutlines::clearSurfacePasses() {
    for (Pixel& p : pixels_)
        for (int h = 0; h < 2; ++h) {
            for (int c = 0; c < 3; ++c) p.emitted[h][c] = 0;
            p.covered[h] = 0;
        }
    surfacePasses_[0] = surfacePasses_[1] = 0;
}

size_t EmitterOutlines::apply(ImageRgb& image, ImageRgb* spread) const {
    ML_ASSERT(image.width == width_ && image.height == height_, "outlines of ", width_, "x", height_, " on a ",
              image.width, "x", image.height, " image");
    const int passes = surfacePasses_[0] + surfacePasses_[1];
    if (passes == 0) return 0;
    const double perPass = double(supersample_) * supersample_;
    size_t changed = 0;
    for (int y = 0; y < height_; ++y)
        for (int x = 0; x < width_; ++x) {
            const Pixel& p = pixels_[size_t(y) * size_t(width_) + size_t(x)];
            if (p.restCount == 0 && p.covered[0] + p.covered[1] == 0) continue;
            // B: off the emitters, from this pixel or else the 3×3 around it.
            Rgb other(0.0);
            double count = p.otherCount;
            if (count > 0) {
                other = Rgb(p.other[0], p.other[1], p.other[2]) / count;
            } else {
                Rgb sum(0.0);
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx) {
                        const int nx = x + dx, ny = y + dy;
                        if (nx < 0 || ny < 0 || nx >= width_ || ny >= height_) continue;
                        const Pixel& q = pixels_[size_t(ny) * size_t(width_) + size_t(nx)];
                        sum += Rgb(q.other[0], q.other[1], q.other[2]);
                        count += q.otherCount;
                    }
                if (count > 0) other = sum / count;
            }
            const Rgb rest = p.restCount > 0 ? Rgb(p.rest[0], p.rest[1], p.rest[2]) / p.restCount : Rgb(0.0);
            // E + c·R + (1 − c)·B over the given halves' sub-pixels.
            const auto rebuilt = [&](int first, int last) {
                Rgb emitted(0.0);
                double covered = 0, subPixels = 0;
                for (int h = first; h <= last; ++h) {
                    emitted += Rgb(p.emitted[h][0], p.emitted[h][1], p.emitted[h][2]);
                    covered += p.covered[h];
                    subPixels += surfacePasses_[h] * perPass;
                }
                const double c = covered / subPixels;
                return emitted / subPixels + c * rest + (1 - c) * other;
            };
            const Rgb value = rebuilt(0, 1);
            ML_ASSERT(isFinite(value), "non-finite outline at pixel ", x, ",", y);
            image.set(x, y, value);
            ++changed;
            if (spread && surfacePasses_[0] > 0 && surfacePasses_[1] > 0) {
                // With independent errors of one size, the mean of both
                // halves errs by half their difference.
                const Rgb d = 0.5 * glm::abs(rebuilt(0, 0) - rebuilt(1, 1));
                spread->set(x, y, d);
            }
        }
    return changed;
}

}  // namespace ml
