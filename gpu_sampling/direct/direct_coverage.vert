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
// first holds 1 + the index of the light the face belongs to (0: none).
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

void dropTriangle() {
    // All six vertices at one point: zero area, no fragment.
    gl_Position = vec4(-4.0, -4.0, 0.0, 1.0);
    vBaryOverW = vec3(0.0);
    vPlaneOverW = 0.0;
}

// Local arrays indexed by variables become per-lane scratch memory on
// llvmpipe (many times slower), so everything here is straight-line code.
void main() {
    int t = gl_VertexID / 6;
    int i = gl_VertexID - 6 * t;
    // Two triangles of a quad: corners 0 1 2, 2 1 3 (bit 0: right, bit 1: top).
    int corner = i < 3 ? i : (i == 3 ? 2 : (i == 4 ? 1 : 3));
    vec4 p0 = uTriangles[3 * t], p1 = uTriangles[3 * t + 1], p2 = uTriangles[3 * t + 2];
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
    // in front of the near plane; otherwise (an occluder touching the eye:
    // rare) the whole image, and the fragment stage's exact tests clip.
    float limit = 1.0 + uPixelNdc;
    vec2 lo = vec2(-limit), hi = vec2(limit);
    if (all(greaterThanEqual(w, vec3(uNear)))) {
        vec2 s0 = c0.xy / c0.z, s1 = c1.xy / c1.z, s2 = c2.xy / c2.z;
        lo = max(min(min(s0, s1), s2) - uPixelNdc, vec2(-limit));
        hi = min(max(max(s0, s1), s2) + uPixelNdc, vec2(limit));
        if (any(greaterThanEqual(lo, hi))) { dropTriangle(); return; }
    }
    vec2 s = vec2((corner & 1) != 0 ? hi.x : lo.x, (corner & 2) != 0 ? hi.y : lo.y);
    vec3 bw = inverse(M) * vec3(s, 1.0);
    vBaryOverW = bw;
    vPlaneOverW = dot(dist, bw);
    // z_ndc = near / w is affine in screen space too; depth clamp keeps
    // corners whose extrapolated plane lies behind the eye.
    gl_Position = vec4(s, uNear * (bw.x + bw.y + bw.z), 1.0);
}
