#include "Commands.h"

#include "core/loaders/ObjLoader.h"
#include "core/scenes/BenchScene.h"
#include "core/scenes/CornellBox.h"
#include "core/scenes/OfficeScene.h"

namespace ml {

Scene loadSceneArgument(const std::string& arg) {
    if (arg == "cornell") return makeCornellBox();
    if (arg == "bench") return makeBenchScene();
    if (arg == "office" || arg.rfind("office:", 0) == 0) return makeOfficeScene(parseOfficeSpec(arg));
    return loadObj(arg);
}

}  // namespace ml
