#include "Commands.h"

#include "core/loaders/ObjLoader.h"
#include "core/scenes/BenchScene.h"
#include "core/scenes/CornellBox.h"

namespace ml {

Scene loadSceneArgument(const std::string& arg) {
    if (arg == "cornell") return makeCornellBox();
    if (arg == "bench") return makeBenchScene();
    return loadObj(arg);
}

}  // namespace ml
