// Adds one cache mesh's irradiance (drawn on its own) to the sum, by blending.
layout(binding = 3) uniform sampler2D uMeshIrradiance;

layout(location = 0) out vec4 outIrradiance;

void main() { outIrradiance = texelFetch(uMeshIrradiance, ivec2(gl_FragCoord.xy), 0); }
