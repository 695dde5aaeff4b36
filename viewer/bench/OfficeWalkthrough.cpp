#include "OfficeWalkthrough.h"

#include "WalkthroughViews.h"

#include "core/Error.h"

#include <cmath>

namespace ml {

namespace {

// The heading (radians about y, from +x towards +z) of a look from `from` at `to`.
double heading(const Vec3& from, const Vec3& to) { return std::atan2(to.z - from.z, to.x - from.x); }

// `to` moved by whole turns to within half a turn of `from`: the shortest way round.
double nearestTurn(double from, double to) {
    const double turn = 2 * M_PI;
    return to - turn * std::round((to - from) / turn);
}

}  // namespace

std::vector<Camera> officeWalkthroughCameras(const Scene& office, const OfficeSettings& settings, int views) {
    ML_ASSERT(office.camera, "the office has a camera");
    const Camera standard = *office.camera;
    const double w = settings.width, d = settings.depth, eye = standard.position.y;
    const Vec3 eye0 = standard.position, eye1(w / 6, eye, 0.5 * d - 0.6), eye2(-0.5 * w + 1.0, eye, 0.5 * d - 0.6),
               eye3(-0.5 * w + 1.0, eye, -0.5 * d + 1.0);
    // Where it looks: the office camera's target (the room's centre), the back-left corner halfway, the
    // front-right corner at the end.
    const Vec3 backLeft(-0.5 * w, 0.8, -0.5 * d), frontRight(0.5 * w, 0.8, 0.5 * d);
    const double yaw0 = heading(eye0, standard.target);
    const double yaw1 = nearestTurn(yaw0, heading(bezier(eye0, eye1, eye2, eye3, 0.5), backLeft));
    const double yaw2 = nearestTurn(yaw1, heading(eye3, frontRight));
    // It starts with the office camera's pitch and looks 12° down from halfway on.
    const Vec3 look0 = standard.target - eye0;
    const double pitch0 = std::atan2(look0.y, std::hypot(look0.x, look0.z)), pitch1 = -glm::radians(12.0);
    std::vector<Camera> cameras;
    for (int i = 0; i < views; ++i) {
        const double s = smoothstep(views > 1 ? double(i) / (views - 1) : 0.0);
        const double yaw = s < 0.5 ? yaw0 + (yaw1 - yaw0) * 2 * s : yaw1 + (yaw2 - yaw1) * (2 * s - 1);
        const double pitch = pitch0 + (pitch1 - pitch0) * std::min(1.0, 2 * s);
        Camera c = standard;
        c.position = bezier(eye0, eye1, eye2, eye3, s);
        c.target = c.position + Vec3(std::cos(yaw) * std::cos(pitch), std::sin(pitch), std::sin(yaw) * std::cos(pitch));
        c.validate();
        cameras.push_back(c);
    }
    return cameras;
}

}  // namespace ml
