#include "CameraOptions.h"

namespace ml {

void declareViewOptions(Options& o) {
    o.value("width", "W", "image width, pixels", std::string("512"));
    o.value("height", "H", "image height, pixels", std::string("512"));
    declareCameraOptions(o);
}

void declareCameraOptions(Options& o) {
    o.value("camera-pos", "X,Y,Z", "camera position (default: the scene's camera or a framing one)");
    o.value("camera-target", "X,Y,Z", "point the camera looks at");
    o.value("camera-up", "X,Y,Z", "camera up vector");
    o.value("fov", "DEG", "vertical field of view, degrees");
}

Camera cameraFromOptions(const Options& o, const Scene& scene, double aspect) {
    Camera c = scene.cameraOrDefault(aspect);
    if (o.has("camera-pos")) c.position = o.vec3("camera-pos");
    if (o.has("camera-target")) c.target = o.vec3("camera-target");
    if (o.has("camera-up")) c.up = o.vec3("camera-up");
    if (o.has("fov")) c.fovYDegrees = o.number("fov", 1e-3, 179.0);
    c.validate();
    return c;
}

}  // namespace ml
