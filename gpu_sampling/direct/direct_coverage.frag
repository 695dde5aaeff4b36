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

#if MASKS
// Occluders with a cut-out (Material::alphaMap; CutOuts in
// DirectLightSampler.cpp): a sample where the face's coverage is below its
// cut-off is not on the face, as Embree's filter decides for the ray-traced
// sampler. Texture::coverage's lookup, in float: wrapped, nearest or bilinear.
flat in uint vMask;  // 1 + the face's record, 0: opaque
layout(std430, binding = 1) readonly buffer MaskFaces { vec4 uMaskFaces[]; };
layout(std430, binding = 2) readonly buffer MaskImages { uint uMaskImages[]; };

float maskWrapped(float u, uint mode) {  // TextureWrap: 0 repeat, 1 mirrored repeat, 2 clamp to edge
    return mode == 2u ? clamp(u, -1.0, 2.0) : u - 2.0 * floor(u / 2.0);
}

int maskIndex(int i, int size, uint mode) {
    if (mode == 2u) return clamp(i, 0, size - 1);
    int period = mode == 1u ? 2 * size : size;
    i = i - period * int(floor(float(i) / float(period)));
    return mode == 1u && i >= size ? period - 1 - i : i;
}

float maskTexel(uint header, float x, float y) {
    int width = int(uMaskImages[header + 1u]), height = int(uMaskImages[header + 2u]);
    uint flags = uMaskImages[header + 3u];
    int i = maskIndex(int(x), width, flags & 3u), j = maskIndex(int(y), height, (flags >> 2) & 3u);
    uint texel = uMaskImages[header] + uint(j * width + i);
    return float((uMaskImages[texel / 4u] >> (8u * (texel % 4u))) & 255u) / 255.0;
}

// Whether the face is cut away at barycentrics `bary` (summing to 1).
bool cutAway(vec3 bary) {
    vec4 a = uMaskFaces[2u * (vMask - 1u)], b = uMaskFaces[2u * (vMask - 1u) + 1u];
    uint header = 12u * floatBitsToUint(b.z);
    vec2 uv = bary.x * a.xy + bary.y * a.zw + bary.z * b.xy;
    uv = uv * vec2(uintBitsToFloat(uMaskImages[header + 6u]), uintBitsToFloat(uMaskImages[header + 7u])) +
         vec2(uintBitsToFloat(uMaskImages[header + 8u]), uintBitsToFloat(uMaskImages[header + 9u]));
    uint flags = uMaskImages[header + 3u];
    float x = maskWrapped(uv.x, flags & 3u) * float(uMaskImages[header + 1u]);
    float y = maskWrapped(uv.y, (flags >> 2) & 3u) * float(uMaskImages[header + 2u]);
    float coverage;
    if ((flags & 16u) != 0u) {
        coverage = maskTexel(header, floor(x), floor(y));
    } else {
        float x0 = floor(x - 0.5), y0 = floor(y - 0.5), fx = x - 0.5 - x0, fy = y - 0.5 - y0;
        coverage = mix(mix(maskTexel(header, x0, y0), maskTexel(header, x0 + 1.0, y0), fx),
                       mix(maskTexel(header, x0, y0 + 1.0), maskTexel(header, x0 + 1.0, y0 + 1.0), fx), fy);
    }
    return uintBitsToFloat(uMaskImages[header + 4u]) * coverage < uintBitsToFloat(uMaskImages[header + 5u]);
}
#endif

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
#if MASKS
    if (inside && vMask != 0u) inside = !cutAway(b / invW);
#endif
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
#if MASKS
    allInside = allInside && vMask == 0u;  // a face with holes is tested sample by sample
#endif
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
