// Cache-mesh edges over the image: positions only.
layout(location = 0) in vec3 aPosition;   // relative to the scene's centre

uniform mat4 uClipFromLocal;

invariant gl_Position;

void main() { gl_Position = uClipFromLocal * vec4(aPosition, 1.0); }
