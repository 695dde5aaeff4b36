// A proxy triangle's radiance (Gouraud) where its reflecting side faces the
// eye; the back of a closed object's surface is black and opaque; an open
// surface's back is its reversed copy's to draw. The side is decided from
// the plane, not the winding, so it holds for mirrored and fish-eye images.
// FISHEYE_DEPTH: depth is the distance from the eye (the fish-eye image has
// no projective depth of its own).
in vec3 vToPoint;
in vec3 vRadiance;
flat in vec4 vNormalClosed;
uniform float maxDistance;  // FISHEYE_DEPTH: depth = distance / maxDistance

out vec4 color;

void main() {
    bool front = dot(vNormalClosed.xyz, vToPoint) < 0.0;
    if (!front && vNormalClosed.w < 0.5) discard;
    color = front ? vec4(max(vRadiance, vec3(0.0)), 1.0) : vec4(0.0, 0.0, 0.0, 1.0);
#ifdef FISHEYE_DEPTH
    gl_FragDepth = clamp(length(vToPoint) / maxDistance, 0.0, 1.0);
#endif
}
