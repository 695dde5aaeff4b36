// The Cornell box as measured by the Cornell Program of Computer Graphics
// (www.graphics.cornell.edu/online/box/data.html), in millimetres.
#pragma once

#include "core/Scene.h"

namespace ml {

// A finalized scene named "cornell": meshes floor, ceiling, back, left (red,
// x ≈ 556), right (green, x = 0), shortBlock, tallBlock (5 faces each, no
// bottom) and light (130 × 105 mm, 0.5 mm below the ceiling, facing -y,
// Ke (17, 12, 4) W·sr⁻¹·m⁻²); 32 triangles with flat normals; walls face into
// the box, blocks outwards. The measured vertices are kept, so some walls are
// slightly non-planar. Camera: the measured 35 mm lens on 25 mm film at
// (278, 273, -800) looking along +z.
Scene makeCornellBox();

}  // namespace ml
