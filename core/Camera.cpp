#include "Camera.h"

#include "Error.h"

#include <glm/gtc/matrix_transform.hpp>

namespace ml {

Mat4 Camera::view() const { return glm::lookAtRH(position, target, up); }

void Camera::basis(Vec3& forward, Vec3& right, Vec3& trueUp) const {
    forward = glm::normalize(target - position);
    right = glm::normalize(glm::cross(forward, up));
    trueUp = glm::cross(right, forward);
}

void Camera::validate() const {
    if (!isFinite(position) || !isFinite(target) || !isFinite(up))
        throw InputError(concat("camera has a non-finite vector"));
    const Vec3 d = target - position;
    const double len = glm::length(d);
    if (!(len > 0)) throw InputError("camera position and target coincide");
    if (!(glm::length(up) > 0)) throw InputError("camera up vector is zero");
    if (glm::length(glm::cross(d / len, glm::normalize(up))) < 1e-9)
        throw InputError("camera up vector is parallel to the view direction");
    if (!(fovYDegrees > 0 && fovYDegrees < 180))
        throw InputError(concat("camera field of view ", fovYDegrees, " is not in (0, 180) degrees"));
}

Camera Camera::framing(const Bounds3& bounds, double aspect, double fovYDegrees) {
    Camera c;
    c.fovYDegrees = fovYDegrees;
    const Vec3 center = bounds.center();
    const Vec3 ext = bounds.extent();
    // Distance at which the box's bounding sphere fits the narrower field of view.
    const double radius = std::max(0.5 * glm::length(ext), 1e-30);
    const double halfY = glm::radians(fovYDegrees) * 0.5;
    const double halfX = std::atan(std::tan(halfY) * aspect);
    const double dist = radius / std::sin(std::min(halfX, halfY));
    c.target = center;
    c.position = center + Vec3(0.0, 0.0, dist);
    c.up = Vec3(0.0, 1.0, 0.0);
    return c;
}

}  // namespace ml
