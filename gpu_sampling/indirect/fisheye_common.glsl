// The fish-eye (hemispherical) image of §5.2: pixel (px, py) of an N×N image
// covers [-1, 1]² in equal squares; a point F of the unit disc is the
// direction F.x·r + F.y·u + sqrt(1 − |F|²)·v. The projection is orthographic
// onto the tangent plane, so equal areas of the disc are equal projected
// solid angles: the sum of radiance × (2/N)² over the pixels is the
// irradiance. Each pixel is sampled at a jittered point, the same one in
// every pass of a gather.
uniform int imageSize;     // N
uniform uint gatherSeed;
uniform vec3 eye;          // relative to the grid's origin
uniform mat3 basis;        // columns r, u, v (v: the surface normal)
uniform float maxDistance; // depth = distance / maxDistance
uniform vec3 nearLo;       // the near box, drawn as triangles (relative to the origin)
uniform vec3 nearHi;
uniform ivec3 nearCellLo;  // the same in voxels (inclusive)
uniform ivec3 nearCellHi;

uint fisheyePixel() { return uint(gl_FragCoord.y) * uint(imageSize) + uint(gl_FragCoord.x); }

// False outside the disc.
bool fisheyeDirection(out vec3 direction) {
    vec2 j = mlJitter(fisheyePixel(), 0u, gatherSeed, 0, 0, 1, 1, true);
    vec2 f = (floor(gl_FragCoord.xy) + j) / float(imageSize) * 2.0 - 1.0;
    float r2 = dot(f, f);
    if (r2 >= 1.0) return false;
    direction = basis * vec3(f, sqrt(1.0 - r2));
    return true;
}

bool inNearBox(vec3 p) { return all(greaterThanEqual(p, nearLo)) && all(lessThanEqual(p, nearHi)); }

// Whether a slice-face hit at p, on a face of slice `slice` along `axis`,
// shows what lies in the near box: the slice is one of the box's and p is
// inside the box across. (A face of the slice just outside lies on the
// box's boundary too, but shows what is outside.)
bool sliceHitInNearBox(vec3 p, int axis, int slice) {
    if (slice < nearCellLo[axis] || slice > nearCellHi[axis]) return false;
    int ua = (axis + 1) % 3, va = (axis + 2) % 3;
    return p[ua] > nearLo[ua] && p[ua] < nearHi[ua] && p[va] > nearLo[va] && p[va] < nearHi[va];
}
