// meshlight render: progressive rendering. A worker thread refines and
// samples the cache meshes while this thread composites snapshots of them:
// for a time budget, an error target or a number of samples, one image or a
// walkthrough of many, with snapshots, a log and a resumable cache file;
// radiance, or illuminance in lux (--quantity lux). Ctrl-C or SIGTERM ends
// refinement at the end of the worker's round and writes what is cached
// (the image and the cache file), then exits with status 130.
#include "CameraOptions.h"
#include "Commands.h"
#include "PhotometryOptions.h"
#include "Plan.h"
#include "SamplerOptions.h"
#include "UntilErrorSchedule.h"
#include "cache/ProgressiveSession.h"
#include "gpu_sampling/gl/GlContext.h"
#include "core/CameraPath.h"
#include "core/Error.h"
#include "core/image/FalseColour.h"
#include "core/image/Illuminance.h"
#include "core/image/Image.h"
#include "core/image/ImageMetrics.h"
#include "core/image/ToneMap.h"
#include "core/io/AtomicFile.h"
#include "core/io/InterruptGuard.h"
#include "viewer/compositor/Compositor.h"
#include "viewer/compositor/ImageErrorEstimate.h"
#include "viewer/compositor/ImageLayers.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <sstream>

namespace ml {

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// --outline-passes auto: what every image's outline passes may take
// (CompositorSettings::outlineSeconds). The Cornell box's light at 512×512
// and the office's panels at 320×180 take their 16 in 0.01–0.12 s; the back
// rooms' glowing walls, which span the view, 0.15 s each at 320×180.
constexpr double kAutoOutlineSeconds = 0.5;

// "frames/view_####.png" → "frames/view_0007.png".
std::string framePath(const std::string& pattern, size_t frame) {
    const size_t at = pattern.find('#');
    size_t end = at;
    while (end < pattern.size() && pattern[end] == '#') ++end;
    std::string number = std::to_string(frame);
    if (number.size() < end - at) number.insert(0, end - at - number.size(), '0');
    return pattern.substr(0, at) + number + pattern.substr(end);
}

enum class OutputQuantity { Radiance, Lux };

OutputQuantity parseOutputQuantity(const std::string& name) {
    if (name == "radiance") return OutputQuantity::Radiance;
    if (name == "lux") return OutputQuantity::Lux;
    throw InputError(concat("--quantity '", name, "': use radiance or lux"));
}

// What an image is written for: a frame of the output (the image, or a
// walkthrough's view), or a --snapshots progress image (beauty only, its
// own exposure).
enum class ImageRole { Frame, Snapshot };

// The images render writes, one per view: radiance (EXR: the beauty image
// and its layers, unless --layers none; HDR linear; PNG tone-mapped) or
// illuminance (EXR: one channel Y in lux; HDR: lux in every channel; PNG:
// the viewer's false colour, iso-lux lines and legend). A walkthrough's
// PNGs share one exposure (and lux range), metered from the first frame
// written.
class ImageOutput {
public:
    // `metadata`: the attributes of an image of a snapshot.
    ImageOutput(Compositor& compositor, const Scene& scene, const CompositorSettings& settings,
                const ToneMapSettings& tone, OutputQuantity quantity, std::optional<LayerSettings> layers,
                bool walkthrough, std::function<ImageAttributes(const CacheSnapshot&)> metadata)
        : compositor_(compositor), scene_(scene), settings_(settings), tone_(tone), quantity_(quantity),
          layers_(layers), walkthrough_(walkthrough), metadata_(std::move(metadata)) {}

