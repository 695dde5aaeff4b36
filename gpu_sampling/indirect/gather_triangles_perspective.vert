// A perspective view of the radiance proxy: the wide single plane, or one
// face of a hemicube. Reversed, infinite depth (z_clip = near, w = distance
// along the view, glClipControl zero-to-one), as the direct-light sampler's.
layout(location = 0) in vec3 position;      // relative to the grid's origin
layout(location = 1) in vec4 normalClosed;  // the reflecting side's normal; w: 1 if closed
layout(location = 2) in vec3 radiance;      // exitant, W·sr⁻¹·m⁻²

uniform mat4 clipFromOrigin;
uniform vec3 eye;  // relative to the grid's origin

out vec3 vToPoint;
out vec3 vRadiance;
flat out vec4 vNormalClosed;

void main() {
    gl_Position = clipFromOrigin * vec4(position, 1.0);
    vToPoint = position - eye;
    vRadiance = radiance;
    vNormalClosed = normalClosed;
}
