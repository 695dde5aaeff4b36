// The window's image in one pass at one sample per pixel: the scene's own
// geometry, shaded from the cached irradiance laid down before it.
layout(location = 0) in vec3 aPosition;   // relative to the scene's centre
layout(location = 1) in vec3 aKd;
layout(location = 2) in int aLight;       // the light this face emits as, −1 for none
#if TEXTURES
layout(location = 3) in vec2 aUv;         // Mesh::texcoords, (0, 0) where the mesh has none
out vec2 vUv;
#endif

uniform mat4 uClipFromLocal;

flat out vec3 vKd;
flat out int vLight;

invariant gl_Position;

void main() {
    vKd = aKd;
    vLight = aLight;
#if TEXTURES
    vUv = aUv;
#endif
    gl_Position = uClipFromLocal * vec4(aPosition, 1.0);
}
