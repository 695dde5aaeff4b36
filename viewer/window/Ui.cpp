#include "Ui.h"

#include "core/Error.h"
#include "WireframeColours.h"
#include "core/image/FalseColour.h"

#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace ml {

namespace {

ImU32 colourU32(const Rgb& c) {
    return ImGui::ColorConvertFloat4ToU32(ImVec4(float(c.r), float(c.g), float(c.b), 1.0f));
}

void copyPath(char* dst, size_t size, const std::string& src) {
    std::snprintf(dst, size, "%s", src.c_str());
}

std::string formatCount(double n) {
    char buf[32];
    if (n >= 1e9)
        std::snprintf(buf, sizeof buf, "%.2fG", n / 1e9);
    else if (n >= 1e6)
        std::snprintf(buf, sizeof buf, "%.2fM", n / 1e6);
    else if (n >= 1e4)
        std::snprintf(buf, sizeof buf, "%.1fk", n / 1e3);
    else
        std::snprintf(buf, sizeof buf, "%.0f", n);
    return buf;
}

// A vertical colour bar of the false-colour scale, 1-2-5 ticks beside it.
void luxLegend(UiModel& m) {
    const DisplayState& d = *m.display;
    ImGuiIO& io = ImGui::GetIO();
    const float barWidth = 22, barHeight = float(legendBarHeight(io.DisplaySize.y));
    const ImGuiStyle& style = ImGui::GetStyle();
    // A size given, not fitted: a fitted window stays hidden in its first
    // frame, and a screenshot right after switching to lux needs the legend.
    const ImVec2 size(barWidth + 150 + 2 * style.WindowPadding.x,
                      barHeight + 4 * ImGui::GetFrameHeightWithSpacing() + 2 * style.WindowPadding.y);
    ImGui::SetNextWindowPos(ImVec2(io.DisplaySize.x - 10, 10), ImGuiCond_Always, ImVec2(1, 0));
    ImGui::SetNextWindowSize(size, ImGuiCond_Always);
    ImGui::SetNextWindowBgAlpha(0.75f);
    ImGui::Begin("Illuminance (lux)", nullptr,
                 ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoFocusOnAppearing | ImGuiWindowFlags_NoMove |
                     ImGuiWindowFlags_NoSavedSettings | ImGuiWindowFlags_NoScrollbar);
    const ImVec2 p = ImGui::GetCursorScreenPos();
    ImDrawList* draw = ImGui::GetWindowDrawList();
    const int steps = 64;
    for (int i = 0; i < steps; ++i) {
        // Top is the high end of the scale.
        const float y0 = p.y + barHeight * float(i) / steps, y1 = p.y + barHeight * float(i + 1) / steps;
        const ImU32 top = colourU32(falseColour(1.0 - double(i) / steps));
        const ImU32 bottom = colourU32(falseColour(1.0 - double(i + 1) / steps));
        draw->AddRectFilledMultiColor(ImVec2(p.x, y0), ImVec2(p.x + barWidth, y1), top, top, bottom, bottom);
    }
    // The levels and labels of the CPU legend (render --quantity lux): FalseColour.h.
    for (const LegendTick& t : legendTicks(d.luxMin, d.luxMax, barHeight, ImGui::GetTextLineHeight())) {
        if (!t.labelled) continue;
        const float y = p.y + barHeight * float(t.position);
        draw->AddLine(ImVec2(p.x + barWidth, y), ImVec2(p.x + barWidth + 6, y), IM_COL32(255, 255, 255, 255));
        draw->AddText(ImVec2(p.x + barWidth + 9, y - ImGui::GetTextLineHeight() * 0.5f), IM_COL32(255, 255, 255, 255),
                      formatLux(t.lux).c_str());
    }
    ImGui::Dummy(ImVec2(barWidth + 70, barHeight));
    ImGui::Text("%s .. %s lx%s", formatLux(d.luxMin).c_str(), formatLux(d.luxMax).c_str(), d.luxAuto ? " (auto)" : "");
    if (m.cursorLux)
        ImGui::Text("cursor: %.4g lx", *m.cursorLux);
    else
        ImGui::TextDisabled("cursor: -");
    ImGui::TextDisabled("%.0f lm/W, %s%s", m.photometry.efficacy, m.photometry.name.c_str(),
                        d.contours ? ", 1-2-5 lines" : "");
    ImGui::End();
}

// Point lights have no emitting faces, so nothing of them is in the image:
// with the wireframe on, each is marked where it is, in its cache mesh's
// colour (the legend's), with its name.
void pointLightMarkers(const UiModel& m) {
    const ImGuiIO& io = ImGui::GetIO();
    Vec3 forward, right, up;
    m.camera.basis(forward, right, up);
    const double t = std::tan(0.5 * m.camera.fovYDegrees * kPi / 180), aspect = io.DisplaySize.x / io.DisplaySize.y;
    ImDrawList* draw = ImGui::GetBackgroundDrawList();
    for (size_t l = 0; l < m.lightInfo.size(); ++l) {
        const ViewLight& v = m.lightInfo[l];
        const Vec3 d = v.position - m.camera.position;
        const double z = glm::dot(d, forward);
        if (!v.point || z <= 0) continue;
        const ImVec2 p(float(0.5 * io.DisplaySize.x * (1 + glm::dot(d, right) / (z * t * aspect))),
                       float(0.5 * io.DisplaySize.y * (1 - glm::dot(d, up) / (z * t))));
        const ImU32 c = colourU32(meshColour(l));
        draw->AddCircle(p, 7, c, 0, 2);
        draw->AddLine(ImVec2(p.x - 11, p.y), ImVec2(p.x + 11, p.y), c, 1.5f);
        draw->AddLine(ImVec2(p.x, p.y - 11), ImVec2(p.x, p.y + 11), c, 1.5f);
        draw->AddText(ImVec2(p.x + 11, p.y + 5), IM_COL32(0, 0, 0, 255), v.name.c_str());  // legible on any image
        draw->AddText(ImVec2(p.x + 10, p.y + 4), c, v.name.c_str());
    }
}

// One light's switch, flux, intensity and colour. True when changed.
bool lightControls(UiModel& m, size_t l) {
    ImGui::PushID(int(l));
    const ViewLight& info = m.lightInfo[l];
    LightControl& c = (*m.lights)[l];
    bool changed = ImGui::Checkbox("##on", &c.on);
    ImGui::SameLine();
    ImGui::Text("%zu '%s' (%s): %.4g lm", l, info.name.c_str(), info.kind.c_str(),
                m.photometry.luminous(info.powerW * c.weight()));
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip("As in the scene: %s,\npower (%.3g, %.3g, %.3g) W, %.4g lm at %.0f lm/W", info.details.c_str(),
                          info.powerW.r, info.powerW.g, info.powerW.b, info.lumens, m.photometry.efficacy);
    float intensity = float(c.intensity);
    if (ImGui::SliderFloat("intensity", &intensity, 0.0f, 10.0f, "%.3f", ImGuiSliderFlags_Logarithmic)) {
        c.intensity = intensity;
        changed = true;
    }
    float colour[3] = {float(c.colour.r), float(c.colour.g), float(c.colour.b)};
    if (ImGui::ColorEdit3("colour", colour, ImGuiColorEditFlags_Float)) {
        c.colour = Rgb(colour[0], colour[1], colour[2]);
        changed = true;
    }
    ImGui::PopID();
    return changed;
}

// A group of lights: one switch and one dimmer for all (ViewLights.h), its
// flux, and its lights' own controls when opened. True when changed.
bool groupControls(UiModel& m, const LightGroup& g) {
    std::vector<LightControl>& lights = *m.lights;
    ImGui::PushID(("group " + g.name).c_str());
    bool changed = false;
    bool on = groupOn(lights, g);
    if (ImGui::Checkbox("##on", &on)) {
        switchGroup(lights, g, on);
        changed = true;
    }
    ImGui::SameLine();
    double lumens = 0, sceneLumens = 0;
    bool alike = true;
    for (size_t l : g.lights) {
        lumens += m.photometry.luminous(m.lightInfo[l].powerW * lights[l].weight());
        sceneLumens += m.lightInfo[l].lumens;
        alike = alike && lights[l].intensity == lights[g.lights[0]].intensity;
    }
    const bool open = ImGui::TreeNode("##lights", "group '%s': %zu lights, %.4g lm", g.name.c_str(), g.lights.size(),
                                      lumens);
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip("%.4g lm as in the scene; the switch and the dimmer set each of its lights", sceneLumens);
    float dimmer = float(lights[g.lights[0]].intensity);
    if (ImGui::SliderFloat("dimmer", &dimmer, 0.0f, 10.0f, alike ? "%.3f" : "%.3f (lights differ)",
                           ImGuiSliderFlags_Logarithmic)) {
        dimGroup(lights, g, std::max(0.0f, dimmer));
        changed = true;
    }
    if (open) {
        for (size_t l : g.lights) changed |= lightControls(m, l);
        ImGui::TreePop();
    }
    ImGui::PopID();
    return changed;
}

// What is shown of indirect light: the cache (with a real-time method
// standing in while it catches up after a move) or a method's own light,
// live, to compare; and which indirect light the image holds now.
void indirectControls(const UiModel& m, UiRequests& r) {
    const std::vector<std::string>& methods = realtimeMethodNames();
    std::vector<std::string> shows = {"cache"};
    shows.insert(shows.end(), methods.begin(), methods.end());
    const RealtimeChoice& c = m.realtime;
    int show = int(std::find(shows.begin(), shows.end(), c.display) - shows.begin());
    std::vector<const char*> showNames;
    for (const std::string& n : shows) showNames.push_back(n.c_str());
    if (ImGui::Combo("indirect light", &show, showNames.data(), int(showNames.size()))) {
        RealtimeChoice next = c;
        next.display = shows[size_t(show)];
        r.realtime = next;
    }
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip("cache: the cache's bounces, a real-time method standing in while they are gathered again\n"
                          "volume, vpl, lpv: that method's estimate alone, live, from the cache's direct light");
    if (c.display == "cache" && c.realtime != "off") {
        // The stand-in: off only from the command line (the worker then
        // starts indirect light at once after a move).
        std::vector<std::string> standIns = {"auto"};
        standIns.insert(standIns.end(), methods.begin(), methods.end());
        int method = int(std::find(standIns.begin(), standIns.end(), c.realtime) - standIns.begin());
        std::vector<const char*> names;
        for (const std::string& n : standIns) names.push_back(n.c_str());
        if (ImGui::Combo("stand-in", &method, names.data(), int(names.size()))) {
            RealtimeChoice next = c;
            next.realtime = standIns[size_t(method)];
            r.realtime = next;
        }
        if (ImGui::IsItemHovered())
            ImGui::SetTooltip("auto: the method with the least error on this scene's first complete cache,\n"
                              "among those whose estimate is fast enough to come before the cache's");
        if (!m.stats.standInChoice.empty()) ImGui::TextWrapped("stand-in: %s", m.stats.standInChoice.c_str());
    }
    ImGui::TextWrapped("indirect shown: %s", m.stats.indirectSource.c_str());
}

}  // namespace

