// The cache file: everything refinement depends on, so a loaded cache goes
// on exactly as if it had never been saved.
//
// Layout (little-endian, as written by this machine):
//   magic "MESHLIGHT-CACHE\n" (16 bytes), u32 format version,
//   u64 scene fingerprint, u64 settings fingerprint, u64 payload bytes,
//   payload, u64 FNV-1a of the payload.
// Payload: u64 rounds, u64 samples, u64 detached faces, u32 refinement
// level (IrradianceCache::tighten), u32 meshes; per
// mesh: u32 vertices, u32 faces, per vertex 6 f64 (point, normal) and its
// sample sums (6 f64, 2 u32, f64 Σ 1/reach, f64 Σ work, f64 Σ work·own
// variance, u32 samples that measured their own), per face 3 u32 vertex
// indices, then u32 grid samples and their sample sums (the grids themselves are made from the
// scene again).
// Faces are stored in index order and rebuilt in that order, so vertex and
// face indices survive a round trip; only halfedge numbering may differ,
// and refinement never depends on it.
#include "IrradianceCache.h"

#include "core/Error.h"
#include "core/io/AtomicFile.h"
#include "detail/CacheImpl.h"

#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>

namespace ml {

namespace {

using detail::CacheTriMesh;
using detail::toOm;
using detail::toVec3;

constexpr char kMagic[16] = {'M', 'E', 'S', 'H', 'L', 'I', 'G', 'H', 'T', '-', 'C', 'A', 'C', 'H', 'E', '\n'};
constexpr uint32_t kFormatVersion = 5;  // 2: the refinement level; 3: the samples' reach; 4: their work;
                                        // 5: their own variance

uint64_t fnv1a(const std::string& bytes) {
    uint64_t h = 0xcbf29ce484222325ull;
    for (unsigned char c : bytes) h = (h ^ c) * 0x100000001b3ull;
    return h;
}

class Writer {
public:
    template <class T>
    void put(const T& v) {
        out_.append(reinterpret_cast<const char*>(&v), sizeof v);
    }
    void vec(const Vec3& v) { put(v.x), put(v.y), put(v.z); }
    std::string& bytes() { return out_; }

private:
    std::string out_;
};

// Reads from a byte range; running off its end is a truncated file.
class Reader {
public:
    Reader(const std::string& path, const char* data, size_t size) : path_(path), data_(data), size_(size) {}
    template <class T>
    T get(const char* what) {
        if (size_ - pos_ < sizeof(T))
            throw InputError(concat(path_, ": cache file is truncated (ends inside ", what, " at byte ", pos_, ")"));
        T v;
        std::memcpy(&v, data_ + pos_, sizeof v);
        pos_ += sizeof v;
        return v;
    }
    Vec3 vec(const char* what) {
        const double x = get<double>(what), y = get<double>(what), z = get<double>(what);
        return {x, y, z};
    }
    size_t remaining() const { return size_ - pos_; }
    size_t position() const { return pos_; }

private:
    std::string path_;
    const char* data_;
    size_t size_;
    size_t pos_ = 0;
};

void writeStats(Writer& w, const detail::VertexStats& st) {
    w.vec(st.sum);
    w.put(st.sumLum), w.put(st.sumLumSq), w.put(st.sumVisibility);
    w.put(st.count), w.put(st.partial);
    w.put(st.sumInverseReach);
    w.put(st.work);
    w.put(st.sumOwnVariance), w.put(st.ownCount);
}

detail::VertexStats readStats(Reader& r, const std::string& path, const char* what, size_t index, size_t mesh) {
    detail::VertexStats st;
    st.sum = r.vec(what);
    st.sumLum = r.get<double>(what);
    st.sumLumSq = r.get<double>(what);
    st.sumVisibility = r.get<double>(what);
    st.count = r.get<uint32_t>(what);
    st.partial = r.get<uint32_t>(what);
    st.sumInverseReach = r.get<double>(what);
    st.work = r.get<double>(what);
    st.sumOwnVariance = r.get<double>(what);
    st.ownCount = r.get<uint32_t>(what);
    if (!(st.count ? st.work > 0 && std::isfinite(st.work) : st.work == 0) ||
        !isFinite(st.sum) || !std::isfinite(st.sumLum) || !std::isfinite(st.sumLumSq) ||
        !(st.sumVisibility >= 0 && st.sumVisibility <= st.count) || st.partial > st.count ||
        !(st.sumInverseReach >= 0 && std::isfinite(st.sumInverseReach)) ||
        !(st.sumOwnVariance >= 0 && std::isfinite(st.sumOwnVariance)) || st.ownCount > st.count)
        throw InputError(concat(path, ": cache file is corrupt (", what, " ", index, " of mesh ", mesh, ")"));
    return st;
}

}  // namespace

void IrradianceCache::save(const std::string& path) const {
    const detail::CacheState& s = impl_->state;
    Writer payload;
    payload.put(uint64_t(s.rounds));
    payload.put(uint64_t(s.samples));
    payload.put(uint64_t(s.detachedFaces));
    payload.put(uint32_t(s.level));
    payload.put(uint32_t(s.meshes.size()));
    for (const detail::LightMesh& lm : s.meshes) {
        payload.put(uint32_t(lm.mesh.n_vertices()));
        payload.put(uint32_t(lm.mesh.n_faces()));
        for (auto v : lm.mesh.vertices()) {
            payload.vec(toVec3(lm.mesh.point(v)));
            payload.vec(toVec3(lm.mesh.normal(v)));
            writeStats(payload, lm.stats[size_t(v.idx())]);
        }
        for (auto f : lm.mesh.faces())
            for (auto v : lm.mesh.fv_range(f)) payload.put(uint32_t(v.idx()));
        payload.put(uint32_t(lm.gridStats.size()));
        for (const detail::VertexStats& st : lm.gridStats) writeStats(payload, st);
    }
    Writer file;
    file.bytes().append(kMagic, sizeof kMagic);
    file.put(kFormatVersion);
    file.put(s.sceneFingerprint);
    file.put(detail::settingsFingerprint(s.settings) ^ s.gatheredSalt);
    file.put(uint64_t(payload.bytes().size()));
    file.bytes() += payload.bytes();
    file.put(fnv1a(payload.bytes()));

    checkOutputDirectory(path);
    AtomicOutput out(path);
    {
        std::ofstream f(out.path(), std::ios::binary);
        f.write(file.bytes().data(), std::streamsize(file.bytes().size()));
        f.flush();
        if (!f) throw InputError(concat(path, ": cannot write the cache file"));
    }
    out.commit();
}

void IrradianceCache::load(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    if (!f) throw InputError(concat(path, ": cannot open the cache file"));
    const std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    if (f.bad()) throw InputError(concat(path, ": cannot read the cache file"));

    Reader in(path, bytes.data(), bytes.size());
    if (bytes.size() < sizeof kMagic || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
        throw InputError(concat(path, ": not a Meshlight cache file (wrong magic bytes)"));
    for (size_t i = 0; i < sizeof kMagic; ++i) in.get<char>("the magic");
    const uint32_t version = in.get<uint32_t>("the header");
    if (version != kFormatVersion)
        throw InputError(concat(path, ": cache file format ", version, ", this build reads format ", kFormatVersion));
    const detail::CacheState& s = impl_->state;
    if (in.get<uint64_t>("the header") != s.sceneFingerprint)
        throw InputError(concat(path, ": the cache was made for another scene (geometry, materials or lights "
                                      "differ); delete it or name another file"));
    if (in.get<uint64_t>("the header") != (detail::settingsFingerprint(s.settings) ^ s.gatheredSalt))
        throw InputError(concat(path, ": the cache was made with other cache settings; use the same settings, "
                                      "or delete it or name another file"));
    const uint64_t payloadBytes = in.get<uint64_t>("the header");
    if (payloadBytes > in.remaining() || in.remaining() - payloadBytes != sizeof(uint64_t))
        throw InputError(concat(path, ": cache file is truncated or has trailing bytes (", bytes.size(),
                                " bytes; the header announces ", payloadBytes, " bytes of data)"));
    const std::string payloadCopy = bytes.substr(in.position(), payloadBytes);
    uint64_t checksum;
    std::memcpy(&checksum, bytes.data() + in.position() + payloadBytes, sizeof checksum);
    if (checksum != fnv1a(payloadCopy))
        throw InputError(concat(path, ": cache file is corrupt (checksum mismatch)"));

    // Build into a fresh state; this cache changes only if all of it reads.
    Reader p(path, payloadCopy.data(), payloadCopy.size());
    detail::CacheState next;
    next.settings = s.settings;
    next.diagonal = s.diagonal;
    // Where border vertices are sampled comes from the scene and the
    // layout, not the file: kept, so that a loaded cache samples each
    // vertex where the one saved did.
    next.edgeOn = s.edgeOn;
    next.insetBorders = s.insetBorders;
    next.borderInset = s.borderInset;
    next.sceneFingerprint = s.sceneFingerprint;
    next.gatheredSalt = s.gatheredSalt;
    next.grids = s.grids;  // made from the scene, which matches
    next.gridSamples = s.gridSamples;
    next.rounds = p.get<uint64_t>("the counters");
    next.samples = p.get<uint64_t>("the counters");
    next.detachedFaces = p.get<uint64_t>("the counters");
    next.level = int(p.get<uint32_t>("the counters"));
    if (next.level < 0 || next.level > IrradianceCache::kMaxRefinementLevel)
        throw InputError(concat(path, ": cache file is corrupt (refinement level ", next.level, ")"));
    const uint32_t meshes = p.get<uint32_t>("the counters");
    if (meshes != s.meshes.size())
        throw InputError(concat(path, ": cache file has ", meshes, " light meshes, the scene has ", s.meshes.size(),
                                " lights"));
    next.meshes.resize(meshes);
    for (uint32_t l = 0; l < meshes; ++l) {
        detail::LightMesh& lm = next.meshes[l];
        const uint32_t nv = p.get<uint32_t>("a mesh header"), nf = p.get<uint32_t>("a mesh header");
        // Each vertex takes 120 bytes and each face 12: refuse counts the
        // file cannot hold before allocating for them.
        if (uint64_t(nv) * 120 + uint64_t(nf) * 12 > p.remaining())
            throw InputError(concat(path, ": cache file is corrupt (mesh ", l, " announces ", nv, " vertices and ",
                                    nf, " faces, more than the file holds)"));
        lm.stats.resize(nv);
        for (uint32_t v = 0; v < nv; ++v) {
            const Vec3 pos = p.vec("a vertex"), n = p.vec("a vertex");
            lm.stats[v] = readStats(p, path, "vertex", v, l);
            if (!isFinite(pos) || !isFinite(n))
                throw InputError(concat(path, ": cache file is corrupt (vertex ", v, " of mesh ", l, ")"));
            const auto vh = lm.mesh.add_vertex(toOm(pos));
            lm.mesh.set_normal(vh, toOm(n));
        }
        for (uint32_t fi = 0; fi < nf; ++fi) {
            CacheTriMesh::VertexHandle vs[3];
            for (auto& vh : vs) {
                const uint32_t idx = p.get<uint32_t>("a face");
                if (idx >= nv)
                    throw InputError(concat(path, ": cache file is corrupt (face ", fi, " of mesh ", l,
                                            " names vertex ", idx, " of ", nv, ")"));
                vh = CacheTriMesh::VertexHandle(int(idx));
            }
            if (!lm.mesh.add_face(vs[0], vs[1], vs[2]).is_valid())
                throw InputError(concat(path, ": cache file is corrupt (face ", fi, " of mesh ", l,
                                        " does not fit the mesh)"));
        }
        const uint32_t grid = p.get<uint32_t>("the grid samples");
        if (grid != s.gridSamples)
            throw InputError(concat(path, ": cache file has ", grid, " grid samples for light ", l, ", this scene's grid "
                                    "caches have ", s.gridSamples));
        lm.gridStats.resize(grid);
        for (uint32_t g = 0; g < grid; ++g) lm.gridStats[g] = readStats(p, path, "grid sample", g, l);
    }
    if (p.remaining() != 0) throw InputError(concat(path, ": cache file is corrupt (unread bytes at the end)"));
    // A full estimate's work: the most a vertex's samples took on average
    // (a vertex sampled only by full estimates has exactly that).
    for (const detail::LightMesh& lm : next.meshes)
        for (const auto* stats : {&lm.stats, &lm.gridStats})
            for (const detail::VertexStats& st : *stats)
                if (st.count) next.fullWork = std::max(next.fullWork, st.work / st.count);
    impl_->state = std::move(next);
}

}  // namespace ml
