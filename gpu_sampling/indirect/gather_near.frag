// The near field: the proxy's triangles touching the near box, intersected
// per pixel (exact, unlike a projected triangle whose straight edges a
// fish-eye would bend). The slices give everything else: their hits inside
// the box are dropped. A triangle's hit may lie a little outside the box
// (triangles are about a voxel across) and counts there too, where it
// competes with the slices by depth: a slice face stands up to a voxel in
// front of what it shows, so a ray grazing down past the box's edge that
// drops the face's hit inside the box still finds the surface itself.
struct NearTriangle {
    vec4 p0, p1, p2;   // corners relative to the grid's origin; p0.w: 1 if closed
    vec4 l0, l1, l2;   // radiance at the corners
};
layout(std430, binding = 2) readonly buffer Near { NearTriangle near[]; };
uniform int nearCount;
uniform float minDistance;

flat in int vInstance;
out vec4 color;

void main() {
    vec3 d;
    if (!fisheyeDirection(d)) discard;
    float best = 3.4e38;
    vec3 radiance = vec3(0.0);
    bool hit = false;
    for (int i = 0; i < nearCount; ++i) {
        vec3 a = near[i].p0.xyz, e1 = near[i].p1.xyz - a, e2 = near[i].p2.xyz - a;
        vec3 pv = cross(d, e2);
        float det = dot(e1, pv);
        if (abs(det) < 1e-30) continue;
        float inv = 1.0 / det;
        vec3 tv = eye - a;
        float b1 = dot(tv, pv) * inv;
        if (b1 < 0.0 || b1 > 1.0) continue;
        vec3 qv = cross(tv, e1);
        float b2 = dot(d, qv) * inv;
        if (b2 < 0.0 || b1 + b2 > 1.0) continue;
        float t = dot(e2, qv) * inv;
        if (!(t > minDistance) || t >= best) continue;
        bool front = dot(cross(e1, e2), d) < 0.0;
        if (!front && near[i].p0.w < 0.5) continue;  // an open surface's back: its reversed copy answers
        best = t;
        hit = true;
        radiance = front ? (1.0 - b1 - b2) * near[i].l0.rgb + b1 * near[i].l1.rgb + b2 * near[i].l2.rgb : vec3(0.0);
    }
    if (!hit) discard;
    color = vec4(max(radiance, vec3(0.0)), 1.0);
    gl_FragDepth = clamp(best / maxDistance, 0.0, 1.0);
}
