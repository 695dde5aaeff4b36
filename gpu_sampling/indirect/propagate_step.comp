// One step of the propagation volume (PropagationVolume.h) on the GPU, in
// gather form: each invocation is a cell; it takes what its 6 neighbours
// send it (their SH times the transfer matrix of the direction, times the
// transmittance of the face between), and tallies what it sends through
// its own faces that the geometry volume or the grid's edge stops.
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;
// Per cell 27 floats: coefficient i, channel c at 3i + c.
layout(std430, binding = 0) readonly buffer Moving { float moving[]; };
layout(std430, binding = 1) writeonly buffer Next { float next[]; };
// Per direction d (+x, −x, +y, −y, +z, −z): 9×9, row i, column j at 81d + 9i + j.
layout(std430, binding = 2) readonly buffer Transfer { float transfer[]; };
// Per axis, per cell: the blocked share of the face to its +axis neighbour.
layout(std430, binding = 3) readonly buffer Blocking { float blocking[]; };
// Per direction, per cell, RGB: flux stopped at that face of the cell.
layout(std430, binding = 4) buffer Absorbed { float absorbed[]; };
uniform ivec3 dims;

const float kFluxOfBand0 = 3.5449077;  // 2√π: a field's flux is band 0 times this

int cellIndex(ivec3 c) { return (c.z * dims.y + c.y) * dims.x + c.x; }
bool inGrid(ivec3 c) { return all(greaterThanEqual(c, ivec3(0))) && all(lessThan(c, dims)); }

void main() {
    ivec3 c = ivec3(gl_GlobalInvocationID);
    if (!inGrid(c)) return;
    int count = dims.x * dims.y * dims.z;
    int self = cellIndex(c);
    float acc[27];
    for (int k = 0; k < 27; ++k) acc[k] = 0.0;
    for (int d = 0; d < 6; ++d) {
        int axis = d / 2;
        ivec3 step = ivec3(0);
        step[axis] = d % 2 == 0 ? 1 : -1;
        // Light travelling along d arrives from the cell behind.
        ivec3 from = c - step;
        if (inGrid(from)) {
            float t = 1.0 - blocking[axis * count + cellIndex(min(from, c))];
            if (t > 0.0) {
                int src = 27 * cellIndex(from);
                for (int i = 0; i < 9; ++i)
                    for (int j = 0; j < 9; ++j) {
                        float m = t * transfer[81 * d + 9 * i + j];
                        if (m == 0.0) continue;
                        acc[3 * i] += m * moving[src + 3 * j];
                        acc[3 * i + 1] += m * moving[src + 3 * j + 1];
                        acc[3 * i + 2] += m * moving[src + 3 * j + 2];
                    }
            }
        }
        // What this cell sends along d and does not get through.
        ivec3 to = c + step;
        float through = inGrid(to) ? 1.0 - blocking[axis * count + cellIndex(min(c, to))] : 0.0;
        if (through < 1.0)
            for (int ch = 0; ch < 3; ++ch) {
                float band0 = 0.0;
                for (int j = 0; j < 9; ++j) band0 += transfer[81 * d + j] * moving[27 * self + 3 * j + ch];
                absorbed[3 * (d * count + self) + ch] += (1.0 - through) * kFluxOfBand0 * band0;
            }
    }
    for (int k = 0; k < 27; ++k) next[27 * self + k] = acc[k];
}