Ui::Ui(GLFWwindow* window, const std::string& screenshotPath, const std::string& cachePath) {
    copyPath(screenshotPath_, sizeof screenshotPath_, screenshotPath);
    copyPath(cachePath_, sizeof cachePath_, cachePath);
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini left in the working folder
    ImGui::StyleColorsDark();
    if (!ImGui_ImplGlfw_InitForOpenGL(window, true)) {
        ImGui::DestroyContext();
        throw std::runtime_error("Dear ImGui: the GLFW back end did not start");
    }
    if (!ImGui_ImplOpenGL3_Init("#version 450")) {
        ImGui_ImplGlfw_Shutdown();
        ImGui::DestroyContext();
        throw std::runtime_error("Dear ImGui: the OpenGL 3 back end did not start (it loads libGL.so.1)");
    }
}

Ui::~Ui() {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
}

bool Ui::wantsMouse() const { return ImGui::GetIO().WantCaptureMouse; }
bool Ui::wantsKeyboard() const { return ImGui::GetIO().WantCaptureKeyboard; }

void Ui::render() {
    ImGui::Render();
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

// A light or an object nudged along x, y or z by a step: the same change
// as the script's `light N move` and `object NAME move` (SceneChange), so
// the cache keeps what stays valid and the real-time stand-in shows while
// it catches up.
void Ui::moveControls(const UiModel& m, UiRequests& r) {
    const size_t lights = m.lightPlaces.size(), targets = lights + m.objects.size();
    if (targets == 0 || !ImGui::CollapsingHeader("Move")) return;
    moveTarget_ = std::clamp(moveTarget_, 0, int(targets) - 1);
    const auto label = [&](size_t t) {
        return t < lights ? concat("light ", t, " '", m.lightInfo[t].name, "'")
                          : concat("object '", m.objects[t - lights], "'");
    };
    if (ImGui::BeginCombo("what", label(size_t(moveTarget_)).c_str())) {
        for (size_t t = 0; t < targets; ++t)
            if (ImGui::Selectable(label(t).c_str(), int(t) == moveTarget_)) moveTarget_ = int(t);
        ImGui::EndCombo();
    }
    const double mpu = metresPerUnit(m.unit);
    ImGui::SliderFloat("step (m)", &moveStep_, 0.001f, 10.0f, "%.3g", ImGuiSliderFlags_Logarithmic);
    const size_t t = size_t(moveTarget_);
    if (t < lights)
        ImGui::Text("at %.4g, %.4g, %.4g %s", m.lightPlaces[t].x, m.lightPlaces[t].y, m.lightPlaces[t].z,
                    lengthUnitName(m.unit));
    ImGui::BeginDisabled(m.changing);
    const char* names[] = {"x", "y", "z"};
    for (int axis = 0; axis < 3; ++axis)
        for (int sign : {-1, 1}) {
            if (axis || sign > 0) ImGui::SameLine();
            if (!ImGui::Button(concat(sign < 0 ? "-" : "+", names[axis]).c_str())) continue;
            Vec3 by(0.0);
            by[axis] = sign * double(moveStep_) / mpu;
            r.sceneChange = t < lights ? SceneChange::moveLight(t, m.lightPlaces[t] + by)
                                       : SceneChange::moveObject(m.objects[t - lights], by);
        }
    ImGui::EndDisabled();
    if (m.changing) ImGui::TextDisabled("applying the last move...");
}

UiRequests Ui::build(UiModel& m) {
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    UiRequests r;
    DisplayState& d = *m.display;

    if (!m.error.empty()) {
        const ImGuiIO& io = ImGui::GetIO();
        ImGui::SetNextWindowPos(ImVec2(io.DisplaySize.x * 0.5f, io.DisplaySize.y - 10), ImGuiCond_Always,
                                ImVec2(0.5f, 1));
        ImGui::SetNextWindowBgAlpha(0.9f);
        ImGui::Begin("Refinement failed", nullptr,
                     ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoSavedSettings);
        ImGui::PushStyleColor(ImGuiCol_Text, IM_COL32(255, 90, 90, 255));
        ImGui::PushTextWrapPos(std::max(300.0f, io.DisplaySize.x * 0.6f));
        ImGui::TextUnformatted(("Refinement failed; the image shows the last snapshot.\n" + m.error).c_str());
        ImGui::PopTextWrapPos();
        ImGui::PopStyleColor();
        ImGui::End();
    }
    if (d.mode == DisplayMode::Illuminance) luxLegend(m);
    if (d.wireframe) pointLightMarkers(m);
    if (!d.showUi) return r;

    ImGui::SetNextWindowPos(ImVec2(10, 10), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(370, 0), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowBgAlpha(0.85f);
    ImGui::Begin("Meshlight", nullptr, ImGuiWindowFlags_NoSavedSettings);

    // --- Progress -------------------------------------------------------------
    const UiStats& s = m.stats;
    ImGui::Text("%.1f s   %.0f frames/s (%.1f ms, composite %.1f ms)", s.elapsed, s.fps, s.frameMs, s.composeMs);
    if (s.snapshot) {
        ImGui::Text("%s vertices, %s triangles (%s in view), %s samples", formatCount(double(s.vertices)).c_str(),
                    formatCount(double(s.triangles)).c_str(), formatCount(double(s.drawnTriangles)).c_str(),
                    formatCount(double(s.samples)).c_str());
        if (s.estimatedError >= 1)  // every light's and bounce's first pass not yet done (FrameStatistics)
            ImGui::Text("error not estimated yet, round %llu, worker %.1f s",
                        static_cast<unsigned long long>(s.rounds), s.workerSeconds);
        else
            ImGui::Text("estimated error %.2f%%, round %llu, worker %.1f s", 100 * s.estimatedError,
                        static_cast<unsigned long long>(s.rounds), s.workerSeconds);
    } else {
        ImGui::TextDisabled("waiting for the first cache snapshot...");
    }
    const char* state = s.saving ? "saving the cache" : s.finished ? "refinement ended" : s.paused ? "paused"
                                                      : s.converged ? "converged for this view" : "refining";
    ImGui::Text("%s%s", state, s.uploadProgress < 1 ? concat(" (copying a snapshot: ",
                                                             int(100 * s.uploadProgress), "%)").c_str() : "");
    if (!s.finished && !s.saving) {
        if (ImGui::Button(s.paused ? "Resume refinement (P)" : "Pause refinement (P)")) r.pause = !s.paused;
    }
    if (!m.message.empty()) ImGui::TextWrapped("%s", m.message.c_str());

    // --- Display --------------------------------------------------------------
    if (ImGui::CollapsingHeader("Display", ImGuiTreeNodeFlags_DefaultOpen)) {
        int mode = int(d.mode);
        const char* modes[] = {"final", "direct only", "indirect only", "one light alone", "reflectance",
                               "illuminance (lux)"};
        if (ImGui::Combo("mode", &mode, modes, IM_ARRAYSIZE(modes))) d.mode = DisplayMode(mode);
        if (d.mode == DisplayMode::Light && !m.lightInfo.empty()) {
            int light = int(std::min(d.light, m.lightInfo.size() - 1));
            const ViewLight& shown = m.lightInfo[size_t(light)];
            if (ImGui::SliderInt("light", &light, 0, int(m.lightInfo.size()) - 1,
                                 concat(shown.name, " (", shown.kind, ")").c_str()))
                d.light = size_t(light);
        }
        if (d.mode == DisplayMode::Indirect && s.indirectMeshes == 0)
            ImGui::TextDisabled("no indirect light cached (yet)");
        if (!s.indirectSource.empty()) indirectControls(m, r);
        ImGui::Checkbox("cache wireframe", &d.wireframe);
        if (d.wireframe)
            for (const auto& [name, colour] : m.meshColours) {
                ImGui::ColorButton(name.c_str(), ImVec4(float(colour.r), float(colour.g), float(colour.b), 1),
                                   ImGuiColorEditFlags_NoTooltip, ImVec2(12, 12));
                ImGui::SameLine();
                ImGui::TextUnformatted(name.c_str());
            }
        if (d.mode == DisplayMode::Illuminance) {
            ImGui::Checkbox("iso-lux lines (1-2-5)", &d.contours);
            if (ImGui::Checkbox("auto range", &d.luxAuto) && d.luxAuto) r.meterLux = true;
            float range[2] = {float(d.luxMin), float(d.luxMax)};
            if (ImGui::DragFloat2("range (lx)", range, 1.0f, 1e-3f, 1e7f, "%.3g", ImGuiSliderFlags_Logarithmic) &&
                range[0] > 0 && range[1] > range[0]) {
                d.luxMin = range[0], d.luxMax = range[1];
                d.luxAuto = false;
            }
        } else if (d.mode != DisplayMode::Reflectance) {
            float ev = float(d.exposureEV);
            if (ImGui::SliderFloat("exposure (EV)", &ev, -10, 10, "%+.1f")) d.exposureEV = ev;
            ImGui::SameLine();
            if (ImGui::Button("meter")) r.meterExposure = true;
            int op = int(d.op);
            const char* ops[] = {"ACES", "Reinhard", "clamp"};
            if (ImGui::Combo("tone map", &op, ops, IM_ARRAYSIZE(ops))) d.op = ToneOperator(op);
        }
        int ss = m.supersample;
        if (ImGui::SliderInt("sub-pixels", &ss, 1, 4, "%d per side")) r.supersample = ss;
    }

    // --- Lights ---------------------------------------------------------------
    if (ImGui::CollapsingHeader("Lights", ImGuiTreeNodeFlags_DefaultOpen)) {
        for (const LightGroup& g : m.groups) {
            if (g.lights.size() == 1)
                r.lightsChanged |= lightControls(m, g.lights[0]);
            else
                r.lightsChanged |= groupControls(m, g);
        }
        ImGui::TextWrapped("Indirect light x(%.2f, %.2f, %.2f): the lights' power-weighted mean, exact when all "
                           "lights change alike (it is cached per bounce, not per light).",
                           m.indirectWeight.r, m.indirectWeight.g, m.indirectWeight.b);
        if (!m.sharedLights.empty()) ImGui::TextWrapped("%s", m.sharedLights.c_str());
    }

    moveControls(m, r);

    // --- Walking --------------------------------------------------------------
    if (ImGui::CollapsingHeader("Camera")) {
        const double mpu = metresPerUnit(m.unit);
        ImGui::Text("position %.4g, %.4g, %.4g %s", m.camera.position.x, m.camera.position.y, m.camera.position.z,
                    lengthUnitName(m.unit));
        ImGui::Text("speed %.3g m/s (wheel to change, Shift x4, Ctrl x1/4)", m.speed * mpu);
        ImGui::TextDisabled("WASD walk, Q/E down/up, drag to look, R reset");
        if (ImGui::Button("slower")) r.speedFactor = 0.5;
        ImGui::SameLine();
        if (ImGui::Button("faster")) r.speedFactor = 2;
        ImGui::SameLine();
        if (ImGui::Button("reset camera (R)")) r.resetCamera = true;
    }

    // --- Files ----------------------------------------------------------------
    if (ImGui::CollapsingHeader("Save")) {
        ImGui::InputText("image", screenshotPath_, sizeof screenshotPath_);
        if (ImGui::Button("save image (F12)")) r.screenshot = std::string(screenshotPath_);
        ImGui::SameLine();
        ImGui::TextDisabled(".png as shown, .exr linear");
        ImGui::InputText("cache", cachePath_, sizeof cachePath_);
        if (ImGui::Button("save cache") && !s.saving) r.saveCache = std::string(cachePath_);
    }
    ImGui::End();
    return r;
}

}  // namespace ml
