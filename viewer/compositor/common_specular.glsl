// The specular pass's image (SpecularPaths, traced on the CPU): mirrors,
// glass and Phong highlights, added to the cached Kd/π × E + Le. SPECULAR
// is a #define: 0 no image (scenes without glossy or specular materials
// compile exactly the shaders of before), 1 added, 2 alone (SpecularPart).
#if SPECULAR
// A texel per uSpecularReduction² sub-pixels, row 0 at the image's top.
layout(binding = 7) uniform sampler2D uSpecular;
uniform int uSpecularReduction;  // 1 for images; more while the viewer's camera moves
uniform int uSpecularRows;       // sub-pixel rows of the target drawn

// W·sr⁻¹·m⁻² at sub-pixel p (GL's rows, from the bottom).
vec3 specularAt(ivec2 p) {
    ivec2 q = ivec2(p.x, uSpecularRows - 1 - p.y) / uSpecularReduction;
    return texelFetch(uSpecular, q, 0).rgb;
}
#endif
