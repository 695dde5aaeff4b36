// The radiance proxy drawn with the fish-eye projection of §5.2 in the vertex
// stage: a point's direction from the eye, (x, y) in the tangent frame
// divided by its distance, is its place on the image (orthographic
// projection of the hemisphere, fisheye_common.glsl). Unlike the paper's
// z = w = 1 trick, clip coordinates are proper (w = 1, z inside the volume)
// and the horizon is a clip plane; the fragment stage writes the distance as
// depth. Edges stay straight on the image while true edges are arcs: exact
// at the corners, off in between by about (edge / distance)² of the edge's
// angle, which matters for proxy triangles close to the eye only.
layout(location = 0) in vec3 position;      // relative to the grid's origin
layout(location = 1) in vec4 normalClosed;  // the reflecting side's normal; w: 1 if closed
layout(location = 2) in vec3 radiance;      // exitant, W·sr⁻¹·m⁻²

uniform vec3 eye;    // relative to the grid's origin
uniform mat3 basis;  // columns r, u, v (v: the surface normal)
uniform vec2 shift;  // the gather's sub-pixel offset of the image, NDC units

out vec3 vToPoint;
out vec3 vRadiance;
flat out vec4 vNormalClosed;

void main() {
    vec3 toPoint = position - eye;
    vec3 local = transpose(basis) * toPoint;
    float r = max(length(local), 1e-30);
    gl_Position = vec4(local.xy / r + shift, 0.0, 1.0);
    gl_ClipDistance[0] = local.z;  // above the horizon only
    vToPoint = toPoint;
    vRadiance = radiance;
    vNormalClosed = normalClosed;
}
