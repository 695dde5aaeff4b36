// Discontinuity meshing where a surface hangs close in front of another: a
// panel 2 cm under a ceiling, a shelf over a desk, a lining off a wall (for
// the bounces' meshes); and where a surface crosses a light's plane (for
// direct light's: CutPlane below).
//
// There the light on the receiver changes over the gap's own length h: the
// indirect light on a ceiling goes from half its value at a panel's outline
// to 0.9 of it 2h outside, and to a tenth 2h inside (seen at grazing angles
// through the gap). Cache vertices laid without regard to the panel put some
// under it (dark) and some outside (lit), and linear interpolation between
// them darkens a band as wide as an edge of the base mesh all round it; the
// gathers' noise hides that from refinement, and later bounces are split at
// most once. On the office's ceiling between 192 panels the outlines are
// 307 m long. Heckbert's D0 discontinuities (Lischinski, Tampieri &
// Greenberg 1992) put mesh edges on the outline instead.
//
// What is cut: a receiver triangle R is cut along every edge of another
// surface that lies in front of R's plane, at a height h above it between a
// thousandth of the scene's size and `closeness` × the edge's length at
// either end, projected onto R and clipped to it. Edges inside a flat
// surface (between two coplanar faces facing one way: a quad's diagonal) cut
// nothing. From a point at distance s outside such an edge, the surface
// hides the directions below atan(h/s), a cosine-weighted share
// 1/2 · h²/(h² + s²) of the hemisphere: the open side gets 1/2, 3/4, 0.9,
// 0.95 of its light at s = 0, h, 2h, 3h, and a point at depth d under the
// surface 1/2 · h²/(h² + d²). A line parallel to the outline at 2h on each
// side puts vertices where that profile bends (read linearly within 0.05 of
// it), where 2h is under half the base mesh's spacing.
//
// Under a hanging face parallel to the receiver, two more lines, at depths h
// and 3h (where the profile is 0.25 and 0.05), each from h/2 inside one end
// of the edge to h/2 inside the other, so that they cross the lines under
// the face alone. There the profile is convex and falls to a tenth of the
// open value at 2h: read linearly from the outline's 0.5 to 2h's 0.1 it
// was 20% bright at h, and from 0.1 to the base's next vertex inside
// (several h on) twice its value at 3h. The camera sees that strip: looking
// up through the gaps between panels, at elevation θ, it sees the ceiling
// under the far panel to a depth h / tan θ (3 to 5h from the office's
// standard view). Measured on the 192-panel office (render
// office:panels=16x12,panelsize=0.4 --width 320 --height 180 --time 20,
// two runs each, against a 2048-spp reference): the pixels an emitter
// covers in part, where the camera sees into the gaps, read their indirect
// light 5.0% too bright on average, and 1.5% with these lines; the image's
// error 2.81/2.85% → 2.64/2.67%, for 24,000 vertices added instead of
// 14,000 (the 48-panel office: 2.26% → 2.19%; the 12-panel one and
// ../shared/scenes' back rooms as before). Drawn 3h past the edge's ends as
// the lines beside it are, they crossed those too: 30,000 vertices.
//
// The hanging surface's side that faces the receiver sees the same gap from
// the other side: light reaches the back of a panel under a ceiling only
// through the gap, 1/2 · h²/(h² + d²) of the open value at depth d inside
// its outline. Its own mesh has vertices on its outline and none inside
// (a panel's back: its four corners), so interpolation spread the corners'
// light over the whole back, and each later bounce sent it on to the
// ceiling above and back again: on the 48-panel office after 40 s the
// back's centre read 10 times its light and the ceiling 1, 5 and 15 cm
// under the panel 1.3, 2.1 and 6.4 times; the pixels an emitter covers in
// part, where the camera sees into the gap, read their indirect light 2.8%
// too bright (6.5% on the 192-panel office at 6 s). So a face of the
// hanging surface beside such an edge and parallel to the receiver gets
// lines 2h and 6h inside the edge (where the profile is at 0.1 and 0.014 of
// the open value).
// Measured at 20 s (render --time 20, 320×180): the 48-panel office's
// indirect light 1.12/1.11% → 0.91/0.73% (two seeds; the image 2.57/2.80%
// → 2.50/2.60%), the 192-panel one's 2.27% → 1.74% (the image 3.28% →
// 2.89%). A line 6h in under the face on the receiver too added twice the
// vertices for no change beyond the runs' spread.
//
// Not cut: touching contacts (a block on a floor, h = 0) and gaps under a
// thousandth of the scene. There the cache's rule for hidden vertices
// (IndirectSolver.h) keeps what is boxed in from darkening its neighbours,
// and a vertex on the contact itself would have the touching surface through
// its sampling point. Measured on the Cornell box at 256² and 30 s (its light
// hangs 0.5 mm under the ceiling, its blocks stand on the floor): 0.566%
// uncut, 0.645% with the light's outline cut, 0.669% with lines 1 mm either
// side of the blocks' footprints too.
//
// The result is a copy of each mesh with its cut triangles re-triangulated
// (a constrained Delaunay triangulation in the triangle's plane, its edges
// and the cuts as constraints; the slivers rounding leaves between an edge's
// points and the hull are dropped). A point put on an edge is shared with
// the triangle across that edge (same vertex indices), which is triangulated
// again with it, so the copy is conforming wherever the original was. New
// vertices interpolate the triangle's position, normal and texture
// coordinate; per-triangle arrays follow the parent triangle. CGAL lives in
// ContactCuts.cpp only.
#pragma once

