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

    // Every tested quantity is affine across the pixel, so its extremes over
    // the pixel are its centre value ± half the sum of its derivatives'
    // magnitudes: when they all agree, every jittered point agrees with them
    // and no sample needs hashing. Only pixels on an edge of the triangle (or
    // of its clipped part) run the per-sample loop.
    vec3 bReach = 0.5 * (abs(bdx) + abs(bdy));
    float invW = vBaryOverW.x + vBaryOverW.y + vBaryOverW.z;
    float wReach = bReach.x + bReach.y + bReach.z;  // bounds the reach of their sum
    float plane = vPlaneOverW - uPlaneTolerance * invW;
    float planeReach = 0.5 * (abs(pdx - uPlaneTolerance * (bdx.x + bdx.y + bdx.z)) +
                              abs(pdy - uPlaneTolerance * (bdy.x + bdy.y + bdy.z)));
    bool planeOut = uClipToLightPlane && plane + planeReach < 0.0;
    bool planeIn = !uClipToLightPlane || plane - planeReach >= 0.0;
    if (any(lessThan(vBaryOverW + bReach, vec3(0.0))) || invW + wReach <= 0.0 || planeOut) discard;
    bool allInside = all(greaterThanEqual(vBaryOverW - bReach, vec3(0.0))) && invW - wReach > 0.0 &&
                     invW + wReach <= maxInvW && planeIn;
    uint outside = unused;
    if (!allInside) {
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
