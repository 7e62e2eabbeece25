// The C interface raybench-peers' `tinybvh.rs` calls (feature `tinybvh`): tinybvh's
// BVH4_CPU and BVH8_CPU layouts built over a flat triangle array, traced one ray at a
// time. Rust never sees a tinybvh type: every structure tinybvh defines (rays, hit
// records, trees) stays on this side, so no layout has to match between the languages.
//
// build.rs compiles this file with the AVX2 and FMA kernels enabled (-mavx2 -mfma): the
// Rust side calls nothing here on a CPU without them.

#define TINYBVH_IMPLEMENTATION
#include "tiny_bvh.h"

#include <cstdint>
#include <cstring>
#include <mutex>
#include <new>
#include <vector>

#if TINY_BVH_VERSION_MAJOR != 1 || TINY_BVH_VERSION_MINOR != 6 || TINY_BVH_VERSION_SUB != 8
#error "raybench's tinybvh shim is written against tinybvh 1.6.8"
#endif
#if !defined BVH_USEAVX2
#error "tinybvh's BVH8_CPU needs AVX2 and FMA: compile with -mavx2 -mfma"
#endif

namespace {

// One built structure: the vertices tinybvh was built over (it keeps pointing at them)
// and the tree of the requested width.
struct Accel {
    uint32_t width = 0;
    std::vector<tinybvh::bvhvec4> vertices;
    tinybvh::BVH4_CPU bvh4;
    tinybvh::BVH8_CPU bvh8;
};

// tinybvh's threaded builders share one process-wide job system, created lazily without
// synchronisation: builds are serialised.
std::mutex build_lock;

// A tinybvh ray from raybench's origin and direction. tinybvh's own constructor
// normalises the direction; this one keeps it, so that `t` is measured in raybench's units
// (the Moeller-Trumbore test and the slab tests do not need a unit direction). The
// reciprocal is tinybvh's own (tinybvh_rcp clamps tiny components).
inline void make_ray(tinybvh::Ray& ray, const float* origin, const float* dir, float t_max) {
    std::memset(&ray, 0, sizeof(ray));
    ray.O = tinybvh::bvhvec3(origin[0], origin[1], origin[2]);
    ray.D = tinybvh::bvhvec3(dir[0], dir[1], dir[2]);
    ray.rD = tinybvh::tinybvh_rcp(ray.D);
    ray.mask = RAY_MASK_INTERSECT_ALL;
    ray.hit.t = t_max;
}

}  // namespace

extern "C" {

// Builds tinybvh's BVH4_CPU (`width` 4) or BVH8_CPU (`width` 8) over `count` triangles,
// `triangles` holding 9 floats per triangle (three vertices' x, y, z). Returns null when
// `width` is neither, `count` is 0 or memory runs out.
void* raybench_tinybvh_build(uint32_t width, const float* triangles, uint32_t count) {
    if ((width != 4 && width != 8) || count == 0 || triangles == nullptr) return nullptr;
    try {
        Accel* a = new Accel();
        a->width = width;
        a->vertices.resize(static_cast<size_t>(count) * 3);
        for (size_t i = 0; i < static_cast<size_t>(count) * 3; i++) {
            const float* v = triangles + 3 * i;
            a->vertices[i] = tinybvh::bvhvec4(v[0], v[1], v[2], 0.0f);
        }
        std::lock_guard<std::mutex> guard(build_lock);
        if (width == 4) {
            a->bvh4.Build(a->vertices.data(), count);
        } else {
            a->bvh8.Build(a->vertices.data(), count);
        }
        return a;
    } catch (...) {
        return nullptr;
    }
}

// Frees a structure `raybench_tinybvh_build` returned (null is ignored).
void raybench_tinybvh_free(void* accel) { delete static_cast<Accel*>(accel); }

// Bytes of the traversal layout (interior nodes and triangle leaves). tinybvh also keeps
// the binary and wide trees it converted from, and the vertices; those are not counted.
uint64_t raybench_tinybvh_bytes(const void* accel) {
    const Accel* a = static_cast<const Accel*>(accel);
    const uint32_t blocks = a->width == 4 ? a->bvh4.allocatedBlocks : a->bvh8.allocatedBlocks;
    return static_cast<uint64_t>(blocks) * 64;
}

// The closest hit of the ray `origin + t dir` with 0 < t < t_max: returns 1 and writes its
// `t`, barycentrics `u`, `v` (of vertices 1 and 2) and triangle index, or returns 0.
// `origin`, `dir` (3 floats each) and `t_max` must be free of NaN (tinybvh exits the
// process on a NaN ray).
int32_t raybench_tinybvh_intersect(const void* accel, const float* origin, const float* dir,
                                   float t_max, float* t, float* u, float* v, uint32_t* prim) {
    const Accel* a = static_cast<const Accel*>(accel);
    tinybvh::Ray ray;
    make_ray(ray, origin, dir, t_max);
    if (a->width == 4) {
        a->bvh4.Intersect(ray);
    } else {
        a->bvh8.Intersect(ray);
    }
    if (!(ray.hit.t < t_max)) return 0;
    *t = ray.hit.t;
    *u = ray.hit.u;
    *v = ray.hit.v;
    *prim = ray.hit.prim;
    return 1;
}

// Whether anything is hit with 0 < t < t_max; the same preconditions as
// `raybench_tinybvh_intersect`.
int32_t raybench_tinybvh_occluded(const void* accel, const float* origin, const float* dir,
                                  float t_max) {
    const Accel* a = static_cast<const Accel*>(accel);
    tinybvh::Ray ray;
    make_ray(ray, origin, dir, t_max);
    const bool hit = a->width == 4 ? a->bvh4.IsOccluded(ray) : a->bvh8.IsOccluded(ray);
    return hit ? 1 : 0;
}

}  // extern "C"
