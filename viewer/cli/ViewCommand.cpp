// meshlight view: the progressive walkthrough viewer (ViewSession.h), and
// its scripted twin (--script, ViewScript.h). Everything the user can get
// wrong, the script included, is checked before the window opens.
#include "viewer/window/ViewRefinement.h"
#include "viewer/window/ViewScript.h"
#include "viewer/window/ViewSession.h"
#include "CameraOptions.h"
#include "Commands.h"
#include "PhotometryOptions.h"
#include "SamplerOptions.h"
#include "Plan.h"

#include "core/Error.h"
#include "core/io/AtomicFile.h"

#include <cstdio>
#include <cstdlib>
#include <stdexcept>

namespace ml {

namespace {

// The built-in scenes' units; an OBJ file says nothing, so metres.
LengthUnit defaultUnit(const std::string& sceneArg) {
    if (sceneArg == "cornell") return LengthUnit::Millimetre;  // the measured box is in millimetres
    return LengthUnit::Metre;
}

}  // namespace

int runView(const std::vector<std::string>& args) {
    Options o("view");
    declareSceneOptions(o);
    o.value("width", "W", "window width, pixels", std::string("1280"));
    o.value("height", "H", "window height, pixels", std::string("720"));
    declareCameraOptions(o);
    o.value("script", "FILE", "play camera keyframes and actions from FILE (see viewer/README.md, Scripts), then keep the "
                              "window open unless it says quit");
    o.value("script-step", "S", "script time advances S seconds per frame instead of with the clock (repeatable "
                                "timing for recordings)");
    o.value("samples", "N", "the worker stops after N irradiance samples in all: with the same seed and view, "
                            "the same cache as 'render --samples N'");
    o.value("publish", "S", "the worker publishes a cache snapshot at most every S seconds",
            concat(ViewRefinement::kPublishSeconds));
    o.value("sampling-threads", "T", "sampling threads, each with its own GL context; 0 = one per core (the cache a "
                                     "--samples budget makes is the same for any T)",
            std::string("0"));
    o.value("cache", "FILE", "resume from this cache file if it exists; 'save cache' and the end of the session "
                             "save to it");
    o.value("units", "mm|cm|m", "the scene's length unit, for walking speed, positions and area lights' power (lux "
                                "and punctual lights' power do not depend on it); default mm for cornell, m otherwise");
    declarePhotometryOption(o);
    o.value("efficacy", "LM_PER_W", "luminous efficacy turning irradiance (W/m2) into lux, in place of the "
                                    "photometry's 179 (RADIANCE's equal-energy white)");
    o.value("supersample", "S", "S×S sub-pixels per pixel on screen (1..4; screenshots use the same)",
            std::string("1"));
    o.value("exposure", "EV", "exposure in stops, on top of the metered exposure (metered once, from the first "
                              "snapshot shown)",
            std::string("0"));
    o.flag("no-auto-exposure", "never meter: the exposure is --exposure alone (as render --no-auto-exposure)");
    o.value("tonemap", "OP", "aces, reinhard or clamp", std::string("aces"));
    o.value("max-fps", "F", "draw at most F frames per second (0: no limit)", std::string("60"));
    o.flag("direct-only", "direct light only: no indirect bounces");
    const RealtimeChoice realtime;
    o.value("realtime", "METHOD",
            "what stands in for the cache's indirect light while it catches up after a light or an object moves (and "
            "at the start): volume, vpl or lpv, estimated on a thread of its own from the cache's direct light and "
            "blended into the cache's bounces as they are gathered; auto: the one of those with the least error on "
            "the scene's first complete cache, among the fast enough (vpl until then); off: the old bounces",
            realtime.realtime);
    o.value("indirect-display", "WHAT",
            "the indirect light shown: cache (with the --realtime stand-in), or volume, vpl or lpv: that method's "
            "estimate alone, live (the panel switches too)",
            realtime.display);
    o.value("realtime-bounces", "N", RealtimeChoice::kBouncesHelp, realtime.bouncesText());
    declareDirectOptions(o);
    declareCacheOptions(o);
    declareIndirectOptions(o);
    if (!o.parseOrPrintHelp(args)) return 0;

    ViewSettings s;
    s.width = o.integer("width", 16, 16384);
    s.height = o.integer("height", 16, 16384);
    s.supersample = o.integer("supersample", 1, 4);
    s.direct = readDirectOptions(o);
    if (s.direct.passes != 1)
        throw InputError("view samples each vertex as often as its noise asks: --passes is for probe");
    s.cache = readCacheSettings(o);
    s.indirect = readIndirectOptions(o);
    s.realtime.realtime = o.str("realtime");
    s.realtime.display = o.str("indirect-display");
    s.realtime.methodBounces = RealtimeChoice::parseBounces(o.str("realtime-bounces"));
    s.realtime.validate();
    s.worker.seed = s.direct.seed;
    s.worker.publishSeconds = o.number("publish", 0, 3600);
    s.worker.threads = o.integer("sampling-threads", 0, 256);
    s.worker.refinementLevels = IrradianceCache::kMaxRefinementLevel;
    if (o.has("samples")) s.worker.maxSamples = uint64_t(o.number("samples", 1, 1e15));
    s.cachePath = o.has("cache") ? o.str("cache") : "";
    if (!s.cachePath.empty()) checkOutputDirectory(s.cachePath);
    const std::string sceneArg = o.positionalValue("scene");
    s.unit = o.has("units") ? parseLengthUnit(o.str("units")) : defaultUnit(sceneArg);
    s.photometry = readPhotometryOption(o);
    if (o.has("efficacy")) s.photometry.efficacy = o.number("efficacy", 1e-3, 683);
    s.display.exposureEV = o.number("exposure", -50, 50);
    s.display.autoExposure = !o.isSet("no-auto-exposure");
    s.display.op = parseToneOperator(o.str("tonemap"));
    s.maxFps = o.number("max-fps", 0, 1000);
    if (o.has("script-step")) {
        if (!o.has("script")) throw InputError("--script-step needs --script");
        s.scriptStep = o.number("script-step", 1e-6, 3600);
    }
    // The script is read and checked (against the scene below) before the window opens.
    std::optional<ViewScript> script;
    if (o.has("script")) script = loadViewScript(o.str("script"));

    const Scene scene = loadScene(o);
    for (const std::string& w : scene.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
    if (script) {
        std::vector<std::string> names;
        for (const Light& l : scene.lights) names.push_back(l.name);
        resolveViewScript(*script, names, lightGroups(scene.lights));
        s.script = std::move(*script);
    }
    s.camera = cameraFromOptions(o, scene, double(s.width) / s.height);
    std::printf("scene '%s': %zu meshes, %zu triangles, %zu lights; units %s, photometry %s\n", scene.name.c_str(),
                scene.meshes.size(), scene.triangleCount(), scene.lights.size(), lengthUnitName(s.unit),
                s.photometry.describe().c_str());
    s.indirect.decide(scene);
    printPlan(scene, s.direct, s.cache, s.indirect);
    if (s.indirect.active()) std::printf("  %s\n", s.realtime.describe().c_str());
    if (s.worker.maxSamples)
        std::printf("  the worker stops after %llu samples\n", static_cast<unsigned long long>(s.worker.maxSamples));

    if (!std::getenv("DISPLAY") && !std::getenv("WAYLAND_DISPLAY"))
        throw std::runtime_error("view opens a window and there is no display: run it on a desktop, or under "
                                 "xvfb-run -a -s \"-screen 0 1920x1080x24\"");
    ViewSession session(scene, s);
    std::printf("OpenGL: %s\n", session.glDescription().c_str());
    if (!s.script)
        std::printf("walk with WASD (Q/E down/up, Shift faster), drag to look, R back to the start; Tab hides the "
                    "panel, P pauses refinement, F12 saves an image; close the window or Ctrl-C to quit\n");
    return session.run();
}

}  // namespace ml
