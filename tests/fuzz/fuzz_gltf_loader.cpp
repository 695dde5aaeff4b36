// libFuzzer target for the glTF 2.0 loader (loadGltfFromMemory): tinygltf's
// parsing, then everything GltfLoader.cpp does with the model (nodes and
// transforms, accessors, sparse data, strips and fans, materials and their
// textures from data URIs or a .glb's buffer, cameras, punctual lights,
// Scene::finalize).
//
// Input: the bytes of a .gltf (JSON) or a .glb (binary, from its "glTF"
// magic), read from memory with no file access at all: a URI naming a file
// is refused as not found. The crease angle (0, 30, 90 or 180 degrees) and
// the emission scale (1 or 0) follow the input's length, so every corpus
// file meets several of them as it is mutated.
//
// An InputError is the loader refusing bad input: a normal outcome. Any other
// exception, a broken promise about the scene it returns (SceneChecks.h), a
// crash, a sanitizer report, a leak or a hang is a finding.
#include "SceneChecks.h"
#include "core/Error.h"
#include "core/loaders/GltfLoader.h"

#include <cstdint>
#include <exception>
#include <string>
#include <vector>

namespace {

constexpr const char* kTarget = "fuzz_gltf_loader";

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::vector<unsigned char> bytes(data, data + size);
    static const double kCreaseAngles[] = {30, 0, 90, 180};
    ml::GltfOptions options;
    options.creaseAngleDegrees = kCreaseAngles[size % 4];
    options.emissionScale = (size / 4) % 2 ? 0.0 : 1.0;
    try {
        ml::fuzz::checkScene(kTarget, ml::loadGltfFromMemory("fuzz/scene.gltf", bytes, options));
    } catch (const ml::InputError&) {
        // Refused with the file and the JSON path of the problem: what bad input should get.
    } catch (const std::exception& e) {
        ml::fuzz::finding(kTarget, std::string("unexpected exception: ") + e.what());
    } catch (...) {
        ml::fuzz::finding(kTarget, "unexpected exception of unknown type");
    }
    return 0;
}
