// Coverage pass, vertex stage: the dilation of §4.2.1 done in screen space,
// one triangle at a time by vertex pulling (six vertices, a quad, per
// triangle; llvmpipe runs vertex stages eight wide, geometry stages one
// primitive at a time, so this replaced a geometry shader at a third of the cost).
//
// The paper dilates triangles by a fixed percentage, which does not guarantee
// a pixel of margin for every view. Here each triangle is replaced by its
// screen-space bounding rectangle grown by one pixel on every side: every
// pixel the triangle touches gets a fragment, whatever the view. What lies
// behind the near plane or the light's plane is cut per sample by the
// fragment stage.
//
// Attributes are passed in homogeneous form (Olano & Greer 1997): for a
// triangle with clip-space columns M = [x; y; w], the barycentrics divided by
// w at screen point s = (sx, sy, 1) are M⁻¹ s. They are exactly affine in
// screen space, so the rasteriser interpolates them without error and their
// screen derivatives are exact: eq. (5) then places the jittered point exactly
// on the triangle, not only to first order as with perspective-interpolated
// coordinates (the paper's unexplained loss of accuracy in §6.1).

// Three vec4 per triangle: xyz relative to the buffer's origin; w of the
// first holds 1 + the index of the light the face belongs to (0: none), w of
// the second 1 + its cut-out record (MASKS; 0: opaque).
layout(std430, binding = 0) readonly buffer Triangles { vec4 uTriangles[]; };

uniform mat4 uClipFromLocal;    // projection × view, translation included (computed in double)
uniform vec4 uLightPlane;       // (n, d): signed distance n·p + d, positive on the eye's side
uniform vec4 uHorizonPlane;     // the receiver's tangent plane through the eye, positive above
uniform float uNear;            // near distance; the projection puts z_clip = uNear
uniform float uPixelNdc;        // one pixel in NDC units (2 / image size)
uniform bool uCullBackFaces;    // the light emits from its front face only
uniform uint uSkipLightId;      // faces of this light are not occluders (0: skip none)
uniform bool uClipToLightPlane; // occluders of a planar light: keep the eye's side only
uniform float uPlaneTolerance;  // distance below which a face counts as on the plane

noperspective out vec3 vBaryOverW;
noperspective out float vPlaneOverW;
#if MASKS
flat out uint vMask;
#endif

void dropTriangle() {
    // All six vertices at one point: zero area, no fragment.
    gl_Position = vec4(-4.0, -4.0, 0.0, 1.0);
    vBaryOverW = vec3(0.0);
    vPlaneOverW = 0.0;
}

// Grows [lo, hi] by homogeneous point p (x, y, w) if it lies in the
// frustum's pyramid |x| <= w, |y| <= w (a hair of slack for points computed
// on its faces).
void addIfInPyramid(vec3 p, inout vec2 lo, inout vec2 hi) {
    float slack = 1e-5 * p.z;
    if (p.z > 0.0 && abs(p.x) <= p.z + slack && abs(p.y) <= p.z + slack) {
        vec2 s = clamp(p.xy / p.z, vec2(-1.0), vec2(1.0));
        lo = min(lo, s);
        hi = max(hi, s);
    }
}

// Where edge a-b crosses the pyramid face k·p = 0, if it does.
void addCrossing(vec3 a, vec3 b, vec3 k, inout vec2 lo, inout vec2 hi) {
    float fa = dot(k, a), fb = dot(k, b);
    if ((fa < 0.0) != (fb < 0.0)) addIfInPyramid(mix(a, b, fa / (fa - fb)), lo, hi);
}

// Screen bounds of the part of triangle (a, b, c) inside the pyramid: its
// corners inside, its edges' crossings of the four faces, and the pyramid's
// corner rays that pierce it in front of the eye. Empty (lo > hi) when the
// triangle misses the pyramid. `inv` is the inverse of [a b c].
void pyramidBounds(vec3 a, vec3 b, vec3 c, mat3 inv, out vec2 lo, out vec2 hi) {
    lo = vec2(1e30);
    hi = vec2(-1e30);
    addIfInPyramid(a, lo, hi);
    addIfInPyramid(b, lo, hi);
    addIfInPyramid(c, lo, hi);
    const vec3 faces[4] = vec3[4](vec3(-1.0, 0.0, 1.0), vec3(1.0, 0.0, 1.0), vec3(0.0, -1.0, 1.0), vec3(0.0, 1.0, 1.0));
    for (int f = 0; f < 4; ++f) {  // constant bounds: unrolled
        addCrossing(a, b, faces[f], lo, hi);
        addCrossing(b, c, faces[f], lo, hi);
        addCrossing(c, a, faces[f], lo, hi);
    }
    for (int k = 0; k < 4; ++k) {
        vec2 corner = vec2((k & 1) != 0 ? 1.0 : -1.0, (k & 2) != 0 ? 1.0 : -1.0);
        vec3 bw = inv * vec3(corner, 1.0);
        if (all(greaterThanEqual(bw, vec3(0.0))) && bw.x + bw.y + bw.z > 0.0) {
            lo = min(lo, corner);
            hi = max(hi, corner);
        }
    }
}

