// The value of one composited sub-pixel, shared by composite.frag (images
// read back) and display.frag (the window, fused with the box filter).
// QUANTITY (0 radiance, 1 reflectance, 2 illuminance: CompositeQuantity) is
// a #define, not a uniform: llvmpipe runs every branch of a shader under a
// mask, so each variant is compiled with only its own code.
layout(binding = 0) uniform sampler2D uSurface;     // rgb: Kd; a: 0 nothing, 1 a surface, 2 + l the front of light l
layout(binding = 1) uniform sampler2D uIrradiance;  // Σ weighted cached irradiance, W·m⁻²
#if TEXTURES
layout(binding = 6) uniform sampler2D uEmissionScale;  // rgb: the emission texture over the light's radiance
#endif

// Each light's emitted radiance times its weight (LightWeights::light):
// what its emitting faces show.
layout(std430, binding = 0) readonly buffer LightEmissionBuffer { vec4 uLightEmission[]; };

uniform vec3 uLuxFactors;  // lm/W per channel: Photometry::factors(), efficacy × luminance weights

// rgb: the quantity; a: 1 where a surface is seen, else 0 (and rgb 0).
vec4 compositeValue(ivec2 p) {
    vec4 s = texelFetch(uSurface, p, 0);
    float seen = s.a > 0.0 ? 1.0 : 0.0;
#if QUANTITY == 1
    return vec4(s.rgb * seen, seen);
#else
    vec3 e = texelFetch(uIrradiance, p, 0).rgb;
#if QUANTITY == 2
    return vec4(vec3(dot(e, uLuxFactors)) * seen, seen);
#else
    vec3 le = s.a >= 2.0 ? uLightEmission[max(int(s.a) - 2, 0)].rgb : vec3(0.0);
#if TEXTURES
    le *= texelFetch(uEmissionScale, p, 0).rgb;
#endif
#if SPECULAR == 1
    return vec4((s.rgb * kInvPi * e + le + specularAt(p)) * seen, seen);
#elif SPECULAR == 2
    return vec4(specularAt(p) * seen, seen);
#else
    return vec4((s.rgb * kInvPi * e + le) * seen, seen);
#endif
#endif
#endif
}
