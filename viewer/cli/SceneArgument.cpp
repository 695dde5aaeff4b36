#include "Commands.h"

#include "core/loaders/GltfLoader.h"
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

}  // namespace ml
