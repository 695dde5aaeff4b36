// One triangle covering the screen; the instance picks a slice face.
flat out int vInstance;
void main() {
    vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2)) * 2.0 - 1.0;
    gl_Position = vec4(p, 0.0, 1.0);
    vInstance = gl_InstanceID;
}
