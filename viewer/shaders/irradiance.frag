in vec3 vIrradiance;
layout(location = 0) out vec4 outIrradiance;

void main() { outIrradiance = vec4(vIrradiance, 1.0); }
