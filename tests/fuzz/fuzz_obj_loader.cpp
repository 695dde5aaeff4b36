// libFuzzer target for the OBJ/MTL loader (loadObj) and what it runs on the
// meshes it reads: degenerate-triangle removal, shading normals, lights.
//
// Input: the OBJ text, optionally followed by a NUL byte and the MTL text.
// Both are served from memory (loadObj's reader overload), the OBJ as
// "fuzz/scene.obj" and the MTL as every library it names; without a NUL,
// no library can be opened. The crease angle (0, 30, 90 or 180 degrees)
// follows the input's length, so every corpus file meets several of them as
// it is mutated.
//
// An InputError is the loader refusing bad input: a normal outcome. Any other
// exception, a broken promise of ObjLoader.h or Scene.h about the scene it
// returns, a crash, a sanitizer report, a leak or a hang is a finding.
#include "core/Error.h"
#include "core/loaders/ObjLoader.h"
#include "SceneChecks.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <string_view>

namespace {

constexpr const char* kTarget = "fuzz_obj_loader";

[[noreturn]] void finding(const std::string& what) { ml::fuzz::finding(kTarget, what); }

// SceneChecks.h's promises, and ObjLoader.h's: every triangle names its
// line of the OBJ.
void checkScene(const ml::Scene& scene, size_t inputLines) {
    ml::fuzz::checkScene(kTarget, scene);
    for (const ml::Mesh& mesh : scene.meshes)
        for (int line : mesh.sourceLines)
            ML_FUZZ_EXPECT(kTarget, line >= 1 && size_t(line) <= inputLines, mesh.name, " line ", line);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string_view input(reinterpret_cast<const char*>(data), size);
    const size_t cut = input.find('\0');
    const bool hasMtl = cut != std::string_view::npos;
    const std::string obj(input.substr(0, cut));
    const std::string mtl = hasMtl ? std::string(input.substr(cut + 1)) : std::string();
    const std::string objPath = "fuzz/scene.obj";
    const ml::ObjFileReader read = [&](const std::string& path, std::string& text) {
        if (path == objPath) text = obj;
        else if (hasMtl) text = mtl;
        else return false;
        return true;
    };
    static const double kCreaseAngles[] = {30, 0, 90, 180};
    ml::ObjOptions options;
    options.creaseAngleDegrees = kCreaseAngles[size % 4];
    size_t objLines = 1;
    for (char c : obj) objLines += c == '\n';
    try {
        checkScene(ml::loadObj(objPath, options, read), objLines);
    } catch (const ml::InputError&) {
        // Refused with file:line and a reason: what bad input should get.
    } catch (const std::exception& e) {
        finding(std::string("unexpected exception: ") + e.what());
    } catch (...) {
        finding("unexpected exception of unknown type");
    }
    return 0;
}
