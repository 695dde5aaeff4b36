// The scene's surfaces as occluders of a cache mesh that keeps only some of
// them (a light's own mesh where lights share, Compositor's
// drawIrradianceMesh): depth only, a little further behind their true depth
// than irradiance.frag puts back faces, so that the mesh's own triangles on
// the same surface win over them, and what the mesh keeps behind a surface
// it lacks stays hidden.
void main() {
    gl_FragDepth = gl_FragCoord.z * (1.0 - 4e-6);  // reversed: smaller is further
}
