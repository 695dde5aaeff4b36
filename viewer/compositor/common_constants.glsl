// Constants of the compositing shaders.
const float kInvPi = 0.31830988618379067;
// Display luminance (the Reinhard operator), Rec. 709 as luminance() in core/Math.h;
// lux takes the photometry's weights instead (uLuxFactors).
const vec3 kLuminance = vec3(0.2126, 0.7152, 0.0722);