    ImageRgb radiance(const CacheSnapshot& s, const Camera& camera) {
        return compositor_.render(camera, s.direct, s.indirect, settings_);
    }
    // The radiance image and its estimated error (ImageErrorEstimate.h);
    // 1 (unknown) while indirect light is asked for and no bounce is shown
    // yet: the image then lacks light by an amount nothing has measured.
    // `check`: for the stop rule, while the worker refines on the same
    // cores: an image of more than 128×128 pixels is estimated at half its
    // size with one pass of one sample a pixel (the cache's error varies
    // slowly over the image: 0.93% against 0.91% for the Cornell box at
    // 512×512 with 4×4 samples a pixel; at 256×256 1.24% against 1.19% with
    // one, and an ask took 0.06-0.17 s instead of 0.25-0.57 s while the
    // worker ran). Smaller images, cheap anyway, keep their settings: with
    // one pass the dark side of each edge weighs more, and a 48×48 room
    // read 20% high.
    ImageErrorEstimate estimate(const CacheSnapshot& s, const Camera& camera, bool check = false) {
        CompositorSettings settings = settings_;
        if (check && settings.width * settings.height > 128 * 128)
            settings.width = std::max(1, settings.width / 2), settings.height = std::max(1, settings.height / 2),
            settings.passes = 1, settings.outlinePasses = 0, settings.supersample = 1;
        ImageErrorEstimate e = estimateImageError(compositor_, scene_, camera, s.direct, s.indirect, settings);
        if (lacksBounces(s)) e.cache = 1;
        return e;
    }
    bool expectIndirect = false;  // the session computes indirect light
    // ml::lacksBounces (ImageErrorEstimate.h) for this session.
    bool lacksBounces(const CacheSnapshot& s) const { return ml::lacksBounces(s, expectIndirect); }
    // The composites at the settings' sub-pixel passes that the last image
    // of `s` written to `path` takes: the estimate's beauty, and every
    // layer of a layered EXR (layerComposites).
    size_t compositesPerPass(const std::string& path, const CacheSnapshot& s) const {
        if (!layered(path)) return 1;
        return 1 + layerComposites(scene_, s.direct.size(), compositor_.hasSpecularPass(), *layers_);
    }
    // `path` is a frame written as a layered EXR (write()).
    bool layered(const std::string& path) const {
        return quantity_ == OutputQuantity::Radiance && outputFormat(path) == ImageFormat::Exr && layers_.has_value();
    }
    // Every layer of `s` from `camera` at the settings' passes, as write()
    // makes them for a layered EXR.
    RenderLayers layers(const CacheSnapshot& s, const Camera& camera) {
        return renderLayers(compositor_, scene_, camera, s.direct, s.indirect, settings_, *layers_);
    }
    int passes() const { return settings_.passes; }
    void setPasses(int passes) { settings_.passes = passes; }
    // CompositorSettings::outlineSeconds: kept at 0 (every pass) where it is.
    void allowOutlineSeconds(double seconds) {
        if (settings_.outlineSeconds > 0) settings_.outlineSeconds = std::max(settings_.outlineSeconds, seconds);
    }
    // Composites `s` from `camera` and writes it to `path`; returns the
    // radiance image written (empty for lux).
    // `made`: the radiance image of `s` from `camera`, when already made;
    // `ready`: the layers of a layered EXR, when already made (layers()).
    ImageRgb write(const std::string& path, const CacheSnapshot& s, const Camera& camera,
                   ImageRole role = ImageRole::Frame, const ImageRgb* made = nullptr,
                   std::optional<RenderLayers> ready = std::nullopt) {
        const bool frame = role == ImageRole::Frame;
        if (quantity_ == OutputQuantity::Lux) {
            writeLux(path, compositor_.renderIlluminance(camera, s.direct, s.indirect, settings_), frame);
            return {};
        }
        const ImageFormat format = outputFormat(path);
        if (format == ImageFormat::Exr && layers_ && frame) {
            RenderLayers layers = ready ? std::move(*ready) : this->layers(s, camera);
            ImageAttributes attributes = metadata_(s);
            attributes.push_back({"meshlight:layers", std::string(kLayerSums)});
            writeImageLayers(path, settings_.width, settings_.height, layers.exrLayers(), attributes);
            return std::move(layers.beauty);
        }
        ImageRgb image = made ? *made : radiance(s, camera);
        if (format != ImageFormat::Png) {
            writeImageLinear(path, image, frame ? metadata_(s) : ImageAttributes{});
            return image;
        }
        // The scale on radiance before the tone operator: the walkthrough's,
        // once metered, or this image's own.
        double scale = tone_.autoExposure ? autoExposureScale(image) : 1.0;
        if (walkthrough_ && frame && tone_.autoExposure) {
            if (!pathExposure_) pathExposure_ = scale;
            scale = *pathExposure_;
        }
        ToneMapSettings tone = tone_;
        tone.autoExposure = false;
        tone.exposureEV = tone_.exposureEV + std::log2(scale);
        const std::string exposure = concat(scale * std::exp2(tone_.exposureEV));
        writeImage8(path, toneMap(image, tone), image.width, image.height,
                    {{"meshlight:exposure", exposure},
                     {"meshlight:exposure_from", std::string(!tone_.autoExposure ? "--exposure alone"
                                                             : walkthrough_ && frame ? "the first frame"
                                                                                     : "this image")}});
        return image;
    }

