// Jitter positions shared bit for bit with gpu_sampling/direct/Jitter.h:
// integer hashing only, so the CPU that weights a sample finds the same point
// of the pixel that the GPU tested.

// "lowbias32" integer hash (C. Wellons): good avalanche, two multiplies.
uint mlHash(uint x) {
    x ^= x >> 16; x *= 0x7feb352du;
    x ^= x >> 15; x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

// Position of sample `bit` inside pixel `pixel` (row-major index), in [0,1)²
// from the pixel's lower-left corner. The pixel is cut into strataX × strataY
// cells and the bit jitters inside its own cell (cx, cy) (stratified
// sampling); with jitter off the cell's centre is used (regular sampling).
vec2 mlJitter(uint pixel, uint bit, uint seed, int cx, int cy, int strataX, int strataY, bool jitter) {
    vec2 r = vec2(0.5);
    if (jitter) {
        // One hash gives both coordinates, 16 bits each: 1/65536 of a stratum
        // is finer than any error we measure, and it halves the hashing.
        uint h = mlHash((pixel * 32u + bit) ^ seed);
        r = (vec2(float(h & 0xffffu), float(h >> 16)) + 0.5) * (1.0 / 65536.0);
    }
    return (vec2(float(cx), float(cy)) + r) / vec2(float(strataX), float(strataY));
}