// Local arrays indexed by variables become per-lane scratch memory on
// llvmpipe (many times slower), so everything here is straight-line code.
void main() {
    int t = gl_VertexID / 6;
    int i = gl_VertexID - 6 * t;
    // Two triangles of a quad: corners 0 1 2, 2 1 3 (bit 0: right, bit 1: top).
    int corner = i < 3 ? i : (i == 3 ? 2 : (i == 4 ? 1 : 3));
    vec4 p0 = uTriangles[3 * t], p1 = uTriangles[3 * t + 1], p2 = uTriangles[3 * t + 2];
#if MASKS
    vMask = floatBitsToUint(p1.w);
#endif
    if (uSkipLightId != 0u && floatBitsToUint(p0.w) == uSkipLightId) { dropTriangle(); return; }

    vec3 c0 = (uClipFromLocal * vec4(p0.xyz, 1.0)).xyw;
    vec3 c1 = (uClipFromLocal * vec4(p1.xyz, 1.0)).xyw;
    vec3 c2 = (uClipFromLocal * vec4(p2.xyz, 1.0)).xyw;
    vec3 dist = vec3(dot(uLightPlane.xyz, p0.xyz), dot(uLightPlane.xyz, p1.xyz), dot(uLightPlane.xyz, p2.xyz)) +
                uLightPlane.w;
    mat3 M = mat3(c0, c1, c2);
    float det = determinant(M);
    // det > 0: counter-clockwise as seen from the eye (see LightFrustum.h for the basis).
    if (det == 0.0 || (uCullBackFaces && det < 0.0)) { dropTriangle(); return; }

    // Wholly behind the eye's near plane, or (occluders of a planar light)
    // wholly behind the light: nothing to draw.
    vec3 w = vec3(c0.z, c1.z, c2.z);
    if (all(lessThan(w, vec3(uNear)))) { dropTriangle(); return; }
    if (uClipToLightPlane && all(lessThan(dist, vec3(uPlaneTolerance)))) { dropTriangle(); return; }
    // Wholly below the receiver's horizon (the floor it stands on): hides
    // nothing above it. Occluders only: the light is clipped to it already.
    vec3 height = vec3(dot(uHorizonPlane.xyz, p0.xyz), dot(uHorizonPlane.xyz, p1.xyz), dot(uHorizonPlane.xyz, p2.xyz)) +
                  uHorizonPlane.w;
    if (!uCullBackFaces && all(lessThanEqual(height, vec3(0.0)))) { dropTriangle(); return; }

    // Screen bounds, grown by one pixel: of the three corners when all are
    // in front of the near plane; otherwise (a wall passing beside or behind
    // the eye) of the part of the triangle inside the frustum's pyramid,
    // which is often nothing at all.
    float limit = 1.0 + uPixelNdc;
    vec2 lo, hi;
    if (all(greaterThanEqual(w, vec3(uNear)))) {
        vec2 s0 = c0.xy / c0.z, s1 = c1.xy / c1.z, s2 = c2.xy / c2.z;
        lo = min(min(s0, s1), s2);
        hi = max(max(s0, s1), s2);
    } else {
        // The pyramid clip is well conditioned only when the triangle's plane
        // keeps some distance from the eye (the apex): within 1e-3 of the
        // triangle's size (a receiver right under a light's edge) float
        // rounding can lose part of the clipped outline, so the whole image
        // is kept and the fragment stage's exact tests clip.
        vec3 normal = cross(c1 - c0, c2 - c0);
        float size = max(max(length(c1 - c0), length(c2 - c1)), length(c0 - c2));
        if (abs(det) > 1e-3 * size * length(normal)) {
            pyramidBounds(c0, c1, c2, inverse(M), lo, hi);
        } else {
            lo = vec2(-1.0);
            hi = vec2(1.0);
        }
    }
    lo = max(lo - uPixelNdc, vec2(-limit));
    hi = min(hi + uPixelNdc, vec2(limit));
    if (any(greaterThanEqual(lo, hi))) { dropTriangle(); return; }
    vec2 s = vec2((corner & 1) != 0 ? hi.x : lo.x, (corner & 2) != 0 ? hi.y : lo.y);
    vec3 bw = inverse(M) * vec3(s, 1.0);
    vBaryOverW = bw;
    vPlaneOverW = dot(dist, bw);
    // z_ndc = near / w is affine in screen space too; depth clamp keeps
    // corners whose extrapolated plane lies behind the eye.
    gl_Position = vec4(s, uNear * (bw.x + bw.y + bw.z), 1.0);
}
