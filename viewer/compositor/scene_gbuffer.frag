flat in vec3 vKd;
flat in int vLight;

// rgb: Kd. a: 1 for a surface, 2 + l where the front of light l is seen:
// a light's radiance is uniform (one material), so the compositor looks it
// up, times the light's weight, instead of storing it per sub-pixel; with
// TEXTURES, a second target holds what an emission texture scales it by.
layout(location = 0) out vec4 outSurface;
#if TEXTURES
layout(location = 1) out vec4 outEmissionScale;
#endif

void main() {
    footprintBegin();
    if (cutAway()) discard;  // a hole of a cut-out: what lies behind shows
    // Back faces a hair behind their depth, as irradiance.frag's: a surface
    // modelled two-sided as two coincident layers facing opposite ways (the
    // back rooms' walls) would otherwise depth-fight in a screen-aligned
    // grid, and where a back face won, an emitter showed no emission.
    gl_FragDepth = gl_FrontFacing ? gl_FragCoord.z : gl_FragCoord.z * (1.0 - 1e-6);  // reversed: smaller is further
    // Emitters radiate from their front (counter-clockwise) face only.
    outSurface = vec4(surfaceKd(vKd), gl_FrontFacing && vLight >= 0 ? 2.0 + float(vLight) : 1.0);
#if TEXTURES
    outEmissionScale = vec4(emissionScale(), 1.0);
#endif
}
