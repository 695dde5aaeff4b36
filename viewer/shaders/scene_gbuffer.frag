flat in vec3 vKd;
flat in vec3 vKe;

layout(location = 0) out vec4 outReflectance;  // Kd
layout(location = 1) out vec4 outEmission;     // Le towards the camera

void main() {
    outReflectance = vec4(vKd, 1.0);
    // Emitters radiate from their front (counter-clockwise) face only.
    outEmission = vec4(gl_FrontFacing ? vKe : vec3(0.0), 1.0);
}
