// Per sub-pixel: Lambertian radiance from cached irradiance, Kd/π × ΣE + Le;
// or the reflectance; or the illuminance in lux (common_composite.glsl).
layout(location = 0) out vec4 outValue;  // alpha: 1 where a surface is seen

void main() { outValue = compositeValue(ivec2(gl_FragCoord.xy)); }