    // How the layers add up, in the EXR's meshlight:layers.
    static constexpr const char* kLayerSums =
        "beauty (R,G,B) = emission + direct + indirect + specular (if present); direct = sum of light.* + "
        "direct_shared + direct_rest "
        "(those present); radiance W/(sr m2) except reflectance (Kd) and illuminance.Y (lux)";

private:
    void writeLux(const std::string& path, const LuxImage& lux, bool frame) {
        if (outputFormat(path) != ImageFormat::Png) {
            writeImageChannel(path, lux.lux, lux.width, lux.height, "Y",
                              {{"meshlight:quantity", std::string("illuminance")},
                               {"meshlight:unit", std::string("lx")},
                               {"meshlight:photometry", settings_.photometry.describe()}});
            return;
        }
        // The viewer's automatic range: percentiles of the lit pixels; a
        // walkthrough keeps its first frame's.
        std::vector<double> values;
        for (size_t i = 0; i < lux.lux.size(); ++i)
            if (lux.coverage[i] > 0) values.push_back(lux.lux[i]);
        std::pair<double, double> range = autoLuxRange(std::move(values));
        if (walkthrough_ && frame) {
            if (!pathLuxRange_) pathLuxRange_ = range;
            range = *pathLuxRange_;
        }
        const auto [lo, hi] = range;
        ImageRgb display = falseColourImage(lux, lo, hi, true);
        drawLuxLegend(display, lo, hi, concat(formatLux(lo), " .. ", formatLux(hi), " lx"));
        writeImage8(path, displayBytes(display), display.width, display.height);
    }

    Compositor& compositor_;
    const Scene& scene_;
    CompositorSettings settings_;
    ToneMapSettings tone_;
    OutputQuantity quantity_;
    std::optional<LayerSettings> layers_;  // none: the beauty image alone
    bool walkthrough_;
    std::function<ImageAttributes(const CacheSnapshot&)> metadata_;
    std::optional<double> pathExposure_;                     // a walkthrough's, from its first frame
    std::optional<std::pair<double, double>> pathLuxRange_;  // likewise, in lux
};

// ProgressiveSession::refineUntil in slices of at most 0.1 s, so that an
// interrupt ends the wait within one; true when one did. `stop` holds for
// the whole view, as in refineUntil.
// `good`: whether a fresh snapshot's image is as good as the stop rule's
// error asks (asked with stop.error set, at most once per snapshot).
bool refineUntilInterrupted(ProgressiveSession& session, CacheWorker::Reader& reader, const StopRule& stop,
                            uint64_t serial, double every, const std::function<void(const CacheSnapshot&)>& tick,
                            const std::function<bool(const CacheSnapshot&)>& good, const InterruptGuard& interrupt) {
    const auto start = Clock::now();
    uint64_t asked = 0;  // the snapshot version last asked about
    for (;;) {
        const double left = stop.seconds ? *stop.seconds - secondsSince(start) : kInf;
        StopRule slice = stop;
        slice.seconds = std::clamp(left, 0.0, 0.1);
        slice.error.reset();  // the image's estimate decides, below
        const CacheSnapshot* s = session.refineUntil(reader, slice, serial, every, tick);
        if (interrupt.interrupted()) return true;
        if (left <= 0.1 || session.finished()) return false;
        const bool fresh = s && s->cameraSerial >= serial;
        if (fresh && s->converged) return false;
        if (fresh && stop.error && s->version != asked) {
            asked = s->version;
            if (good(*s)) return false;
        }
    }
}

// The --log rows, kept in memory and written whole at the end.
class ConvergenceLog {
public:
    ConvergenceLog(size_t lights, bool shared, bool reference) : reference_(reference) {
        out_ << "seconds,frame,rounds,vertices,samples,estimated_error,direct_error,indirect_error,bounces_done,"
                "indirect_vertices,indirect_samples,image_estimated_error,image_sampling_spread";
        if (reference) out_ << ",rmse,relative_rmse";
        for (size_t l = 0; l < lights; ++l) out_ << ",light" << l << "_vertices,light" << l << "_samples";
        if (shared) out_ << ",shared_vertices,shared_samples";
        out_ << "\n";
    }
    void add(double seconds, size_t frame, const CacheSnapshot& s, const ImageErrorEstimate& estimate,
             const ImageRgb* ref) {
        out_ << seconds << "," << frame << "," << s.rounds << "," << s.vertices << "," << s.samples << ","
             << s.estimatedError << "," << s.directError << "," << s.indirectError << "," << s.bouncesFinished << ","
             << s.indirectVertices << "," << s.indirectSamples << "," << estimate.cache << "," << estimate.sampling;
        if (reference_) out_ << "," << rmse(estimate.image, *ref) << "," << relativeRmse(estimate.image, *ref);
        for (const IrradianceMeshCopy& m : s.direct) {
            uint64_t samples = 0;
            for (uint32_t c : m.samples) samples += c;
            out_ << "," << m.positions.size() << "," << samples;
        }
        out_ << "\n";
    }
    std::string text() const { return out_.str(); }

private:
    bool reference_;
    std::ostringstream out_;
};

// One line of progress: redrawn in place on a terminal, else one line per
// call (the caller calls it at snapshot times).
void printStatus(const CacheSnapshot& s, double seconds, const std::string& what, bool done) {
    static const bool terminal = ::isatty(STDERR_FILENO) != 0;
    std::fprintf(stderr, "%s%s %.1f s: %s%s", terminal ? "\r" : "", what.c_str(), seconds,
                 describeProgress(s).c_str(), terminal && !done ? "   " : "\n");
    std::fflush(stderr);
}

}  // namespace

