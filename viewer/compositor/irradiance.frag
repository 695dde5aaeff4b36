// A cache mesh's irradiance where it is the nearest surface (see
// Compositor's drawIrradianceMesh): its front faces carry it, its back faces
// occlude and carry nothing, a hair behind their depth so that a reversed
// copy of the same triangle wins over them whichever is drawn first.
in vec3 vIrradiance;
layout(location = 0) out vec4 outIrradiance;
#if CUT_OUTS
// The scene's depth with its cut-outs' holes open (the surface pass), reversed.
layout(binding = 9) uniform sampler2D uVisibleDepth;
#endif

void main() {
#if CUT_OUTS
    // Nearer than the surface in view: a face its cut-out removes here (the
    // cache mesh covers it whole), whose irradiance is not what shows. The
    // margin, 1e-5 of the depth, is 100× the float rounding that separates
    // a cache triangle from the scene face it lies on.
    if (gl_FragCoord.z > texelFetch(uVisibleDepth, ivec2(gl_FragCoord.xy), 0).r * (1.0 + 1e-5)) discard;
#endif
    gl_FragDepth = gl_FrontFacing ? gl_FragCoord.z : gl_FragCoord.z * (1.0 - 1e-6);  // reversed: smaller is further
    outIrradiance = vec4(gl_FrontFacing ? vIrradiance : vec3(0.0), 1.0);
}