#include "core/Scene.h"

#include <cstddef>
#include <vector>

namespace ml {

// The plane of a one-sided planar light, along which receivers are cut
// within `region`. Behind that plane the light gives nothing; in front of it
// a receiver crossing the plane gets light growing linearly from 0 at the
// crossing (the light seen edge-on): a kink in the irradiance (Heckbert's D1
// discontinuity) along a line no cache vertex lies on. Linear interpolation
// from a vertex behind the plane to one in front spreads the light over the
// part behind it: on the office's walls, 2 cm under the ceiling where the
// panels hang, the first pixels under the ceiling read their direct light
// about 3 too bright in pixels of about 35, about a fifth of the squared
// direct light error of the 48- and 192-panel offices' images; splitting
// does not find it (the kink lies between vertices whose neighbours fit a
// plane), and edges a quarter of a pixel long left it as it was. A line on
// the crossing puts the kink on mesh edges (cache/README.md, "Lights'
// planes", has the measurements).
struct CutPlane {
    Vec3 point{0.0};
    Vec3 normal{0.0, 1.0, 0.0};  // unit, towards the side the lights shine on
    Bounds3 region;              // receivers are cut only inside this box
    // The bounds of the lights in the plane. In front of the plane a
    // receiver's light grows from 0 and bends over about the distance δ
    // from the crossing to the nearest light: where δ is under half the
    // base mesh's spacing, the base's vertices lie beyond the bend and the
    // interpolation from the line's 0 reads the ramp dark until refinement
    // reaches it (the 192-panel office's walls, 5 cm from the panels), so a
    // second line goes δ in front, where the ramp bends.
    std::vector<Bounds3> lights;
};

// The cut planes of the scene's lights: one per plane that planar area
// lights lie in (coplanar lights merged, their regions joined and their
// bounds listed), a light's region its bounds grown by twice their diagonal
// each way (where its light may matter against the others'), at most
// kMaxLightPlanes of them (those of the most powerful lights: a mesh of many
// small emitters facing every way gets no cuts beyond). Punctual lights have
// none: a point light has no plane, and a spot's cone is smooth where its
// falloff is.
std::vector<CutPlane> lightCutPlanes(const Scene& scene);
constexpr size_t kMaxLightPlanes = 64;

struct ContactCutSettings {
    // An edge cuts a receiver when both its ends hang in front of the
    // receiver's plane within closeness × the edge's length (typical 0.1).
    double closeness = 0.1;
    // The base mesh's longest edge (scene units): penumbra lines are laid
    // only for gaps h with 2h below half of it. 0: none.
    double spacing = 0;
    // Receivers are also cut where they cross these planes (CutPlane), by
    // more than a thousandth of the scene on either side (the Cornell box's
    // light, 0.5 mm under its ceiling, cuts nothing, as for contacts), and
    // where they cross the plane moved the distance δ to the nearest light
    // in front, when δ is under half of `spacing` (CutPlane::lights; δ is
    // taken from each receiver triangle's shadow on the plane, as a small
    // triangle may hold the second line without crossing the plane, so the
    // line may stop where a triangle's shadow lies far from every light).
    // With `spacing` > 0 the meshes near a plane are first bisected to
    // edges of at most `spacing` (bisectLongEdges, core/MeshUtil.h), then
    // cut: cutting an object's large triangles first left pieces (a strip
    // 2 cm high, slivers beside it) whose bisection to the base's edges
    // made 60% more base vertices on ../shared/scenes' back rooms.
    std::vector<CutPlane> planes;
};

struct ContactCutReport {
    size_t receivers = 0;  // triangles re-triangulated (cut, or given a neighbour's point)
    size_t segments = 0;   // cut segments after clipping, penumbra lines and plane cuts included
    size_t planes = 0;         // settings.planes cut along
    size_t planeSegments = 0;  // of those, where a receiver crosses a CutPlane
    size_t triangles = 0;  // triangles those became
    size_t vertices = 0;   // vertices added
    size_t dropped = 0;    // faces thinner than 1e-6 of the scene (float-degenerate on the GPU) left out
};

// The scene's meshes, each cut along the edges of surfaces hanging close in
// front of it (settings.closeness; 0: none) and along settings.planes;
// skip[i] leaves mesh i as it is (it still cuts others).
// Deterministic: the same scene gives the same meshes to the bit. Cost: a
// uniform grid of the scene's edges, then per receiver the edges near it.
std::vector<Mesh> cutAlongContacts(const Scene& scene, const std::vector<bool>& skip,
                                   const ContactCutSettings& settings, ContactCutReport* report = nullptr);

}  // namespace ml
