// A parametric open-plan office in metres: the many-lights scene. A room lit
// by a grid of square ceiling panels whose total power does not depend on
// how many there are, with desks, a partition and cabinets casting shadows.
//
// Geometry (y up; the floor's centre is the origin; all in metres):
//   room       x ∈ [−W/2, W/2], z ∈ [−D/2, D/2], y ∈ [0, H]; floor, ceiling
//              and four walls face into the room, each split into cells of
//              at most 2 m (the cache refines them further on its own)
//   panels     NX × NZ squares, one centred in each cell of an NX × NZ grid
//              over the ceiling, H − panelDrop high, facing −y; one mesh
//              "panels" whose quads do not touch, so finalize() makes one
//              Light per panel ("panel#k", or "panel" alone)
//   cabinets   boxes 0.45 (x) × 0.8 (z) × 1.2 (y) m in a row centred against
//              the left wall (x = −W/2, facing the camera), 0.02 m apart
//   desks      tabletops 1.6 (x) × 0.8 (z) × 0.03 m, top at 0.72 m, on four
//              0.05 × 0.05 m legs inset 0.05 m; two rows (ceil(n/2) desks in
//              the back row, z < 0, the rest in front), 0.2 m apart in a
//              row, the cluster centred in z and in the floor that the
//              cabinets leave free along x
//   partition  a 0.05 m thick, 1.5 m high screen along x between the two rows
//              (0.05 m from each row), as long as the back row
// Boxes face outwards and omit the faces nothing can see: a box's bottom on
// the floor, a leg's top under its tabletop, a cabinet's back on the wall
// (as the Cornell box's blocks omit their bottoms). Nothing else touches:
// panels, desks and cabinets keep gaps, so no two surfaces coincide.
// Flat shading normals. The defaults give 434 triangles, 24 of them emissive.
//
// Camera: at eye height 1.6 m, 0.5 m from the walls in the (+x, +z) corner,
// looking at the room's centre 0.8 m above the floor; 60° vertical field of
// view (the aspect ratio is the render's).
//
// Light level. With the default Ke, the unoccluded direct irradiance at the
// floor's centre of the default room is about 310 W·m⁻² (read it as lux: an
// office's few hundred); 305 with 8 × 6 or 16 × 12 panels of the same power.
#pragma once

#include "core/Scene.h"

#include <string>

namespace ml {

struct OfficeSettings {
    // Room
    double width = 8.0;   // m, along x; 2..1000, typical 8
    double depth = 6.0;   // m, along z; 2..1000, typical 6
    double height = 2.8;  // m, along y (up); 2..1000, typical 2.8

    // Ceiling panels
    int panelsX = 4;          // panels along x (NX of panels=NXxNZ); 1..1000, typical 4
    int panelsZ = 3;          // panels along z (NZ); 1..1000, typical 3
    double panelSize = 0.6;   // m, side of each square panel; typical 0.6 (a 600 mm troffer).
                              // It must fit its grid cell with >= 0.01 m between neighbours:
                              // side <= min(W/NX, D/NZ) − 0.01. In the default room 0.6 m
                              // fits up to 13 × 9 panels; 16 × 12 needs 0.49 m or less
    double panelDrop = 0.02;  // m, the emitting face below the ceiling; > 0, typical 0.02
    // W·sr⁻¹·m⁻², the Ke of each panel in the reference layout of 12 panels of
    // 0.6 × 0.6 m; typical (1700, 1650, 1550), a neutral white giving a few
    // hundred W·m⁻² on the floor. The total power π · Ke · 12 · 0.36 m² is held
    // constant: each of the NX · NZ panels of side s emits
    // Ke · 12 · 0.36 / (NX · NZ · s²), which is Ke · 12 / (NX · NZ) for 0.6 m panels.
    // Components >= 0 and finite, at least one > 0.
    Rgb panelRadiance{1700.0, 1650.0, 1550.0};

    // Furniture
    int desks = 6;       // desks in two rows (ceil(n/2) at the back); 0..1000, typical 6
    int partitions = 1;  // 0 or 1: the screen between the two rows of desks
    int cabinets = 4;    // boxes in a row against the left wall; 0..1000, typical 4

    // Throws InputError naming the field (and its key in an office spec) when
    // a value is out of range or the layout does not fit: panels overlapping
    // each other or the walls, desks or cabinets not fitting the floor,
    // furniture reaching the panels.
    void validate() const;
};

// A finalized scene named "office" as described at the top of this file,
// with its camera. Throws InputError for invalid settings (validate()).
Scene makeOfficeScene(const OfficeSettings& settings = {});

// Reads a scene argument of the form
//   office
//   office:KEY=VALUE[,KEY=VALUE]...
// e.g. "office:panels=8x6", "office:panels=8x6,size=10x8x3,desks=4". Keys
// (each at most once; numbers in decimal, metres where they are lengths):
//   panels=NXxNZ      panelsX, panelsZ (positive integers), e.g. 16x12
//   size=WxDxH        width, depth, height in metres, e.g. 10x8x3
//   panelsize=S       panelSize in metres, e.g. 0.4
//   desks=N           desks (integer >= 0)
//   partitions=0|1    partitions
//   cabinets=N        cabinets (integer >= 0)
// Unset keys keep the OfficeSettings defaults. Returns validated settings.
// Throws InputError naming the key for an unknown or repeated key, a
// malformed value, or settings that validate() refuses.
OfficeSettings parseOfficeSpec(const std::string& spec);

}  // namespace ml
