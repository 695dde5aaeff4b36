// Coverage pass, fragment stage: BITS membership tests per pixel at jittered
// points (§4.2.1 eq. 5, §4.2.2), one bit each. BITS, STRATA_X, STRATA_Y and
// JITTER are #defined per program variant, so the loop unrolls and the
// strata need no integer division (slow on llvmpipe).
//
// Convention of the paper: a bit is 1 where the sample is NOT on this
// triangle. The light is drawn with GL_OR_INVERTED (dst |= ~src: the light's
// samples are switched on, the union of its triangles), the occluders with
// GL_AND (dst &= src: a sample an occluder covers is switched off).
noperspective in vec3 vBaryOverW;
noperspective in float vPlaneOverW;

// The same bits to both images: the first becomes "visible light" (occluders
// AND into it), the second stays "light" (masked during the occluder pass).
layout(location = 0) out uint outOutsideBits;
layout(location = 1) out uint outOutsideBitsLightOnly;

uniform uint uSeed;             // fresh for every pass: independent jitter
uniform int uImageSize;         // pixels per side
uniform float uNear;
uniform bool uClipToLightPlane;
uniform float uPlaneTolerance;

// Whether the point at offset o (pixels from the centre) lies on the
// triangle's visible part.
bool covers(vec2 o, vec3 bdx, vec3 bdy, float pdx, float pdy, float maxInvW) {
    vec3 b = vBaryOverW + o.x * bdx + o.y * bdy;
    float invW = b.x + b.y + b.z;
    bool inside = invW > 0.0 && invW <= maxInvW && all(greaterThanEqual(b, vec3(0.0)));
    if (uClipToLightPlane) inside = inside && (vPlaneOverW + o.x * pdx + o.y * pdy) >= uPlaneTolerance * invW;
    return inside;
}

void main() {
    // Screen derivatives of affine attributes are exact (see the vertex stage).
    vec3 bdx = dFdx(vBaryOverW), bdy = dFdy(vBaryOverW);
    float pdx = dFdx(vPlaneOverW), pdy = dFdy(vPlaneOverW);
    float maxInvW = 1.0 / uNear;
    uint unused = BITS >= 32 ? 0u : (0xffffffffu << uint(BITS));

    // Every tested quantity is affine across the pixel, so its extremes are
    // at the pixel's corners: when all four corners agree, every jittered
    // point agrees with them and no sample needs hashing. Only pixels on an
    // edge of the triangle (or of its clipped part) run the per-sample loop.
    vec3 reach = 0.5 * (abs(bdx) + abs(bdy));
    if (any(lessThan(vBaryOverW + reach, vec3(0.0)))) discard;  // wholly outside one edge
    bool c0 = covers(vec2(-0.5, -0.5), bdx, bdy, pdx, pdy, maxInvW);
    bool c1 = covers(vec2(0.5, -0.5), bdx, bdy, pdx, pdy, maxInvW);
    bool c2 = covers(vec2(-0.5, 0.5), bdx, bdy, pdx, pdy, maxInvW);
    bool c3 = covers(vec2(0.5, 0.5), bdx, bdy, pdx, pdy, maxInvW);
    uint outside = unused;
    if (!(c0 && c1 && c2 && c3)) {
        uint pixel = uint(gl_FragCoord.y) * uint(uImageSize) + uint(gl_FragCoord.x);
        for (int k = 0; k < BITS; ++k) {
            vec2 o = mlJitter(pixel, uint(k), uSeed, k % STRATA_X, k / STRATA_X, STRATA_X, STRATA_Y, JITTER) - 0.5;
            if (!covers(o, bdx, bdy, pdx, pdy, maxInvW)) outside |= 1u << uint(k);
        }
        // Nothing of this triangle here: leave colour and depth alone.
        if (outside == 0xffffffffu) discard;
    }
    outOutsideBits = outside;
    outOutsideBitsLightOnly = outside;
}
