// The scene's surfaces as occluders of the cache meshes that keep only some
// of them (the lights' own meshes where lights share, Compositor's
// drawPartialMeshes): depth only, a little further behind their true depth
// than irradiance.frag puts back faces, so that a mesh's triangles on the
// surface in view pass the depth test, and what a mesh keeps behind a
// surface it lacks stays hidden.
void main() {
    gl_FragDepth = gl_FragCoord.z * (1.0 - 4e-6);  // reversed: smaller is further
}
