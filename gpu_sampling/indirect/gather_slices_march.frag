// The slice gather with the loop over faces inside the fragment program:
// the ray through the pixel's jittered point visits the slice planes of the
// three axes in the order it crosses them (a 3D DDA over planes) and stops
// at the first face texel it finds covered. Faces, texels, back-projection
// (eq. 7–10) and the stochastic coverage test are those of the quad-per-face
// pass (gather_slices.frag), so both give the same hit for the same jitter;
// this one stops at the first hit instead of shading every face.
layout(binding = 0) uniform sampler2DArray faces;
layout(binding = 1) uniform sampler2DArray depths;  // where in its slice a texel's content lies
uniform vec2 arraySize;  // texels of one layer; a face of axis a fills its lower-left (dims[a+1]−1) × (dims[a+2]−1)
// Per axis a and slice i: layerOf[layerOffset[a] + 2i] is the layer of the
// slice's upper face, + 1 its lower face, −1 where that face is empty.
layout(std430, binding = 3) readonly buffer Layers { int layerOf[]; };
uniform ivec3 layerOffset;
uniform ivec3 dims;
uniform float voxel;

flat in int vInstance;
out vec4 color;

// Where face `layer` (of axis `axis`) is read at p, in array coordinates;
// false off the face.
bool faceCoord(vec3 p, int axis, int layer, out vec3 coord) {
    int ua = (axis + 1) % 3, va = (axis + 2) % 3;
    // Face texels start half a voxel in (VoxelGrid::texelOrigin).
    vec2 size = vec2(float(max(dims[ua] - 1, 1)), float(max(dims[va] - 1, 1)));
    vec2 uv = (vec2(p[ua], p[va]) - 0.5 * voxel) / (size * voxel);
    coord = vec3(uv * size / arraySize, float(layer));
    return all(greaterThanEqual(uv, vec2(0.0))) && all(lessThan(uv, vec2(1.0)));
}

// The texel of face `layer` (of axis `axis`) at p, if covered there for
// this pixel (stochastic coverage).
bool faceTexel(vec3 p, int axis, int layer, uint pixel, out vec4 s) {
    vec3 coord;
    if (!faceCoord(p, axis, layer, coord)) return false;
    s = texture(faces, coord);
    if (s.a <= 0.0) return false;
    uint h = mlHash(pixel ^ mlHash(gatherSeed + uint(layer) * 0x9e3779b9u + uint(axis) * 0x85ebca6bu));
    return (float(h >> 8) + 0.5) * (1.0 / 16777216.0) < s.a;
}

void main() {
    vec3 d;
    if (!fisheyeDirection(d)) discard;
    ivec3 cell = clamp(ivec3(floor(eye / voxel)), ivec3(0), dims - 1);
    ivec3 plane, stepDir;
    vec3 t;
    for (int a = 0; a < 3; ++a) {
        if (d[a] > 0.0) {
            plane[a] = cell[a] + 1; stepDir[a] = 1;
        } else {
            plane[a] = cell[a]; stepDir[a] = -1;
        }
        t[a] = d[a] != 0.0 ? (float(plane[a]) * voxel - eye[a]) / d[a] : 3.4e38;
    }
    uint pixel = fisheyePixel();
    int steps = dims.x + dims.y + dims.z + 3;
    // A hit on a face whose slice lies in the near box stands for what the
    // box holds, which the near-field pass draws exactly; it counts at the
    // far side of its slice, so a triangle of that slice, if the ray meets
    // one, is nearer and wins. The march goes on until no face can be nearer.
    float best = 3.4e38;
    vec3 radiance = vec3(0.0);
    // The point's own slice along an axis its surface is (nearly) parallel
    // to (a wall's own slice across the floor) holds surfaces the other
    // axes see edge-on (the floor a hair below): the ray meets them before
    // it leaves the slice, so that slice's face looking the way the ray goes
    // is read where the ray leaves it. Not along the surface's own normal:
    // there the face would show the surface's own back.
    bvec3 own = lessThan(abs(basis[2]), vec3(0.1));
    for (int k = 0; k < steps; ++k) {
        int a = t.x <= t.y ? (t.x <= t.z ? 0 : 2) : (t.y <= t.z ? 1 : 2);
        float ta = t[a];
        if (ta >= best || ta >= 3.0e38) break;
        // Going up, the ray meets the lower face of the slice above the
        // plane; going down, the upper face of the slice below it.
        int slice = stepDir[a] > 0 ? plane[a] : plane[a] - 1;
        if (own[a]) {
            own[a] = false;
            int ownLayer = layerOf[layerOffset[a] + 2 * cell[a] + (stepDir[a] > 0 ? 1 : 0)];
            vec4 s;
            vec3 p = eye + ta * d;
            if (ownLayer >= 0 && ta > 0.0 && faceTexel(p, a, ownLayer, pixel, s)) {
                // Only what lies ahead of the eye along the ray: the face
                // also shows what is behind it in the slice.
                vec3 coord;
                faceCoord(p, a, ownLayer, coord);
                // (A tenth of a voxel ahead, so the surface through the eye
                // never counts.)
                float tc = (texture(depths, coord).r - eye[a]) / d[a];
                if (tc * abs(d[a]) > 0.1 * voxel && tc < best) {
                    best = tc;
                    radiance = s.rgb / s.a;
                }
            }
        }
        if (slice < 0 || slice >= dims[a]) {
            t[a] = 3.4e38;
            continue;
        }
        int layer = layerOf[layerOffset[a] + 2 * slice + (stepDir[a] > 0 ? 1 : 0)];
        plane[a] += stepDir[a];
        t[a] = (float(plane[a]) * voxel - eye[a]) / d[a];
        if (layer < 0 || !(ta > 0.0)) continue;
        vec3 p = eye + ta * d;
        vec4 s;
        if (!faceTexel(p, a, layer, pixel, s)) continue;
        float depth = sliceHitInNearBox(p, a, slice) ? t[a] : ta;  // t[a] is now the slice's far side
        if (depth < best) {
            best = depth;
            radiance = s.rgb / s.a;
        }
    }
    if (best >= 3.0e38) discard;
    color = vec4(radiance, 1.0);
    gl_FragDepth = clamp(best / maxDistance, 0.0, 1.0);
}
