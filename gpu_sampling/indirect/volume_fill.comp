// The 3D texture of the ray march, from the slice faces (VoxelSlices), in
// world order: block k = 2a + s (s = 0: the faces seen from above along axis
// a, radiance towards +a; s = 1: from below) holds at texel (c.x, c.y, c.z +
// k·dims.z) the face of slice c[a] at face texel (c[a+1], c[a+2]). Face
// texels start half a voxel in and number dims − 1 across (VoxelGrid::
// texels), so each block leaves its last row along the other two axes empty.
// RGB premultiplied by the coverage in alpha; zero where a face is empty.
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;
layout(binding = 0) uniform sampler2DArray faces;
// Per axis a and slice i: layerOf[layerOffset[a] + 2i] the layer of the
// slice's upper face, + 1 its lower face, −1 where empty.
layout(std430, binding = 3) readonly buffer Layers { int layerOf[]; };
layout(rgba32f, binding = 0) uniform writeonly image3D volume;
uniform ivec3 layerOffset;
uniform ivec3 dims;
uniform ivec3 texels;  // face texels along each axis

void main() {
    ivec3 g = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(g, ivec3(dims.x, dims.y, 6 * dims.z)))) return;
    int block = g.z / dims.z;
    ivec3 c = ivec3(g.x, g.y, g.z - block * dims.z);
    int a = block / 2, ua = (a + 1) % 3, va = (a + 2) % 3;
    vec4 v = vec4(0.0);
    if (c[ua] < texels[ua] && c[va] < texels[va]) {
        int layer = layerOf[layerOffset[a] + 2 * c[a] + block % 2];
        if (layer >= 0) v = texelFetch(faces, ivec3(c[ua], c[va], layer), 0);
    }
    imageStore(volume, g, v);
}
