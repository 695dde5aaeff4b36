// Shades the nearest surface of each pixel as compositeValue() does for a
// sub-pixel, straight from the face's Kd and light (no float G-buffer to
// write and read back: the cost that dominates on a software rasteriser),
// then maps it for display (common_display.glsl).
flat in vec3 vKd;
flat in int vLight;

layout(binding = 1) uniform sampler2D uIrradiance;  // Σ weighted cached irradiance, W·m⁻²
layout(std430, binding = 0) readonly buffer LightEmissionBuffer { vec4 uLightEmission[]; };
uniform vec3 uLuxFactors;  // lm/W per channel: Photometry::factors(), efficacy × luminance weights

layout(location = 0) out vec4 outColor;

void main() {
    footprintBegin();
    if (cutAway()) discard;  // a hole of a cut-out: what lies behind shows
    // Back faces a hair behind, as in scene_gbuffer.frag: of two coincident
    // layers facing opposite ways the front one shows.
    gl_FragDepth = gl_FrontFacing ? gl_FragCoord.z : gl_FragCoord.z * (1.0 - 1e-6);  // reversed: smaller is further
#if QUANTITY == 1
    vec3 value = surfaceKd(vKd);
#else
    vec3 e = texelFetch(uIrradiance, ivec2(gl_FragCoord.xy), 0).rgb;
#if QUANTITY == 2
    vec3 value = vec3(dot(e, uLuxFactors));
#else
    // Emitters radiate from their front (counter-clockwise) face only.
    vec3 le = gl_FrontFacing && vLight >= 0 ? uLightEmission[max(vLight, 0)].rgb * emissionScale() : vec3(0.0);
    vec3 value = surfaceKd(vKd) * kInvPi * e + le;
#if SPECULAR == 1
    value += specularAt(ivec2(gl_FragCoord.xy));
#elif SPECULAR == 2
    value = specularAt(ivec2(gl_FragCoord.xy));
#endif
#endif
#endif
    outColor = displayColour(value, 1.0);
}
