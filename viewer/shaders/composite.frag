// Lambertian radiance from cached irradiance: Kd/π × Σ E + Le.
layout(binding = 0) uniform sampler2D uReflectance;
layout(binding = 1) uniform sampler2D uEmission;
layout(binding = 2) uniform sampler2D uIrradiance;

layout(location = 0) out vec4 outRadiance;

const float kInvPi = 0.31830988618379067;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 kd = texelFetch(uReflectance, p, 0);
    vec3 e = texelFetch(uIrradiance, p, 0).rgb;
    vec3 le = texelFetch(uEmission, p, 0).rgb;
    // kd.a is 0 where no surface was drawn: the background stays black.
    outRadiance = vec4(kd.a > 0.0 ? kd.rgb * kInvPi * e + le : vec3(0.0), 1.0);
}
