// The settings of the hemispherical gathers (SliceGather, VoxelMarchGather,
// TriangleGather), apart from the passes themselves so that code choosing a
// gather never sees their GL objects.
#pragma once

namespace ml {

struct GatherSettings {
    int imageSize = 40;        // N: the fish-eye image is N×N (the paper's 40)
    int resolution = 64;       // voxels along the scene's longest side (32..128 typical)
    // The near box: the point's voxel and this many more each way. Its
    // triangles reach about a voxel beyond it, and each costs a ray test per
    // pixel: 0 (the paper's "a little") is the default, bench indirect
    // weighs 1 and 2.
    int nearVoxels = 0;
    int sliceSupersample = 2;  // sub-texels per texel side when filling the slices
    // How the faces are drawn: one full-screen quad per face in front of the
    // point, nearest hit by depth (the paper's §5.4), or one pass whose
    // fragment program visits the faces in the order the pixel's ray crosses
    // them and stops at the first hit (the same hits, found sooner).
    bool quadPerFace = false;
    void validate() const;
};

enum class TriangleProjection { Perspective, Hemicube, Fisheye };

// "perspective", "hemicube", "fisheye-triangles": the names of
// `--indirect-method`.
const char* triangleProjectionName(TriangleProjection projection);

struct TriangleGatherSettings {
    TriangleProjection projection = TriangleProjection::Hemicube;
    // Pixels per side: of the perspective image (the paper: 128 to 256 at
    // 160°), of a hemicube's top face (its sides are N × N/2, so N is even;
    // 32..128 typical), of the fish-eye image (40).
    int imageSize = 64;
    // The proxy's voxels along the scene's longest side (its triangles are
    // at most a voxel across; 16..64 typical).
    int resolution = 32;
    // Perspective only: the angle across a side of the square image, degrees
    // in (0, 176]; the paper's 160.
    double fieldOfViewDegrees = 160;
    // The seed turns (and, fish-eye, shifts) the image; false: one fixed
    // grid whatever the seed (regular sampling).
    bool jitter = true;
    // Cluster edge in voxels for the culling (ProxyClusters).
    int clusterVoxels = 4;
    // Fish-eye only: triangles near the eye are split (1 into 4, again and
    // again) until no edge spans more than this angle seen from the eye,
    // degrees; typical 10 (the arc then strays from the chord by under a
    // sixth of a pixel of a 40×40 image). 0: none, the straight edges of §5.2.
    double tessellationDegrees = 10;
    void validate() const;  // InputError naming the bad value
};

}  // namespace ml
