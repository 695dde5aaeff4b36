// OpenMesh types of the cache; included by cache/*.cpp only.
#pragma once

#include "core/Math.h"

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

namespace ml::detail {

struct CacheTraits : public OpenMesh::DefaultTraits {
    // Double precision: cache points sit on surfaces next to lights and at
    // scales from 1e-3 to 1e5.
    using Point = OpenMesh::Vec3d;
    using Normal = OpenMesh::Vec3d;
    VertexAttributes(OpenMesh::Attributes::Normal | OpenMesh::Attributes::Status);
    EdgeAttributes(OpenMesh::Attributes::Status);
    FaceAttributes(OpenMesh::Attributes::Status);
};

using CacheTriMesh = OpenMesh::TriMesh_ArrayKernelT<CacheTraits>;

inline Vec3 toVec3(const OpenMesh::Vec3d& p) { return {p[0], p[1], p[2]}; }
inline OpenMesh::Vec3d toOm(const Vec3& p) { return {p.x, p.y, p.z}; }

}  // namespace ml::detail
