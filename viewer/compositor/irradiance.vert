// Irradiance pass: a cache mesh with its per-vertex irradiance,
// interpolated across triangles (Gouraud) by the rasteriser.
layout(location = 0) in vec3 aPosition;   // relative to the scene's centre
layout(location = 1) in vec3 aIrradiance; // W·m⁻²

uniform mat4 uClipFromLocal;
// The mesh's weight (LightWeights): exact, since irradiance is linear in emission.
uniform vec3 uWeight;

out vec3 vIrradiance;

invariant gl_Position;

void main() {
    vIrradiance = aIrradiance * uWeight;
    gl_Position = uClipFromLocal * vec4(aPosition, 1.0);
}
