// An edge, a pixel or so wide, where this mesh's surface is the one the
// composite saw (its depth within a small relative margin of the scene's:
// the cache lies on the scene's surfaces but is tessellated differently).
noperspective in vec3 vBarycentric;

layout(binding = 0) uniform sampler2D uSceneDepth;  // reversed depth, supersampled
uniform int uSupersample;
uniform vec3 uColor;

layout(location = 0) out vec4 outColor;

void main() {
    float sceneDepth = texelFetch(uSceneDepth, ivec2(gl_FragCoord.xy) * uSupersample, 0).r;
    // Reversed depth (near / distance): 0.2% further than the scene is hidden.
    if (gl_FragCoord.z < sceneDepth * 0.998) discard;
    // Distance to the nearest edge in pixels (barycentrics are linear on screen).
    vec3 d = vBarycentric / max(fwidth(vBarycentric), vec3(1e-7));
    float edge = min(d.x, min(d.y, d.z));
    if (edge >= 0.75) discard;
    outColor = vec4(uColor, 0.9 * (1.0 - edge / 0.75));
}
