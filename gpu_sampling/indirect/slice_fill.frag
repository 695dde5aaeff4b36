uniform int axis;
uniform float towardViewer;  // +1: the face looks at the slice from larger coordinates

in vec3 vRadiance;
in float vDepth;
flat in vec4 vNormalClosed;
layout(location = 0) out vec4 color;
layout(location = 1) out vec2 depth;  // (coordinate along the axis, 1) where covered

void main() {
    bool front = vNormalClosed[axis] * towardViewer > 0.0;
    // An open surface's back is drawn by its own reversed copy.
    if (!front && vNormalClosed.w < 0.5) discard;
    // The inside of a closed object: black, but it blocks.
    color = front ? vec4(max(vRadiance, vec3(0.0)), 1.0) : vec4(0.0, 0.0, 0.0, 1.0);
    depth = vec2(vDepth, 1.0);
}
