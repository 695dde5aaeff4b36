// Parallel projection of the radiance proxy onto one slice face (§5.3).
layout(location = 0) in vec3 position;   // relative to the grid's origin
layout(location = 1) in vec3 radiance;   // exitant, W·sr⁻¹·m⁻²
layout(location = 2) in vec4 normalClosed; // xyz: the side that reflects; w: 1 if the back is a closed object's inside

uniform int axis;
uniform vec2 extentUV;      // the face's size along its two texture axes
uniform vec2 texelOrigin;   // where its texels start, relative to the grid's origin
uniform float nearPlane;    // along `axis`, the viewer's side (relative to the origin)
uniform float farPlane;

out vec3 vRadiance;
out float vDepth;  // the coordinate along the slice's axis (relative to the grid's origin)
flat out vec4 vNormalClosed;

void main() {
    int ua = (axis + 1) % 3, va = (axis + 2) % 3;
    vec2 uv = (vec2(position[ua], position[va]) - texelOrigin) / extentUV * 2.0 - 1.0;
    float z = (position[axis] - nearPlane) / (farPlane - nearPlane) * 2.0 - 1.0;
    gl_Position = vec4(uv, z, 1.0);
    vRadiance = radiance;
    vDepth = position[axis];
    vNormalClosed = normalClosed;
}
