// The window's image in one pass when pixels are supersampled: each pixel
// composites its S×S sub-pixels (common_composite.glsl), averages them and
// maps the mean for display (common_display.glsl). SUPERSAMPLE is a #define.
layout(location = 0) out vec4 outColor;

void main() {
    ivec2 base = ivec2(gl_FragCoord.xy) * SUPERSAMPLE;
    vec4 sum = vec4(0.0);
    for (int y = 0; y < SUPERSAMPLE; ++y)
        for (int x = 0; x < SUPERSAMPLE; ++x) sum += compositeValue(base + ivec2(x, y));
    const float n = float(SUPERSAMPLE * SUPERSAMPLE);
    outColor = displayColour(sum.rgb / n, sum.a / n);
}
