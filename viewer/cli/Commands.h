// The subcommands of the `meshlight` binary. Each parses its own options
// (see Options.h), returns the process exit code and lets InputError escape
// for main() to report.
#pragma once

#include "core/Scene.h"

#include <string>
#include <vector>

namespace ml {

int runRender(const std::vector<std::string>& args);
int runProbe(const std::vector<std::string>& args);
int runGrid(const std::vector<std::string>& args);
int runBench(const std::vector<std::string>& args);
int runPlan(const std::vector<std::string>& args);
int runReference(const std::vector<std::string>& args);
int runView(const std::vector<std::string>& args);

// Where `reference` writes the standard error of its image OUT: the same
// folder and extension, ".noise" before it ("ref.exr" -> "ref.noise.exr").
std::string referenceNoisePath(const std::string& out);

// What a command's <scene> argument may be, for its usage text.
inline constexpr const char* kSceneArgumentHelp =
    "cornell, office[:KEY=VALUE,...], bench, an OBJ or a glTF (.gltf, .glb) file";
// A scene argument: "cornell" (the built-in measured Cornell box), "bench"
// (the paper's §6.1 bench scene), "office[:...]" (OfficeScene.h) or the path
// of an OBJ or glTF file.
Scene loadSceneArgument(const std::string& arg);

class Options;
// The scene every command takes: the positional <scene> and what may be
// added to it (--luminaires FILE: photometric luminaires placed by a layout
// file, core/loaders/LuminaireLayout.h). Declared and read in one place.
void declareSceneOptions(Options& o);
Scene loadScene(const Options& o);

}  // namespace ml