int runRender(const std::vector<std::string>& args) {
    Options o("render");
    declareSceneOptions(o);
    o.value("out", "FILE", "output image: .exr (linear radiance and its layers) or .hdr (linear radiance) or "
                           ".png (tone-mapped); with --camera-path a pattern whose #### becomes the frame number",
            std::string("meshlight.png"));
    o.value("layers", "all|none", "an EXR of radiance: all = the beauty image (R,G,B) and the layers emission, "
                                  "direct, indirect, light.NAME per light, reflectance, illuminance (default); "
                                  "none = the beauty image alone");
    o.value("max-light-layers", "N", "lights with a layer of their own (in the scene's order); the others go "
                                     "together into direct_rest (default 64)");
    o.value("quantity", "radiance|lux", "what the image holds: radiance, or illuminance in lux at each pixel's "
                                        "surface (EXR: channel Y; PNG: false colour with iso-lux lines and a legend)",
            std::string("radiance"));
    declarePhotometryOption(o);
    declareViewOptions(o);
    o.value("camera-path", "FILE", "walkthrough: one image per line (px,py,pz,tx,ty,tz,ux,uy,uz,fov), all from one "
                                   "cache that keeps refining; --time and --until-error apply per image");
    o.flag("direct-only", "direct light only: no indirect bounces");
    o.value("time", "S", "refine for S seconds of wall-clock time, then write the image");
    o.value("until-error", "E", "stop once the image's estimated relative RMSE (the cache's predicted error, "
                                "composited) is at most E (default 0.02 when neither --time nor --samples is given)");
    o.value("samples", "N", "stop after N irradiance samples in all: a budget that repeats on any machine");
    o.value("snapshots", "DIR", "also write an image every --every seconds into DIR");
    o.value("every", "S", "seconds between snapshots and log rows", std::string("1"));
    o.value("log", "FILE.csv", "a row per snapshot: seconds, vertices and samples per mesh, the cache's and the "
                               "image's estimated errors");
    o.value("reference", "REF.exr", "with --log: add RMSE and relative RMSE against this image");
    o.value("cache", "FILE", "resume from this cache file if it exists, save the cache to it at the end");
    o.value("publish", "S", "the worker publishes a cache snapshot at most every S seconds", std::string("0.25"));
    o.value("sampling-threads", "T", "sampling threads, each with its own GL context; 0 = one per core (the cache a "
                                     "--samples budget makes is the same for any T)",
            std::string("0"));
    declareDirectOptions(o);
    declareCacheOptions(o);
    declareIndirectOptions(o);
    o.value("supersample", "S", "S×S sub-pixels per pixel (box filter)", std::string("4"));
    o.value("subpixel-passes", "K|auto",
            "average K images (1..64), the sub-pixel grid shifted in a rook pattern: edges (an emitter's outline) get "
            "S·K levels of coverage each way; auto: 4 for snapshots and walkthrough frames, and for the last image "
            "the most (a power of two up to 64) whose composite takes at most a tenth of the refinement's time; with "
            "--samples, 4 (the image, like the cache, the same on any machine)",
            std::string("auto"));
    o.value("outline-passes", "M|auto",
            concat("passes of the surfaces alone (no cache mesh: cheap) that resolve the emitters' outlines: a pixel "
                   "an emitter covers in part takes the emission and coverage from M·S² sub-pixels (0: from the "
                   "sub-pixel passes alone); auto: ", kRenderOutlinePasses, ", or fewer (a power of two) where they "
                   "would take over ", kAutoOutlineSeconds, " s, or for the last image over a tenth of the "
                   "refinement's time if more (emitters that span the view); with --samples, ", kRenderOutlinePasses),
            std::string("auto"));
    o.value("exposure", "EV", "exposure in stops, on top of auto exposure (a walkthrough's is metered once, "
                              "from its first frame)",
            std::string("0"));
    o.flag("no-auto-exposure", "do not scale the log-average luminance to middle grey: the exposure is --exposure "
                               "alone");
    o.value("tonemap", "OP", "aces, reinhard or clamp", std::string("aces"));
    if (!o.parseOrPrintHelp(args)) return 0;

    // Everything the user can get wrong is checked before any work.
    const std::string out = o.str("out");
    const bool walkthrough = o.has("camera-path");
    if (walkthrough && out.find('#') == std::string::npos)
        throw InputError(concat("--out '", out, "': with --camera-path it must contain #### for the frame number"));
    checkOutputPath(walkthrough ? framePath(out, 0) : out);
    CompositorSettings comp;
    comp.width = o.integer("width", 1, 16384);
    comp.height = o.integer("height", 1, 16384);
    comp.supersample = o.integer("supersample", 1, 16);
    const bool autoPasses = o.str("subpixel-passes") == "auto";
    comp.passes = autoPasses ? 4 : o.integer("subpixel-passes", 1, 64);
    const bool autoOutlines = o.str("outline-passes") == "auto";
    comp.outlinePasses = autoOutlines ? kRenderOutlinePasses : o.integer("outline-passes", 0, 1024);
    comp.photometry = readPhotometryOption(o);
    comp.validate();
    const OutputQuantity quantity = parseOutputQuantity(o.str("quantity"));
    const bool exrRadiance = outputFormat(out) == ImageFormat::Exr && quantity == OutputQuantity::Radiance;
    std::optional<LayerSettings> layers;
    if (o.has("layers") && o.str("layers") != "all" && o.str("layers") != "none")
        throw InputError(concat("--layers '", o.str("layers"), "': use all or none"));
    if (o.has("layers") && o.str("layers") == "all" && !exrRadiance)
        throw InputError("--layers all needs an EXR of radiance (--out .exr, --quantity radiance)");
    if (exrRadiance && (!o.has("layers") || o.str("layers") == "all")) {
        layers = LayerSettings{};
        if (o.has("max-light-layers")) layers->maxLightLayers = size_t(o.integer("max-light-layers", 0, 100000));
    } else if (o.has("max-light-layers")) {
        throw InputError("--max-light-layers is for an EXR with layers");
    }
    const DirectChoice choice = readDirectOptions(o);
    if (choice.passes != 1)
        throw InputError("render samples each vertex as often as its noise asks: --passes is for probe; "
                         "use --samples, --time or --until-error");
    const CacheSettings cacheSettings = readCacheSettings(o);
    IndirectChoice indirect = readIndirectOptions(o);
    ToneMapSettings tone;
    tone.exposureEV = o.number("exposure", -50, 50);
    tone.autoExposure = !o.isSet("no-auto-exposure");
    tone.op = parseToneOperator(o.str("tonemap"));
    StopRule stop;
    if (o.has("time")) stop.seconds = o.number("time", 0, 1e7);
    if (o.has("until-error")) stop.error = o.number("until-error", 1e-9, 1);
    if (o.has("samples")) stop.samples = uint64_t(o.number("samples", 1, 1e15));
    if (!stop.seconds && !stop.error && !stop.samples) stop.error = 0.02;
    // Timed outline passes, unless the image must not depend on the
    // machine's speed (a sample budget).
    if (autoOutlines && !stop.samples) comp.outlineSeconds = kAutoOutlineSeconds;
    const double every = o.number("every", 0.01, 1e6);
    const std::string snapshotsDir = o.has("snapshots") ? o.str("snapshots") : "";
    if (!snapshotsDir.empty()) makeOutputDirectory(snapshotsDir);
    const std::string logPath = o.has("log") ? o.str("log") : "";
    if (!logPath.empty()) checkOutputDirectory(logPath);
    if (o.has("reference") && logPath.empty()) throw InputError("--reference needs --log, where the errors go");
    if (o.has("reference") && quantity != OutputQuantity::Radiance)
        throw InputError("--reference compares radiance: it does not go with --quantity lux");
    ImageRgb reference;
    if (o.has("reference")) {
        reference = readImageLinear(o.str("reference"));
        if (reference.width != comp.width || reference.height != comp.height)
            throw InputError(concat(o.str("reference"), ": the reference is ", reference.width, "x",
                                    reference.height, ", the render ", comp.width, "x", comp.height));
    }
    const std::string cachePath = o.has("cache") ? o.str("cache") : "";
    if (!cachePath.empty()) checkOutputDirectory(cachePath);
    SessionSettings sessionSettings;
    sessionSettings.cache = cacheSettings;
    sessionSettings.worker.seed = choice.seed;
    sessionSettings.worker.publishSeconds = o.number("publish", 0, 3600);
    sessionSettings.worker.threads = o.integer("sampling-threads", 0, 256);
    sessionSettings.worker.refinementLevels = IrradianceCache::kMaxRefinementLevel;
    sessionSettings.cachePath = cachePath;

    const auto t0 = Clock::now();
    const Scene scene = loadScene(o);
    for (const std::string& w : scene.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
    const double aspect = double(comp.width) / comp.height;
    const std::vector<Camera> cameras =
        walkthrough ? loadCameraPath(o.str("camera-path")) : std::vector<Camera>{cameraFromOptions(o, scene, aspect)};
    std::printf("scene '%s': %zu meshes, %zu triangles, %zu lights\n", scene.name.c_str(), scene.meshes.size(),
                scene.triangleCount(), scene.lights.size());
    indirect.decide(scene);
    printPlan(scene, choice, cacheSettings, indirect);
    std::printf("  stop refining each image at %s\n", stop.describe().c_str());
    if (quantity == OutputQuantity::Lux)
        std::printf("  the image: illuminance in lux, photometry %s\n", comp.photometry.describe().c_str());
    if (layers) {
        const size_t own = std::min(scene.lights.size(), layers->maxLightLayers);
        std::printf("  the EXR: the beauty image and the layers emission, direct, indirect, %zu light.NAME%s, "
                    "reflectance, illuminance (--layers none: the beauty image alone)\n",
                    own, own < scene.lights.size() ? concat(", direct_rest (", scene.lights.size() - own,
                                                            " lights past --max-light-layers)").c_str()
                                                   : "");
    }

    if (indirect.active()) sessionSettings.indirect = indirect.solver;
    ProgressiveSession session(scene, sessionSettings, samplerFactory(scene, choice, indirect), stop);
    const IrradianceCache& cache = session.cache();
    if (session.resumed()) {
        std::printf("cache: resumed from %s: %zu vertices, %llu samples, %llu rounds\n", cachePath.c_str(),
                    cache.totalVertices(), static_cast<unsigned long long>(cache.totalSamples()),
                    static_cast<unsigned long long>(cache.rounds()));
    } else {
        std::printf("cache: %zu vertices over %zu light meshes%s to start with, %.1f MB\n", cache.totalVertices(),
                    cache.lightCount(), cache.hasSharedMesh() ? " and the mesh they share" : "",
                    cache.memoryBytes() / 1e6);
    }

    std::unique_ptr<GlContext> context = createHeadlessContext(choice.backend);
    std::printf("OpenGL: %s\n", context->describe().c_str());
    Compositor compositor(*context, scene);
    // The header of a frame: where it comes from and how far it got.
    std::string command = "meshlight render";
    for (const std::string& a : args) command += " " + a;
    const std::string sceneArgument = o.positionalValue("scene");
    const std::string cacheDescription =
        concat("edges at most 1/", 1 / cacheSettings.maxEdgeFraction, " of the scene, split tolerance ",
               cacheSettings.splitTolerance, ", noise tolerance ", cacheSettings.noiseTolerance);
    const std::string indirectDescription = indirect.active() ? indirect.describe()
                                            : indirect.enabled ? std::string("no bounce")
                                                               : std::string("none (--direct-only)");
    double imageEstimate = -1;  // the final image's estimated error, once known
    auto metadata = [&](const CacheSnapshot& s) -> ImageAttributes {
        ImageAttributes a{{"meshlight:scene", sceneArgument},
                {"meshlight:command", command},
                {"meshlight:direct", choice.describe()},
                {"meshlight:cache", cacheDescription},
                {"meshlight:indirect", indirectDescription},
                {"meshlight:samples", double(s.samples)},
                {"meshlight:vertices", double(s.vertices)},
                {"meshlight:seconds", session.seconds()},
                {"meshlight:estimated_error", s.estimatedError},
                {"meshlight:direct_error", s.directError},
                {"meshlight:indirect_error", s.indirectError},
                {"meshlight:converged", int(s.converged)},
                {"meshlight:photometry", comp.photometry.describe()}};
        if (imageEstimate >= 0) a.push_back({"meshlight:image_estimated_error", imageEstimate});
        return a;
    };
    ImageOutput output(compositor, scene, comp, tone, quantity, layers, walkthrough, metadata);
    output.expectIndirect = indirect.active();
    ConvergenceLog log(scene.lights.size(), cache.hasSharedMesh(), o.has("reference"));

    // From here on, the first Ctrl-C ends refinement and writes what is cached.
    const InterruptGuard interrupt;
    const uint64_t firstSerial = session.start(RefinementCamera{cameras.front(), comp.width, comp.height});
    CacheWorker::Reader reader = session.reader();

    size_t snapshotIndex = 0;
    auto tick = [&](const CacheSnapshot& s, size_t frame) {
        const double seconds = session.seconds();
        ImageRgb image;
        if (!snapshotsDir.empty()) {
            char name[96];
            std::snprintf(name, sizeof name, "snapshot_%04zu%s.%s", snapshotIndex,
                          walkthrough ? concat("_frame", frame).c_str() : "",
                          outputFormat(out) == ImageFormat::Png ? "png" : "exr");
            image = output.write((std::filesystem::path(snapshotsDir) / name).string(), s, cameras[frame],
                                 ImageRole::Snapshot);
        }
        ++snapshotIndex;
        if (!logPath.empty())
            log.add(seconds, frame, s, output.estimate(s, cameras[frame]), o.has("reference") ? &reference : nullptr);
        printStatus(s, seconds, walkthrough ? concat("frame ", frame) : std::string("refining"), false);
    };

    // --until-error: a fresh snapshot is good enough once its image's
    // estimated error is at most E. The estimate composites the image (and
    // its errors), on this thread while the worker samples on its own, at
    // half size and one sample a pixel (ImageOutput::estimate): 0.06-0.17 s
    // for the 256×256 Cornell box. It is asked at most a third of the time,
    // and at each snapshot near where the last two estimates (a power law)
    // say the error crosses E (UntilErrorSchedule). Asked every 0.5 s at
    // most, and composited with 4×4 samples a pixel (0.25-0.57 s), that box
    // asked every other snapshot and, until 2%, stopped at 1.7-2.3 s with
    // 1.04-1.12% measured (ten runs until 1-5%: 0.82-1.43%); now at 1.0-1.1
    // s with 1.15-1.37%, and until 1% at 1.6-1.7 s with 1.04%.
    // The image written is the snapshot the rule found good (`judged`; the
    // reader keeps it until its next acquire), not the one the worker
    // publishes as it stops: that is later by the ask and the end of a
    // round, cut short by the stop between two batches, whose new vertices
    // are shown filled from their neighbours. The 256×256 Cornell box asked
    // until 1% stopped at 0.91% by its last ask and wrote an image whose
    // estimate read 2.07% (measured 0.91%).
    UntilErrorSchedule schedule;
    const CacheSnapshot* judged = nullptr;
    auto good = [&](size_t frame) {
        schedule = UntilErrorSchedule();  // a new view's error starts afresh
        judged = nullptr;
        return [&, frame](const CacheSnapshot& s) {
            // Nothing to ask before a bounce is shown (the estimate is then
            // unknown: ImageOutput::estimate).
            if (output.lacksBounces(s)) return false;
            const double now = session.seconds();
            if (!schedule.shouldAsk(now, s.seconds, *stop.error)) return false;
            const double estimate = output.estimate(s, cameras[frame], true).cache;
            schedule.asked(now, session.seconds(), s.seconds, estimate);
            if (estimate > *stop.error) return false;
            judged = &s;
            return true;
        };
    };

    // The frame refined last: the last one, or the one an interrupt ended.
    size_t lastFrame = cameras.size() - 1;
    bool interrupted = false;
    for (size_t frame = 0; frame < cameras.size() && !interrupted; ++frame) {
        // Only snapshots made for this frame's view count for it.
        const uint64_t serial =
            frame == 0 ? firstSerial : session.setCamera(RefinementCamera{cameras[frame], comp.width, comp.height});
        const auto frameStart = Clock::now();
        interrupted = refineUntilInterrupted(session, reader, stop, serial, every,
                                             [&](const CacheSnapshot& s) { tick(s, frame); }, good(frame),
                                             interrupt);
        if (interrupted) {
            lastFrame = frame;
        } else if (frame + 1 < cameras.size()) {
            const CacheSnapshot* s = judged ? judged : reader.acquire();
            output.write(framePath(out, frame), *s, cameras[frame]);
            std::printf("frame %zu: %.2f s, %zu vertices; wrote %s\n", frame, secondsSince(frameStart), s->vertices,
                        framePath(out, frame).c_str());
        }
    }
    // The last image is made from everything the worker did (or, stopped by
    // --until-error, from the snapshot judged), so it stops first (at the end
    // of its round).
    if (interrupted) std::fprintf(stderr, "\nmeshlight: %s: ending the worker's round\n", interrupt.signalName());
    session.stop();
    session.rethrowIfFailed();
    const CacheSnapshot* final = judged && !interrupted ? judged : reader.acquire();
    ML_ASSERT(final, "the worker published no snapshot");
    const double refineSeconds = session.seconds();
    const std::string lastPath = walkthrough ? framePath(out, lastFrame) : out;
    const bool radianceOut = quantity == OutputQuantity::Radiance;
    // Under a sample budget the last image keeps the snapshots' passes: a
    // count timed on this machine would make the image, unlike the cache,
    // depend on its speed and load (a run under load took 4.75 s instead of
    // 2.1 s and composited more passes than its resumed copies, 2.5% apart).
    std::optional<RenderLayers> lastLayers;  // made while timing the last image's passes, if kept
    if (autoPasses && !walkthrough && radianceOut && !stop.samples) {
        // As many passes as a tenth of the refinement's time pays for, timed
        // on one pass (subpixelPassesWithin) and counted over every
        // composite the image takes: a layered EXR composites each light's
        // layer at those passes too. Counting the beauty alone, the back
        // rooms' `--time 240` (240×135) took 32 passes, and its last image,
        // with 16 lights' layers, 127 s after 241 s of refinement. A layered
        // EXR's pass is timed, not counted: its layers are made at one pass
        // (kept when that is all the time pays for), as a light's layer
        // costs what its mesh covers (Compositor::composite of parts). The
        // 48-panel office's counted 56 composites of a beauty pass took 16 s
        // a pass at 240 s, for one pass; its layers take about 4.5 s.
        CompositorSettings one = comp;
        one.passes = 1;
        one.outlinePasses = 0;
        const GpuCacheMeshes meshes = compositor.upload(final->direct, final->indirect);
        compositor.setSpecularCache(final->direct, final->indirect);
        const auto t0 = Clock::now();
        compositor.composite(cameras[lastFrame], meshes, LightWeights::unit(scene.lights.size()), one);
        const double pass = secondsSince(t0);
        const size_t composites = output.compositesPerPass(lastPath, *final);
        double perPass = pass * double(composites);
        if (output.layered(lastPath)) {
            output.setPasses(1);
            const auto t1 = Clock::now();
            lastLayers = output.layers(*final, cameras[lastFrame]);
            perPass = pass + secondsSince(t1);  // the estimate's beauty, and the layers
        }
        const int k = subpixelPassesWithin(perPass, refineSeconds);
        output.setPasses(k);
        if (k != 1) lastLayers.reset();
        std::printf("sub-pixel passes: %d for the last image (one pass %.3f s, %zu composites, %.1f whole images; "
                    "a tenth of %.1f s refined)\n",
                    k, pass, composites, perPass / pass, refineSeconds);
    }
    // The last image's outline passes may take a tenth of the refinement's
    // time, as its sub-pixel passes do.
    output.allowOutlineSeconds(0.1 * refineSeconds);
    ImageErrorEstimate finalEstimate;
    if (radianceOut || !logPath.empty()) {
        finalEstimate = output.estimate(*final, cameras[lastFrame]);
        imageEstimate = finalEstimate.cache;
    }
    output.write(lastPath, *final, cameras[lastFrame], ImageRole::Frame,
                 finalEstimate.image.data.empty() ? nullptr : &finalEstimate.image, std::move(lastLayers));
    if (!logPath.empty())
        log.add(refineSeconds, lastFrame, *final, finalEstimate, o.has("reference") ? &reference : nullptr);
    printStatus(*final, refineSeconds, walkthrough ? concat("frame ", lastFrame) : std::string("refined"), true);
    if (!logPath.empty()) writeTextFileAtomically(logPath, log.text());
    if (!cachePath.empty()) session.save(cachePath);

    const DirectPhaseTimes& p = final->directPhases;
    std::printf("refinement: %.2f s, %llu rounds, %zu vertices, %llu samples (%.1f us each; GPU phases: setup %.2f s, "
                "draw %.2f s, readback %.2f s, weighting %.2f s), estimated error %.3g%%%s\n",
                refineSeconds, static_cast<unsigned long long>(final->rounds), final->vertices,
                static_cast<unsigned long long>(final->samples),
                final->samples ? refineSeconds / double(final->samples) * 1e6 : 0.0, p.setup, p.draw, p.readback,
                p.weighting, 100 * final->estimatedError, final->converged ? " (converged)" : "");
    if (radianceOut)
        std::printf("image: estimated error %.3g%% (relative RMSE from the cache's predicted error; the sub-pixel "
                    "passes' halves differ by %.3g%%)\n",
                    100 * finalEstimate.cache, 100 * finalEstimate.sampling);
    std::printf("cache: %.1f MB (%zu bytes per vertex)%s\n", cache.memoryBytes() / 1e6, IrradianceCache::bytesPerVertex(),
                cachePath.empty() ? "" : concat("; saved to ", cachePath).c_str());
    if (session.indirect()) {
        const IndirectStats& st = final->indirectStats;
        std::printf("indirect: %d of %d bounces converged, %zu vertices, %llu gathers (%.3f ms each), sources built in "
                    "%.2f s, %.1f MB held; last source: %s\n",
                    final->bouncesFinished, final->bounces, final->indirectVertices,
                    static_cast<unsigned long long>(final->indirectSamples),
                    st.estimates ? 1e3 * st.estimateSeconds / double(st.estimates) : 0.0, st.buildSeconds,
                    st.sourceBytes / 1e6, st.source.c_str());
    }
    if (compositor.hasSpecularPass())
        std::printf("specular pass (mirrors, glass, highlights): %.2f s of tracing on the CPU\n",
                    compositor.specularSeconds());
    std::printf("total %.2f s; wrote %s (%dx%d)\n", secondsSince(t0), lastPath.c_str(), comp.width, comp.height);
    if (interrupted) {
        std::fprintf(stderr, "meshlight: interrupted: wrote %s%s (what was cached after %.1f s)\n", lastPath.c_str(),
                     cachePath.empty() ? "" : concat(" and ", cachePath).c_str(), refineSeconds);
        return 130;
    }
    return 0;
}

}  // namespace ml
