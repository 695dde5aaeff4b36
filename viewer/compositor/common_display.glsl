// Display mapping of a pixel, shared by display.frag (deferred, S×S
// sub-pixels) and scene_forward.frag (one sample per pixel): radiance
// tone-mapped as toneMap() does on the CPU (exposure, operator, clip, sRGB),
// reflectance through the sRGB curve, illuminance in false colour with
// optional iso-lux lines. QUANTITY, OPERATOR (0 ACES, 1 Reinhard, 2 clamp)
// and CONTOURS are #defines: llvmpipe runs every branch under a mask, so
// each variant is compiled with only its own code.
uniform float uExposure;
uniform float uLog10LuxMin;
uniform float uLog10LuxMax;

// falseColourPalette(): display values, evenly spaced stops.
layout(std430, binding = 1) readonly buffer PaletteBuffer { vec4 uPalette[]; };
uniform int uPaletteSize;

float srgbOetf(float v) {
    v = clamp(v, 0.0, 1.0);
    return v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
}

float aces(float x) { return clamp(x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0); }

// luxLevelIndex() of Illuminance.cpp: an integer at each 1-2-5 value.
float levelIndex(float lux) {
    float k = floor(log(lux) / log(10.0));
    float m = max(lux / pow(10.0, k), 1.0);
    float within = m < 2.0 ? m - 1.0 : (m < 5.0 ? 1.0 + (m - 2.0) / 3.0 : min(2.0 + (m - 5.0) / 5.0, 3.0));
    return 3.0 * k + within;
}

vec3 falseColour(float t) {
    float x = clamp(t, 0.0, 1.0) * float(uPaletteSize - 1);
    int i = min(int(x), uPaletteSize - 2);
    return mix(uPalette[i].rgb, uPalette[i + 1].rgb, x - float(i));
}

// `value`: the pixel's mean quantity (black off every surface); `coverage`:
// the share of the pixel that sees a surface.
vec4 displayColour(vec3 value, float coverage) {
#if QUANTITY == 2
    // Lux where a surface is seen, whatever share of the pixel it covers.
    float lux = coverage > 0.0 ? value.r / coverage : 0.0;
    float t = lux > 0.0 ? (log(lux) / log(10.0) - uLog10LuxMin) / max(uLog10LuxMax - uLog10LuxMin, 1e-6) : 0.0;
    vec3 c = coverage > 0.0 ? falseColour(t) : vec3(0.08);
#if CONTOURS
    // A line where the level index crosses an integer, about a pixel wide;
    // none across silhouettes or jumps of more than a level.
    float index = lux > 0.0 ? levelIndex(lux) : -60.0;
    float width = fwidth(index);
    float d = abs(fract(index + 0.5) - 0.5) / max(width, 1e-6);
    if (coverage >= 1.0 && width < 1.0) c = mix(vec3(0.0), c, clamp(d, 0.0, 1.0));
#endif
    return vec4(c, 1.0);
#else
    vec3 c = value;
#if QUANTITY == 0
    c = max(c * uExposure, vec3(0.0));
#if OPERATOR == 0
    c = vec3(aces(c.r), aces(c.g), aces(c.b));
#elif OPERATOR == 1
    c /= 1.0 + dot(c, kLuminance);
#endif
#endif
    return vec4(srgbOetf(c.r), srgbOetf(c.g), srgbOetf(c.b), 1.0);
#endif
}
