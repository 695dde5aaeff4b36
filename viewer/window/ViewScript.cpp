#include "ViewScript.h"

#include "core/image/Image.h"
#include "core/io/AtomicFile.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

namespace ml {

namespace {

using Kind = ScriptAction::Kind;

const char* const kActions =
    "camera, wait, wait-samples, wait-error, wait-done, mode, wireframe, contours, ui, light, group, exposure, tonemap, "
    "lux-range, pause, resume, screenshot, save-cache, quit, object, indirect";

double parseNumber(const std::string& token, const std::string& what, const SourceLocation& where) {
    errno = 0;
    char* end = nullptr;
    const double v = std::strtod(token.c_str(), &end);
    if (token.empty() || end != token.c_str() + token.size() || errno == ERANGE || !std::isfinite(v))
        throwInputError(where, what, " '", token, "' is not a finite number");
    return v;
}

Vec3 parseVec3(const std::string& token, const std::string& what, const SourceLocation& where) {
    std::vector<std::string> parts;
    std::string part;
    std::istringstream in(token);
    while (std::getline(in, part, ',')) parts.push_back(part);
    if (parts.size() != 3 || token.back() == ',')
        throwInputError(where, what, " '", token, "' is not three numbers X,Y,Z");
    return Vec3(parseNumber(parts[0], what, where), parseNumber(parts[1], what, where),
                parseNumber(parts[2], what, where));
}

bool parseOnOff(const std::string& token, const std::string& action, const SourceLocation& where) {
    if (token == "on") return true;
    if (token == "off") return false;
    throwInputError(where, "'", action, "' takes on or off, not '", token, "'");
}

void expectArguments(const std::vector<std::string>& t, size_t lo, size_t hi, const std::string& usage,
                     const SourceLocation& where) {
    const size_t n = t.size() - 1;
    if (n < lo || n > hi) throwInputError(where, "'", t[0], "' takes ", usage, ", got ", n, n == 1 ? " argument" : " arguments");
}

ScriptAction parseCamera(const std::vector<std::string>& t, const SourceLocation& where) {
    ScriptAction a;
    a.kind = Kind::Camera;
    std::map<std::string, std::string> keys;
    for (size_t i = 1; i < t.size(); ++i) {
        const size_t eq = t[i].find('=');
        if (eq == std::string::npos || eq == 0)
            throwInputError(where, "camera: '", t[i], "' is not KEY=VALUE (keys: t or in, pos, target, up, fov)");
        const std::string key = t[i].substr(0, eq);
        if (key != "t" && key != "in" && key != "pos" && key != "target" && key != "up" && key != "fov")
            throwInputError(where, "camera: unknown key '", key, "' (keys: t or in, pos, target, up, fov)");
        if (!keys.emplace(key, t[i].substr(eq + 1)).second) throwInputError(where, "camera: '", key, "' given twice");
    }
    if (keys.count("t") == keys.count("in") || !keys.count("pos") || !keys.count("target"))
        throwInputError(where, "camera needs t=SECONDS (or in=SECONDS), pos=X,Y,Z and target=X,Y,Z");
    a.relative = keys.count("in") > 0;
    const std::string timeKey = a.relative ? "in" : "t";
    a.time = parseNumber(keys[timeKey], "camera time " + timeKey, where);
    if (a.time < 0) throwInputError(where, "camera time ", timeKey, "=", keys[timeKey], " is negative");
    a.position = parseVec3(keys["pos"], "camera pos", where);
    a.target = parseVec3(keys["target"], "camera target", where);
    if (keys.count("up")) a.up = parseVec3(keys["up"], "camera up", where);
    if (keys.count("fov")) a.fov = parseNumber(keys["fov"], "camera fov", where);
    // What can be checked without the camera it starts from.
    Camera c;
    c.position = a.position;
    c.target = a.target;
    c.up = a.up.value_or(Vec3(0.0, 1.0, 0.0));
    c.fovYDegrees = a.fov.value_or(40.0);
    if (!a.up) {
        // Any up not parallel to the view will do for the check.
        const Vec3 d = glm::normalize(c.target - c.position);
        if (glm::length(d) > 0 && std::abs(d.y) > 0.99) c.up = Vec3(1.0, 0.0, 0.0);
    }
    try {
        c.validate();
    } catch (const InputError& e) {
        throwInputError(where, e.what());
    }
    return a;
}

// What `light N ...` or `group NAME ...` changes, from t[2] on: on, off,
// `scale` X (its intensity: "intensity" or "dim") or, with `colour`, color R,G,B.
void parseLightChange(const std::vector<std::string>& t, const std::string& scale, bool colour, ScriptAction& a,
                      const SourceLocation& where) {
    const std::string& what = t[2];
    const std::string line = concat("'", t[0], " ", t[1], " ", what, "'");
    if (what == "on" || what == "off") {
        if (t.size() != 3) throwInputError(where, line, " takes no further argument");
        a.change = what == "on" ? ScriptAction::LightChange::On : ScriptAction::LightChange::Off;
    } else if (what == scale) {
        if (t.size() != 4) throwInputError(where, line, " takes one number");
        a.change = ScriptAction::LightChange::Intensity;
        a.number = parseNumber(t[3], t[0] + " " + scale, where);
        if (a.number < 0 || a.number > 1e6) throwInputError(where, t[0], " ", scale, " ", t[3], " is not within 0..1e6");
    } else if (colour && (what == "color" || what == "colour")) {
        if (t.size() != 4) throwInputError(where, line, " takes R,G,B");
        a.change = ScriptAction::LightChange::Colour;
        a.colour = parseVec3(t[3], t[0] + " color", where);
        if (a.colour.r < 0 || a.colour.g < 0 || a.colour.b < 0)
            throwInputError(where, t[0], " color ", t[3], " has a negative component");
    } else {
        throwInputError(where, "unknown ", t[0], " change '", what, "' (use ",
                        colour ? concat("on, off, ", scale, " X or color R,G,B") : concat("on, off or ", scale, " F"),
                        ")");
    }
}

ScriptAction parseLine(const std::vector<std::string>& t, const SourceLocation& where) {
    ScriptAction a;
    a.where = where;
    const std::string& name = t[0];
    if (name == "camera") {
        a = parseCamera(t, where);
    } else if (name == "wait") {
        expectArguments(t, 1, 1, "SECONDS", where);
        a.kind = Kind::Wait;
        a.number = parseNumber(t[1], "wait", where);
        if (a.number < 0) throwInputError(where, "wait ", t[1], " is negative");
    } else if (name == "wait-samples") {
        expectArguments(t, 1, 1, "a number of samples N", where);
        a.kind = Kind::WaitSamples;
        const double n = parseNumber(t[1], "wait-samples", where);
        if (n < 1 || n != std::floor(n) || n > 1e15)
            throwInputError(where, "wait-samples ", t[1], " is not a whole number from 1 to 1e15");
        a.samples = uint64_t(n);
    } else if (name == "wait-error") {
        expectArguments(t, 1, 1, "an estimated error E", where);
        a.kind = Kind::WaitError;
        a.number = parseNumber(t[1], "wait-error", where);
        if (!(a.number > 0 && a.number <= 1)) throwInputError(where, "wait-error ", t[1], " is not within (0, 1]");
    } else if (name == "wait-done") {
        expectArguments(t, 0, 0, "no argument", where);
        a.kind = Kind::WaitDone;
    } else if (name == "mode") {
        expectArguments(t, 1, 2, "final, direct, indirect, reflectance, lux, wireframe or light N", where);
        a.kind = Kind::Mode;
        const std::string& m = t[1];
        if (m == "light") {
            if (t.size() != 3) throwInputError(where, "'mode light' needs the light: an index from 0 or a name");
            a.mode = DisplayMode::Light;
            a.lightName = t[2];
        } else {
            if (t.size() != 2) throwInputError(where, "'mode ", m, "' takes no further argument");
            if (m == "final") a.mode = DisplayMode::Final;
            else if (m == "direct") a.mode = DisplayMode::Direct;
            else if (m == "indirect") a.mode = DisplayMode::Indirect;
            else if (m == "reflectance") a.mode = DisplayMode::Reflectance;
            else if (m == "lux") a.mode = DisplayMode::Illuminance;
            else if (m == "wireframe") a.mode = DisplayMode::Final, a.flag = true;
            else
                throwInputError(where, "unknown mode '", m,
                                "' (use final, direct, indirect, reflectance, lux, wireframe or light N)");
        }
    } else if (name == "wireframe" || name == "contours" || name == "ui") {
        expectArguments(t, 1, 1, "on or off", where);
        a.kind = name == "wireframe" ? Kind::Wireframe : name == "contours" ? Kind::Contours : Kind::Ui;
        a.flag = parseOnOff(t[1], name, where);
    } else if (name == "light" && t.size() >= 3 && (t[2] == "move" || t[2] == "aim")) {
        if (t.size() != 4) throwInputError(where, "'light ", t[1], " ", t[2], "' takes X,Y,Z");
        a.kind = Kind::Change;
        a.lightName = t[1];
        const Vec3 p = parseVec3(t[3], "light " + t[2], where);
        a.sceneChange = t[2] == "move" ? SceneChange::moveLight(0, p) : SceneChange::aimLight(0, p);
    } else if (name == "light") {
        if (t.size() < 3)
            throwInputError(where, "'light' takes the light (index or name) and on, off, intensity X, color R,G,B, "
                                   "move X,Y,Z or aim X,Y,Z");
        a.kind = Kind::Light;
        a.lightName = t[1];
        parseLightChange(t, "intensity", true, a, where);
    } else if (name == "object") {
        const bool move = t.size() >= 3 && t[2] == "move", rotate = t.size() >= 3 && t[2] == "rotate";
        if (!move && !rotate) throwInputError(where, "'object' takes the object's name and move DX,DY,DZ or rotate AX,AY,AZ DEG");
        if (move && t.size() != 4) throwInputError(where, "'object ", t[1], " move' takes DX,DY,DZ");
        if (rotate && t.size() != 5) throwInputError(where, "'object ", t[1], " rotate' takes AX,AY,AZ and DEG");
        a.kind = Kind::Change;
        a.sceneChange = move ? SceneChange::moveObject(t[1], parseVec3(t[3], "object move", where))
                             : SceneChange::rotateObject(t[1], parseVec3(t[3], "object rotate axis", where),
                                                         parseNumber(t[4], "object rotate DEG", where));
        if (rotate && !(glm::length(a.sceneChange.axis) > 0))
            throwInputError(where, "object rotate: the axis ", t[3], " is zero");
    } else if (name == "group") {
        if (t.size() < 3) throwInputError(where, "'group' takes the group's name and on, off or dim F");
        a.kind = Kind::Group;
        a.lightName = t[1];
        parseLightChange(t, "dim", false, a, where);
    } else if (name == "exposure") {
        expectArguments(t, 1, 1, "stops EV or auto", where);
        if (t[1] == "auto") {
            a.kind = Kind::ExposureAuto;
        } else {
            a.kind = Kind::Exposure;
            a.number = parseNumber(t[1], "exposure", where);
            if (std::abs(a.number) > 50) throwInputError(where, "exposure ", t[1], " is not within -50..50 stops");
        }
    } else if (name == "tonemap") {
        expectArguments(t, 1, 1, "aces, reinhard or clamp", where);
        a.kind = Kind::Tonemap;
        try {
            a.op = parseToneOperator(t[1]);
        } catch (const InputError& e) {
            throwInputError(where, e.what());
        }
    } else if (name == "lux-range") {
        expectArguments(t, 1, 2, "MIN MAX (lux) or auto", where);
        if (t[1] == "auto") {
            if (t.size() != 2) throwInputError(where, "'lux-range auto' takes no further argument");
            a.kind = Kind::LuxRangeAuto;
        } else {
            if (t.size() != 3) throwInputError(where, "'lux-range' takes MIN MAX (lux) or auto");
            a.kind = Kind::LuxRange;
            a.number = parseNumber(t[1], "lux-range minimum", where);
            a.number2 = parseNumber(t[2], "lux-range maximum", where);
            if (!(a.number > 0 && a.number2 > a.number))
                throwInputError(where, "lux-range ", t[1], " ", t[2], ": needs 0 < MIN < MAX");
        }
    } else if (name == "indirect") {
        expectArguments(t, 1, 1, "cache, volume, vpl or lpv", where);
        if (t[1] != "cache" && t[1] != "volume" && t[1] != "vpl" && t[1] != "lpv")
            throwInputError(where, "indirect '", t[1], "': expected cache, volume, vpl or lpv");
        a.kind = Kind::Indirect;
        a.path = t[1];
    } else if (name == "pause" || name == "resume" || name == "quit") {
        expectArguments(t, 0, 0, "no argument", where);
        a.kind = name == "pause" ? Kind::Pause : name == "resume" ? Kind::Resume : Kind::Quit;
    } else if (name == "screenshot" || name == "save-cache") {
        expectArguments(t, 1, 1, "a file name", where);
        a.kind = name == "screenshot" ? Kind::Screenshot : Kind::SaveCache;
        a.path = t[1];
        if (a.kind == Kind::Screenshot) {
            try {
                outputFormat(a.path);
            } catch (const InputError& e) {
                throwInputError(where, "screenshot: ", e.what());
            }
        }
    } else {
        throwInputError(where, "unknown action '", name, "' (actions: ", kActions, ")");
    }
    a.where = where;
    return a;
}

// A line's words: separated by white space, a "quoted name" one word with
// its spaces, a '#' at the start of a word the start of a comment ("Panel#2"
// is a name, as Scene::finalize names lights).
std::vector<std::string> splitWords(const std::string& line, const SourceLocation& where) {
    std::vector<std::string> words;
    size_t i = 0;
    const auto space = [](char c) { return c == ' ' || c == '\t' || c == '\r'; };
    while (i < line.size()) {
        if (space(line[i])) {
            ++i;
            continue;
        }
        if (line[i] == '#') break;
        if (line[i] == '"') {
            const size_t close = line.find('"', i + 1);
            if (close == std::string::npos) throwInputError(where, "a quoted name has no closing '\"'");
            words.push_back(line.substr(i + 1, close - i - 1));
            i = close + 1;
            if (i < line.size() && !space(line[i]))
                throwInputError(where, "'", line.substr(close + 1), "' follows a quoted name without a space");
            continue;
        }
        const size_t start = i;
        while (i < line.size() && !space(line[i])) ++i;
        words.push_back(line.substr(start, i - start));
    }
    return words;
}

}  // namespace

ViewScript parseViewScript(const std::string& text, const std::string& file) {
    ViewScript script;
    script.file = file;
    std::istringstream in(text);
    std::string line;
    int number = 0;
    std::optional<size_t> lastKeyframe;  // index of the last camera line so far
    while (std::getline(in, line)) {
        ++number;
        const SourceLocation where{file, number};
        const std::vector<std::string> tokens = splitWords(line, where);
        if (tokens.empty()) continue;
        ScriptAction a = parseLine(tokens, where);
        if (a.kind == Kind::Camera && !a.relative) {
            if (lastKeyframe) {
                const ScriptAction& before = script.actions[*lastKeyframe];
                if (a.time < before.time)
                    throwInputError(where, "camera t=", a.time, " comes before the keyframe at line ",
                                    before.where.line, " (t=", before.time, "): times never decrease");
            }
            lastKeyframe = script.actions.size();
        }
        script.actions.push_back(std::move(a));
    }
    return script;
}

ViewScript loadViewScript(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw InputError(SourceLocation{path, 0}, "cannot read the script");
    std::ostringstream text;
    text << in.rdbuf();
    return parseViewScript(text.str(), path);
}

void resolveViewScript(ViewScript& script, const std::vector<std::string>& lightNames,
                       const std::vector<LightGroup>& groups) {
    for (ScriptAction& a : script.actions) {
        if (a.kind == Kind::Group) {
            const auto g = std::find_if(groups.begin(), groups.end(),
                                        [&](const LightGroup& x) { return x.name == a.lightName; });
            if (g == groups.end())
                throwInputError(a.where, "no light group '", a.lightName, "' in the scene (",
                                groups.empty() ? std::string("it has no lights") : "groups: " + describeGroups(groups),
                                ")");
            a.group = *g;
        }
        const bool namesLight = a.kind == Kind::Light || (a.kind == Kind::Mode && a.mode == DisplayMode::Light) ||
                                (a.kind == Kind::Change && a.sceneChange.movesLight());
        if (namesLight) {
            bool found = false;
            for (size_t l = 0; l < lightNames.size() && !found; ++l)
                if (lightNames[l] == a.lightName) a.light = l, found = true;
            if (!found) {
                char* end = nullptr;
                const long index = std::strtol(a.lightName.c_str(), &end, 10);
                if (!a.lightName.empty() && *end == '\0' && index >= 0 && size_t(index) < lightNames.size())
                    a.light = size_t(index), found = true;
            }
            if (!found) {
                std::string names;
                for (size_t l = 0; l < lightNames.size(); ++l)
                    names += concat(l ? ", " : "", l, " '", lightNames[l], "'");
                throwInputError(a.where, "no light '", a.lightName, "' in the scene (",
                                lightNames.empty() ? std::string("it has none") : "lights: " + names, ")");
            }
        }
        try {
            if (a.kind == Kind::Screenshot) checkOutputPath(a.path);
            if (a.kind == Kind::SaveCache) checkOutputDirectory(a.path);
        } catch (const InputError& e) {
            throwInputError(a.where, e.what());
        }
    }
}

Camera interpolateCamera(const Camera& from, const Camera& to, double a) {
    if (a >= 1) return to;
    a = std::max(a, 0.0);
    Camera c;
    c.position = glm::mix(from.position, to.position, a);
    c.target = glm::mix(from.target, to.target, a);
    c.up = glm::mix(from.up, to.up, a);
    c.fovYDegrees = from.fovYDegrees + (to.fovYDegrees - from.fovYDegrees) * a;
    try {
        c.validate();
    } catch (const InputError&) {
        // Halfway between opposite ups, or a target crossing the eye: hold
        // the pose it came from for this frame.
        return from;
    }
    return c;
}

std::string ScriptPlayer::where() const {
    if (finished()) return script_.file + ": end";
    return script_.actions[next_].where.str();
}

void ScriptPlayer::advance(double now, ScriptHost& host) {
    while (next_ < script_.actions.size()) {
        bool endFrame = false;
        if (!run(script_.actions[next_], now, host, endFrame)) return;
        ++next_;
        started_ = false;
        if (endFrame) return;
    }
}

bool ScriptPlayer::run(const ScriptAction& a, double now, ScriptHost& host, bool& endFrame) {
    const bool first = !started_;
    if (first) {
        started_ = true;
        startedAt = now;
    }
    DisplayState& d = host.display();
    switch (a.kind) {
        case Kind::Camera: {
            if (first) from_ = host.camera();
            Camera to;
            to.position = a.position;
            to.target = a.target;
            to.up = a.up.value_or(from_.up);
            to.fovYDegrees = a.fov.value_or(from_.fovYDegrees);
            const double arrival = a.relative ? startedAt + a.time : a.time;
            if (now >= arrival || arrival <= startedAt) {
                try {
                    to.validate();
                } catch (const InputError& e) {
                    throwInputError(a.where, e.what(), " (up taken from the camera before)");
                }
                host.setCamera(to);
                return true;
            }
            host.setCamera(interpolateCamera(from_, to, (now - startedAt) / (arrival - startedAt)));
            return false;
        }
        case Kind::Wait: return now - startedAt >= a.number;
        case Kind::WaitSamples: return host.shownSamples() >= a.samples || host.refinementDone();
        case Kind::WaitError: return host.shownError() <= a.number || host.refinementDone();
        case Kind::WaitDone: return host.refinementDone();
        case Kind::Mode:
            d.mode = a.mode;
            if (a.mode == DisplayMode::Light) d.light = a.light;
            if (a.flag) d.wireframe = true;
            return true;
        case Kind::Wireframe: d.wireframe = a.flag; return true;
        case Kind::Contours: d.contours = a.flag; return true;
        case Kind::Ui: d.showUi = a.flag; return true;
        case Kind::Light: {
            LightControl& l = host.lights().at(a.light);
            switch (a.change) {
                case ScriptAction::LightChange::On: l.on = true; break;
                case ScriptAction::LightChange::Off: l.on = false; break;
                case ScriptAction::LightChange::Intensity: l.intensity = a.number; break;
                case ScriptAction::LightChange::Colour: l.colour = a.colour; break;
            }
            host.lightsChanged();
            return true;
        }
        case Kind::Group:
            if (a.change == ScriptAction::LightChange::Intensity)
                dimGroup(host.lights(), a.group, a.number);
            else
                switchGroup(host.lights(), a.group, a.change == ScriptAction::LightChange::On);
            host.lightsChanged();
            return true;
        case Kind::Exposure: d.exposureEV = a.number; return true;
        case Kind::ExposureAuto: host.meterExposure(); return true;
        case Kind::Tonemap: d.op = a.op; return true;
        case Kind::LuxRange:
            d.luxAuto = false;
            d.luxMin = a.number;
            d.luxMax = a.number2;
            return true;
        case Kind::LuxRangeAuto:
            d.luxAuto = true;
            host.meterLuxRange();
            return true;
        case Kind::Indirect: host.setIndirectDisplay(a.path); return true;
        case Kind::Pause: host.setPaused(true); return true;
        case Kind::Resume: host.setPaused(false); return true;
        case Kind::Screenshot:
            host.screenshot(a.path);
            endFrame = true;
            return true;
        case Kind::SaveCache:
            if (first) host.saveCache(a.path);
            return !host.busySaving();
        case Kind::Quit:
            host.quit();
            endFrame = true;
            return true;
        case Kind::Change: {
            SceneChange c = a.sceneChange;
            c.where = a.where;
            if (c.movesLight()) c.light = a.light;
            return host.changeScene(c);
        }
    }
    return true;
}

}  // namespace ml
