// The camera of a scene whose file has none (core/raytrace/DefaultCamera.h):
// outside for an object or an open room, inside for a closed interior.
#include "core/raytrace/DefaultCamera.h"
#include "core/raytrace/EmbreeScene.h"
#include "core/scenes/CornellBox.h"
#include "TestScenes.h"

#include <gtest/gtest.h>

namespace ml {
namespace {

using test::kX;
using test::kY;
using test::kZ;

// A closed 4 x 2.5 x 3 room, every face towards the inside, a 0.5 x 0.5
// lamp facing down 1 cm under the ceiling: from outside, no ray meets a
// surface that sees it.
Scene closedRoom() {
    Mesh room;
    room.name = "room";
    const Vec3 lo(-2, 0, -1.5);
    test::addQuad(room, 1, lo, 3.0 * kZ, 4.0 * kX);                      // floor, up
    test::addQuad(room, 1, lo + 2.5 * kY, 4.0 * kX, 3.0 * kZ);           // ceiling, down
    test::addQuad(room, 1, lo, 4.0 * kX, 2.5 * kY);                      // z = -1.5, +z
    test::addQuad(room, 1, lo + 3.0 * kZ, 2.5 * kY, 4.0 * kX);           // z = 1.5, -z
    test::addQuad(room, 1, lo, 2.5 * kY, 3.0 * kZ);                      // x = -2, +x
    test::addQuad(room, 1, lo + 4.0 * kX, 3.0 * kZ, 2.5 * kY);           // x = 2, -x
    return test::sceneOf("closed", {Material::diffuse("lamp", Rgb(0.5), Rgb(10.0)), Material::diffuse("wall", Rgb(0.5))},
                         {room, test::quadMesh("lamp", 0, Vec3(-0.25, 2.49, -0.25), 0.5 * kX, 0.5 * kZ)});
}

TEST(DefaultCamera, AClosedRoomIsSeenFromInside) {
    const Scene scene = closedRoom();
    const CameraChoice c = chooseDefaultCamera(scene, 16.0 / 9);
    // Under the lamp, 0.55 of the way down (2.49 - 0.55 x 2.49, up to the
    // ray offset), looking level.
    EXPECT_NEAR(c.camera.position.x, 0.0, 1e-6);
    EXPECT_NEAR(c.camera.position.z, 0.0, 1e-6);
    EXPECT_NEAR(c.camera.position.y, 0.45 * 2.49, 1e-4);
    EXPECT_NEAR(c.camera.target.y, c.camera.position.y, 1e-9);
    EXPECT_NE(c.reason.find("inside, under light 'lamp'"), std::string::npos) << c.reason;
    const EmbreeScene rays(scene);
    const ViewHits inside = viewHits(rays, c.camera, 16.0 / 9, {0});
    EXPECT_EQ(inside.back, 0);
    EXPECT_GT(inside.lit, inside.rays / 2);
    // From any side outside, nothing lit is seen.
    EXPECT_EQ(viewHits(rays, Camera::framing(scene.bounds, 16.0 / 9), 16.0 / 9, {0}).lit, 0);
}

TEST(DefaultCamera, AnObjectKeepsTheFramingAndAnOpenRoomIsSeenThroughItsOpening) {
    // A lit floor and its lamp: the view from +z sees the lit floor.
    const Scene floor = test::sceneOf("floor", {Material::diffuse("lamp", Rgb(0.5), Rgb(10.0)), Material::diffuse("grey", Rgb(0.5))},
                                      {test::unitLight(), test::floorMesh()});
    const CameraChoice f = chooseDefaultCamera(floor, 1.0);
    EXPECT_EQ(f.camera.position, Camera::framing(floor.bounds, 1.0).position);
    EXPECT_EQ(f.camera.target, Camera::framing(floor.bounds, 1.0).target);
    // The Cornell box (its camera ignored here) is open towards -z: from +z
    // the back wall's outside shows, from -z the lit room.
    const Scene cornell = makeCornellBox();
    const CameraChoice c = chooseDefaultCamera(cornell, 1.0);
    const Camera plusZ = Camera::framing(cornell.bounds, 1.0);
    const Vec3 centre = cornell.bounds.center();
    EXPECT_NEAR(c.camera.position.z, centre.z - glm::length(plusZ.position - centre), 1e-6);
    EXPECT_EQ(c.camera.target, centre);
    EXPECT_NE(c.reason.find("framing it from -z"), std::string::npos) << c.reason;
}

}  // namespace
}  // namespace ml
