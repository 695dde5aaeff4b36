// A cache mesh's irradiance where it is the nearest surface (see
// Compositor's drawIrradianceMesh): its front faces carry it, its back faces
// occlude and carry nothing, a hair behind their depth so that a reversed
// copy of the same triangle wins over them whichever is drawn first.
in vec3 vIrradiance;
layout(location = 0) out vec4 outIrradiance;

void main() {
    gl_FragDepth = gl_FrontFacing ? gl_FragCoord.z : gl_FragCoord.z * (1.0 - 1e-6);  // reversed: smaller is further
    outIrradiance = vec4(gl_FrontFacing ? vIrradiance : vec3(0.0), 1.0);
}
