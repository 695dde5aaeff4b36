// The voxel faces as one 3D texture (volume_fill.comp), ray-marched: the ray
// through each fish-eye pixel's jittered point visits the slice planes of
// the three axes in the order it crosses them (a 3D DDA), and at each
// crossing takes the face it enters by: the radiance the surfaces in that
// slice send out through it, and their coverage. It composites them front
// to back, the expectation of the slice gather's stochastic coverage test:
// the same mean without the noise of coverage. The near field's triangles
// (common_near_field.glsl) are exact; a face of a slice in the near box
// stands for what the box holds and counts at its slice's far side, so a
// near triangle in front of that wins (SliceGather's rule).
layout(binding = 0) uniform sampler3D volume;  // dims.x × dims.y × 6·dims.z
uniform ivec3 dims;
uniform ivec3 texels;  // face texels along each axis (VoxelGrid::texels)
uniform float voxel;

out vec4 color;

void main() {
    vec3 d;
    if (!fisheyeDirection(d)) discard;
    float tNear;
    vec3 nearRadiance;
    bool nearHit = nearFieldHit(d, tNear, nearRadiance);

    ivec3 cell = clamp(ivec3(floor(eye / voxel)), ivec3(0), dims - 1);
    ivec3 plane, stepDir;
    vec3 t;
    for (int a = 0; a < 3; ++a) {
        stepDir[a] = d[a] > 0.0 ? 1 : -1;
        plane[a] = d[a] > 0.0 ? cell[a] + 1 : cell[a];
        t[a] = d[a] != 0.0 ? (float(plane[a]) * voxel - eye[a]) / d[a] : 3.4e38;
    }
    vec3 sum = vec3(0.0);
    float transmittance = 1.0;
    float stop = nearHit ? tNear : 3.0e38;
    int steps = dims.x + dims.y + dims.z + 3;
    for (int k = 0; k < steps; ++k) {
        int a = t.x <= t.y ? (t.x <= t.z ? 0 : 2) : (t.y <= t.z ? 1 : 2);
        float ta = t[a];
        if (ta >= stop) break;
        // Going up, the ray enters the slice above the plane by its lower
        // face (block 2a + 1); going down, the slice below by its upper face.
        int slice = stepDir[a] > 0 ? plane[a] : plane[a] - 1;
        if (slice < 0 || slice >= dims[a]) {
            t[a] = 3.4e38;
            continue;
        }
        plane[a] += stepDir[a];
        t[a] = (float(plane[a]) * voxel - eye[a]) / d[a];
        if (!(ta > 0.0)) continue;
        vec3 p = eye + ta * d;
        int ua = (a + 1) % 3, va = (a + 2) % 3;
        ivec2 texel = ivec2(floor((vec2(p[ua], p[va]) - 0.5 * voxel) / voxel));
        if (any(lessThan(texel, ivec2(0))) || texel.x >= texels[ua] || texel.y >= texels[va]) continue;
        ivec3 c;
        c[a] = slice;
        c[ua] = texel.x;
        c[va] = texel.y;
        int block = 2 * a + (stepDir[a] > 0 ? 1 : 0);
        vec4 s = texelFetch(volume, ivec3(c.x, c.y, c.z + block * dims.z), 0);
        if (s.a <= 0.0) continue;
        if (nearHit && (sliceHitInNearBox(p, a, slice) ? t[a] : ta) >= tNear) continue;
        sum += transmittance * s.rgb;
        transmittance *= 1.0 - s.a;
        if (transmittance < 1e-4) break;
    }
    if (nearHit) sum += transmittance * nearRadiance;
    color = vec4(sum, 1.0);
}
