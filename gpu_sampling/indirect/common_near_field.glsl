// The near field (NearField.h): the proxy's triangles touching the near box,
// intersected per pixel (Möller–Trumbore) as gather_near.frag does. A hit
// counts wherever it lies (the triangles reach about a voxel beyond the box).
struct NearTriangle {
    vec4 p0, p1, p2;   // corners relative to the grid's origin; p0.w: 1 if closed
    vec4 l0, l1, l2;   // radiance at the corners
};
layout(std430, binding = 2) readonly buffer Near { NearTriangle near[]; };
uniform int nearCount;
uniform float minDistance;

// The nearest near-field hit along unit direction d from the eye: its
// distance and radiance (black for the back of a closed object).
bool nearFieldHit(vec3 d, out float tHit, out vec3 radiance) {
    tHit = 3.4e38;
    radiance = vec3(0.0);
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
        if (!(t > minDistance) || t >= tHit) continue;
        bool front = dot(cross(e1, e2), d) < 0.0;
        if (!front && near[i].p0.w < 0.5) continue;  // an open surface's back: its reversed copy answers
        tHit = t;
        hit = true;
        radiance = front ? max((1.0 - b1 - b2) * near[i].l0.rgb + b1 * near[i].l1.rgb + b2 * near[i].l2.rgb, vec3(0.0))
                         : vec3(0.0);
    }
    return hit;
}
