// Back-projection of a fish-eye pixel onto one slice face (§5.4, eq. 7–10):
// the ray through the pixel's jittered point meets the face's plane at P,
// whose texel gives the radiance; the nearest face wins by depth. Texel
// coverage (alpha) is tested stochastically: a half-covered voxel face
// stops half the rays.
layout(binding = 0) uniform sampler2DArray faces;
layout(binding = 1) uniform sampler2DArray depths;  // where in its slice a texel's content lies
layout(std430, binding = 1) readonly buffer Planes { vec2 planes[]; };
uniform int axis;
uniform vec2 extentUV;
uniform vec2 texelOrigin;  // where the face's texels start (relative to the grid's origin)
uniform vec2 texScale;   // the face's share of a layer (it fills the lower-left corner)
uniform int firstLayer;
uniform float voxel;
// 1: the faces drawn are the point's own slice's, read where the ray leaves
// the slice (on the face's opposite plane): see gather_slices_march.frag.
uniform int ownSlice;

flat in int vInstance;
out vec4 color;

void main() {
    vec3 d;
    if (!fisheyeDirection(d)) discard;
    int layer = firstLayer + vInstance;
    float plane = ownSlice == 1 ? planes[layer].x - planes[layer].y * voxel : planes[layer].x;
    float t = (plane - eye[axis]) / d[axis];
    if (!(t > 0.0)) discard;
    vec3 p = eye + t * d;
    int ua = (axis + 1) % 3, va = (axis + 2) % 3;
    vec2 uv = (vec2(p[ua], p[va]) - texelOrigin) / extentUV;
    if (any(lessThan(uv, vec2(0.0))) || any(greaterThanEqual(uv, vec2(1.0)))) discard;
    // The face's slice: an upper face lies on its slice's upper plane.
    int slice = int(floor(planes[layer].x / voxel + 0.5)) - (planes[layer].y > 0.0 ? 1 : 0);
    // A face of a slice in the near box counts at the slice's far side, so
    // a triangle there (the near-field pass) is nearer and wins.
    float depth = ownSlice == 0 && sliceHitInNearBox(p, axis, slice) ? t + voxel / abs(d[axis]) : t;
    if (ownSlice == 1) {
        // Only what lies ahead of the eye along the ray: the face also shows
        // what is behind it in the slice.
        depth = (texture(depths, vec3(uv * texScale, float(layer))).r - eye[axis]) / d[axis];
        if (!(depth * abs(d[axis]) > 0.1 * voxel)) discard;  // ahead, and not the surface through the eye
    }
    vec4 s = texture(faces, vec3(uv * texScale, float(layer)));
    if (s.a <= 0.0) discard;
    uint h = mlHash(fisheyePixel() ^ mlHash(gatherSeed + uint(layer) * 0x9e3779b9u + uint(axis) * 0x85ebca6bu));
    if ((float(h >> 8) + 0.5) * (1.0 / 16777216.0) >= s.a) discard;
    color = vec4(s.rgb / s.a, 1.0);
    gl_FragDepth = clamp(depth / maxDistance, 0.0, 1.0);
}
