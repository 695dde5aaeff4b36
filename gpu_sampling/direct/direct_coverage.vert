// Coverage pass, vertex stage: the dilation of §4.2.1 done in screen space,
// one triangle at a time by vertex pulling (six vertices, a quad, per
// triangle; llvmpipe runs vertex stages eight wide, geometry stages one
// primitive at a time, so this replaced a geometry shader at a third of the cost).
//
// The paper dilates triangles by a fixed percentage, which does not guarantee
// a pixel of margin for every view. Here each triangle is replaced by the
// screen-space bounding rectangle of its visible part (clipped to the near
// plane and, for occluders of a planar light, to the light's plane), grown by
// one pixel on every side: every pixel the triangle touches gets a fragment,
// whatever the view.
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
uniform float uNear;            // near distance; the projection puts z_clip = uNear
uniform float uPixelNdc;        // one pixel in NDC units (2 / image size)
uniform bool uCullBackFaces;    // the light emits from its front face only
uniform uint uSkipLightId;      // faces of this light are not occluders (0: skip none)
uniform bool uClipToLightPlane; // occluders of a planar light: keep the eye's side only
uniform float uPlaneTolerance;  // distance below which a face counts as on the plane

noperspective out vec3 vBaryOverW;
noperspective out float vPlaneOverW;

const int kCorner[6] = int[6](0, 1, 2, 2, 1, 3);

void dropTriangle() {
    // All six vertices at one point: zero area, no fragment.
    gl_Position = vec4(-4.0, -4.0, 0.0, 1.0);
    vBaryOverW = vec3(0.0);
    vPlaneOverW = 0.0;
}

void main() {
    int t = gl_VertexID / 6;
    int corner = kCorner[gl_VertexID - t * 6];
    vec4 p[3] = vec4[3](uTriangles[3 * t], uTriangles[3 * t + 1], uTriangles[3 * t + 2]);
    if (uSkipLightId != 0u && floatBitsToUint(p[0].w) == uSkipLightId) { dropTriangle(); return; }

    vec3 clip[3];
    vec3 dist;
    for (int i = 0; i < 3; ++i) {
        vec4 c = uClipFromLocal * vec4(p[i].xyz, 1.0);
        clip[i] = c.xyw;
        dist[i] = dot(uLightPlane.xyz, p[i].xyz) + uLightPlane.w;
    }
    mat3 M = mat3(clip[0], clip[1], clip[2]);
    float det = determinant(M);
    // det > 0: counter-clockwise as seen from the eye (see LightFrustum.h for the basis).
    if (det == 0.0 || (uCullBackFaces && det < 0.0)) { dropTriangle(); return; }

    // Clip to w >= near and (optionally) to the light plane, in homogeneous
    // space, to bound the triangle's visible part on screen.
    vec4 poly[5];  // xyw, plane distance
    vec4 next[5];
    int n = 3;
    for (int i = 0; i < 3; ++i) poly[i] = vec4(clip[i], dist[i]);
    for (int plane = 0; plane < 2; ++plane) {
        if (plane == 1 && !uClipToLightPlane) break;
        int m = 0;
        for (int i = 0; i < n; ++i) {
            vec4 a = poly[i];
            vec4 b = poly[(i + 1) % n];
            float fa = plane == 0 ? a.z - uNear : a.w - uPlaneTolerance;
            float fb = plane == 0 ? b.z - uNear : b.w - uPlaneTolerance;
            if (fa >= 0.0) next[m++] = a;
            if ((fa >= 0.0) != (fb >= 0.0) && m < 5) next[m++] = mix(a, b, fa / (fa - fb));
        }
        n = m;
        for (int i = 0; i < n; ++i) poly[i] = next[i];
        if (n < 3) { dropTriangle(); return; }
    }

    vec2 lo = vec2(1e30), hi = vec2(-1e30);
    for (int i = 0; i < n; ++i) {
        vec2 s = poly[i].xy / poly[i].z;
        lo = min(lo, s);
        hi = max(hi, s);
    }
    // One pixel of margin, then keep to the image (plus that margin).
    float limit = 1.0 + uPixelNdc;
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
