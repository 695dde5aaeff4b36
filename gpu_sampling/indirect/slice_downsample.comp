// Averages ss×ss sub-texels into one texel of a face: premultiplied
// radiance and covered fraction, and the mean depth of what covers it.
layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 0) uniform sampler2D source;
layout(binding = 1) uniform sampler2D sourceDepth;
layout(rgba32f, binding = 0) uniform writeonly image2DArray faces;
layout(r32f, binding = 1) uniform writeonly image2DArray depths;
uniform int ss;
uniform int layer;
uniform ivec2 size;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= size.x || p.y >= size.y) return;
    vec4 sum = vec4(0.0);
    vec2 depth = vec2(0.0);
    for (int j = 0; j < ss; ++j)
        for (int i = 0; i < ss; ++i) {
            sum += texelFetch(source, p * ss + ivec2(i, j), 0);
            depth += texelFetch(sourceDepth, p * ss + ivec2(i, j), 0).xy;
        }
    imageStore(faces, ivec3(p, layer), sum / float(ss * ss));
    // The mean depth of what covers the texel (where in the slice it lies).
    imageStore(depths, ivec3(p, layer), vec4(depth.y > 0.0 ? depth.x / depth.y : 0.0));
}
