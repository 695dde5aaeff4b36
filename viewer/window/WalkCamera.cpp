#include "WalkCamera.h"

#include "core/Error.h"

#include <algorithm>
#include <cmath>

namespace ml {

WalkCamera::WalkCamera(const Camera& start, double speed) : start_(start), speed_(speed) {
    start.validate();
    setSpeed(speed);
    set(start);
}

void WalkCamera::setSpeed(double unitsPerSecond) {
    ML_ASSERT(unitsPerSecond > 0 && std::isfinite(unitsPerSecond), "walking speed ", unitsPerSecond);
    speed_ = unitsPerSecond;
}

void WalkCamera::reset() { set(start_); }

void WalkCamera::set(const Camera& c) {
    c.validate();
    exact_ = c;
    setBasis(c);
}

void WalkCamera::setBasis(const Camera& c) {
    position_ = c.position;
    fovY_ = c.fovYDegrees;
    const Vec3 d = c.target - c.position;
    focus_ = glm::length(d);
    const Vec3 forward = d / focus_;
    vertical_ = glm::normalize(c.up);
    // validate() guarantees forward is not parallel to up: the horizontal
    // part of the view direction is the heading at yaw 0.
    north_ = glm::normalize(forward - glm::dot(forward, vertical_) * vertical_);
    east_ = glm::cross(north_, vertical_);
    yaw_ = 0;
    pitch_ = std::asin(std::clamp(glm::dot(forward, vertical_), -1.0, 1.0));
    const double limit = kPi / 2 - kPitchMargin;
    pitch_ = std::clamp(pitch_, -limit, limit);
}

Vec3 WalkCamera::heading() const { return std::cos(yaw_) * north_ + std::sin(yaw_) * east_; }

bool WalkCamera::update(const WalkInput& in, double seconds, double radiansPerPixel) {
    const bool moves = in.forward != 0 || in.right != 0 || in.up != 0;
    const bool turns = in.lookRight != 0 || in.lookDown != 0;
    if ((!moves || !(seconds > 0)) && !turns) return false;
    if (turns) {
        yaw_ += in.lookRight * radiansPerPixel;
        yaw_ = std::remainder(yaw_, 2 * kPi);
        const double limit = kPi / 2 - kPitchMargin;
        pitch_ = std::clamp(pitch_ - in.lookDown * radiansPerPixel, -limit, limit);
    }
    if (moves && seconds > 0) {
        const Vec3 h = heading();
        const Vec3 right = glm::cross(h, vertical_);
        Vec3 step = in.forward * h + in.right * right + in.up * vertical_;
        const double len = glm::length(step);
        if (len > 1) step /= len;  // diagonal walking is no faster
        position_ += step * (speed_ * in.speedFactor * seconds);
    }
    exact_.reset();
    return true;
}

Camera WalkCamera::camera() const {
    if (exact_) return *exact_;
    Camera c;
    c.position = position_;
    const Vec3 forward = std::cos(pitch_) * heading() + std::sin(pitch_) * vertical_;
    c.target = position_ + focus_ * forward;
    c.up = vertical_;
    c.fovYDegrees = fovY_;
    return c;
}

}  // namespace ml
