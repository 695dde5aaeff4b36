#include "Commands.h"
#include "Options.h"

#include "core/loaders/GltfLoader.h"
#include "core/loaders/LuminaireLayout.h"
#include "core/loaders/ObjLoader.h"
#include "core/scenes/BenchScene.h"
#include "core/scenes/CornellBox.h"
#include "core/scenes/OfficeScene.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

namespace ml {

namespace {

// ".gltf" and ".glb" in any case (Windows exporters write ".GLB").
bool isGltfPath(const std::string& arg) {
    std::string ext = std::filesystem::path(arg).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return ext == ".gltf" || ext == ".glb";
}

}  // namespace

Scene loadSceneArgument(const std::string& arg) {
    if (arg == "cornell") return makeCornellBox();
    if (arg == "bench") return makeBenchScene();
    if (arg == "office" || arg.rfind("office:", 0) == 0) return makeOfficeScene(parseOfficeSpec(arg));
    if (isGltfPath(arg)) return loadGltf(arg);
    return loadObj(arg);
}

void declareSceneOptions(Options& o) {
    o.positional("scene", kSceneArgumentHelp);
    o.value("luminaires", "FILE.csv",
            "add photometric luminaires (IES LM-63 .ies, EULUMDAT .ldt) placed by a layout file: columns file,x,y,z "
            "and optionally aim_x,aim_y,aim_z, rotation, multiplier, group, name (core/loaders/LuminaireLayout.h)");
}

Scene loadScene(const Options& o) {
    Scene scene = loadSceneArgument(o.positionalValue("scene"));
    if (o.has("luminaires")) addLuminaireLayout(scene, o.str("luminaires"));
    return scene;
}

}  // namespace ml
