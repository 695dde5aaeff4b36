// Box filter: the mean of a pixel's S×S sub-pixels of the composite, and in
// alpha the fraction of them that see a surface.
layout(binding = 2) uniform sampler2D uComposite;
uniform int uSupersample;

layout(location = 0) out vec4 outPixel;

void main() {
    ivec2 base = ivec2(gl_FragCoord.xy) * uSupersample;
    vec4 sum = vec4(0.0);
    for (int y = 0; y < uSupersample; ++y)
        for (int x = 0; x < uSupersample; ++x) sum += texelFetch(uComposite, base + ivec2(x, y), 0);
    outPixel = sum / float(uSupersample * uSupersample);
}
