// Gives each corner of a triangle its barycentric coordinates: the fragment
// stage draws where one of them is within a pixel of 0.
layout(triangles) in;
layout(triangle_strip, max_vertices = 3) out;

noperspective out vec3 vBarycentric;

void main() {
    for (int i = 0; i < 3; ++i) {
        gl_Position = gl_in[i].gl_Position;
        vBarycentric = vec3(i == 0, i == 1, i == 2);
        EmitVertex();
    }
    EndPrimitive();
}
