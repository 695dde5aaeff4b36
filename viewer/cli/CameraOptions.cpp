#include "CameraOptions.h"

#include "core/raytrace/DefaultCamera.h"

#include <cstdio>

namespace ml {

void declareViewOptions(Options& o) {
    o.value("width", "W", "image width, pixels", std::string("512"));
    o.value("height", "H", "image height, pixels", std::string("512"));
    declareCameraOptions(o);
}

void declareCameraOptions(Options& o) {
    o.value("camera-pos", "X,Y,Z", "camera position (default: the scene's camera, else one framing it from outside or, for a closed interior, one inside under a light)");
    o.value("camera-target", "X,Y,Z", "point the camera looks at");
    o.value("camera-up", "X,Y,Z", "camera up vector");
    o.value("fov", "DEG", "vertical field of view, degrees");
}

Camera cameraFromOptions(const Options& o, const Scene& scene, double aspect) {
    Camera c = scene.cameraOrDefault(aspect);
    // No camera in the file and none asked: outside, unless that view is of
    // a closed interior's outer walls (core/raytrace/DefaultCamera.h).
    if (!scene.camera && !o.has("camera-pos")) {
        const CameraChoice choice = chooseDefaultCamera(scene, aspect);
        if (choice.camera.position != c.position) {
            // The options that give this view again (for another command, or to move from it).
            const Camera& k = choice.camera;
            std::printf("camera: %s (--camera-pos %.6g,%.6g,%.6g --camera-target %.6g,%.6g,%.6g --fov %.6g)\n",
                        choice.reason.c_str(), k.position.x, k.position.y, k.position.z, k.target.x, k.target.y,
                        k.target.z, k.fovYDegrees);
        }
        c = choice.camera;
    }
    if (o.has("camera-pos")) c.position = o.vec3("camera-pos");
    if (o.has("camera-target")) c.target = o.vec3("camera-target");
    if (o.has("camera-up")) c.up = o.vec3("camera-up");
    if (o.has("fov")) c.fovYDegrees = o.number("fov", 1e-3, 179.0);
    c.validate();
    return c;
}

}  // namespace ml
