// raybench's GPU kernels: ray casting, Whitted ray tracing, path tracing and explicit rays.
//
// Every routine here is a port of raybench-core's routine of the same name (the Rust
// names are given beside each function); the buffers are laid out by `crates/wgpu/src/records.rs`.
// The ports keep the operations and their order, so hits differ from the CPU's only where
// the GPU rounds differently: WGSL division and square root are not correctly rounded on
// Vulkan (2.5 ULP and 1 ULP of the reciprocal square root), drivers may fuse a * b + c,
// and the triangle test has no double-precision retry for edge functions that are exactly
// zero. The tolerances the tests allow are bounded by that (see `tests/equivalence.rs`).

// Whether to count ray/primitive tests and node visits (a pipeline-override constant, so
// the uncounted kernels carry no counting code).
override COUNT: bool = false;

// Whether the kernels walk the CWBVH (`wide_nodes`) instead of the BVH2 (`nodes`): a
// pipeline-override constant, so each pipeline carries one traversal.
override WIDE: bool = false;

// Whether the scene holds height fields, CSG trees, Bezier patches, SDF models, instances
// (HAS_HEIGHTFIELD, HAS_CSG, HAS_BEZIER, HAS_SDF, HAS_INSTANCES): pipeline-override
// constants (`records::Features`), so a pipeline carries only the routines its scene needs
// (shader compilers inline every routine at every call site). They are declared with the
// shared constants below.

// The constants shared with Rust (NO_HIT, KIND_*, HAS_*, MAT_*, LIGHT_POINT, EMITTER_BIT,
// NO_ENTRY, STACK_SIZE, WHITTED_STACK, AMBIENT, ROULETTE_DEPTH, DIMENSIONS_PER_BOUNCE,
// SHADOW_SHORTEN, MIN_POSITIVE, INV_PI, PI, TAU, BLOCK) are generated from the Rust definitions and prepended
// to this file by `crates/wgpu/src/constants.rs`.

// Per-dispatch parameters (`records::Params`).
struct Params {
    origin: vec3<f32>,
    inv_width: f32,
    forward: vec3<f32>,
    inv_height: f32,
    right: vec3<f32>,
    seed: u32,
    up: vec3<f32>,
    spp: u32,
    background: vec3<f32>,
    max_depth: u32,
    cast_light: vec3<f32>,
    inf: f32,
    width: u32,
    height: u32,
    band_y0: u32,
    y0: u32,
    rows: u32,
    s0: u32,
    s1: u32,
    node_count: u32,
    unbounded_first: u32,
    unbounded_count: u32,
    emitter_first: u32,
    emitter_count: u32,
    light_first: u32,
    light_count: u32,
    emitter_weight: f32,
    ray_count: u32,
    far_scale: f32,
    cull_slack: f32,
    mis: u32,
    instance_count: u32,
    top_root: u32,
    instance_records: u32,
    instance_order: u32,
    flat_count: u32,
    // Shading: lights, environment, textures, attributes (`shading::ShadingBlock`).
    light_total: f32,
    env_choice: f32,
    env_first: u32,
    env_width: u32,
    env_height: u32,
    env_cdf: u32,
    env_cos: f32,
    env_sin: f32,
    emitter_table: u32,
    attr_table: u32,
    attr_count: u32,
    tex_table: u32,
    // The volume modes (`kernels/volume.wgsl`): the volume table's index in `geo`, how many.
    volume_first: u32,
    volume_count: u32,
    _vpad0: u32,
    _vpad1: u32,
}

// 32-byte BVH2 node, raybench-bvh's `Node`: interior nodes have their first child next.
struct Node {
    min: vec3<f32>,
    first_or_right: u32,
    max: vec3<f32>,
    count: u32,
}

// 80-byte CWBVH node (`cwbvh::WideNode`, Ylitie et al. 2017): the origin's bits in
// p_e.xyz and the biased exponents (bytes 0-2) and interior mask (byte 3) in p_e.w; the
// first interior child, the first primitive and the eight metadata bytes in base_meta;
// the quantised planes lo.x, lo.y (q0), lo.z, hi.x (q1), hi.y, hi.z (q2), eight bytes each.
struct WideNode {
    p_e: vec4<u32>,
    base_meta: vec4<u32>,
    q0: vec4<u32>,
    q1: vec4<u32>,
    q2: vec4<u32>,
}

// 48-byte primitive (`records::GpuPrim`): a.w holds the kind, b.w the primitive id.
// Triangle: vertices a.xyz, b.xyz, c.xyz.
// Sphere: centre a.xyz, radius c.x. Plane: point a.xyz, unit normal c.xyz.
struct Prim {
    a: vec4<f32>,
    b: vec4<f32>,
    c: vec4<f32>,
}

// 32-byte output: colour and t (pixels) or t, u, v (explicit rays); primitive id.
struct Out {
    v: vec4<f32>,
    id: u32,
    // Explicit rays: the sub-primitive id.
    sub: u32,
    _pad1: u32,
    _pad2: u32,
}

// Explicit rays: origin and t_min, direction and t_max.
struct RayIn {
    o: vec4<f32>,
    d: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> nodes: array<Node>;
@group(0) @binding(2) var<storage, read> prims: array<Prim>;
@group(0) @binding(3) var<storage, read> prim_info: array<u32>;
@group(0) @binding(4) var<storage, read> shading: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> rays_in: array<RayIn>;
@group(0) @binding(6) var<storage, read_write> out: array<Out>;
@group(0) @binding(7) var<storage, read_write> counters: array<atomic<u32>, 6>;
@group(0) @binding(8) var<storage, read> wide_nodes: array<WideNode>;
// The primitives' own data beyond their 48-byte record (height-field samples, CSG trees,
// Bezier control points, SDF programs, voxels), laid out by `crates/wgpu/src/geo/`; a
// record points into it.
@group(0) @binding(9) var<storage, read> geo: array<vec4<f32>>;

var<private> n_rays: u32;
var<private> n_tests: u32;
var<private> n_visits: u32;

// ---------------------------------------------------------------------------------------
// Small helpers.

fn is_nan(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7fffffffu) > 0x7f800000u;
}

// Neither infinite nor NaN (by the bits: WGSL's comparisons with inf may be folded away).
fn is_finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7fffffffu) < 0x7f800000u;
}

fn copysign(x: f32, s: f32) -> f32 {
    return bitcast<f32>((bitcast<u32>(x) & 0x7fffffffu) | (bitcast<u32>(s) & 0x80000000u));
}

fn max3(v: vec3<f32>) -> f32 {
    return max(max(v.x, v.y), v.z);
}

// glam's `normalize_or_zero` / `normalize_or`.
fn normalize_or(v: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let inv_len = 1.0 / length(v);
    if inv_len > 0.0 && inv_len < params.inf {
        return v * inv_len;
    }
    return fallback;
}

// Adds to a 64-bit counter kept as two 32-bit words.
fn add64(slot: u32, x: u32) {
    if x == 0u {
        return;
    }
    let old = atomicAdd(&counters[slot], x);
    if old > 0xffffffffu - x {
        atomicAdd(&counters[slot + 1u], 1u);
    }
}

fn flush_counters() {
    add64(0u, n_rays);
    n_rays = 0u;
    if COUNT {
        add64(2u, n_tests);
        add64(4u, n_visits);
        n_tests = 0u;
        n_visits = 0u;
    }
}

// ---------------------------------------------------------------------------------------
// Counter-based random numbers (`sampling`, docs/sampling.md).

fn pcg3d(v_in: vec3<u32>) -> vec3<u32> {
    var v = v_in * 1664525u + 1013904223u;
    v.x += v.y * v.z;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v ^= v >> vec3<u32>(16u);
    v.x += v.y * v.z;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    return v;
}

struct Sampler {
    pixel: u32,
    sample: u32,
    dimension: u32,
}

fn next_f32(s: ptr<function, Sampler>) -> f32 {
    let h = pcg3d(vec3<u32>((*s).pixel, (*s).sample, (*s).dimension ^ (params.seed * 0x9E3779B9u)));
    (*s).dimension += 1u;
    return f32(h.x >> 8u) * (1.0 / 16777216.0);
}

// ---------------------------------------------------------------------------------------
// Rays (`Ray::with_interval`).

struct Ray {
    o: vec3<f32>,
    d: vec3<f32>,
    inv: vec3<f32>,
    t_min: f32,
    t_max: f32,
    kx: u32,
    ky: u32,
    kz: u32,
    shear: vec3<f32>,
}

fn make_ray(o: vec3<f32>, d: vec3<f32>, t_min: f32, t_max: f32) -> Ray {
    let a = abs(d);
    var kz = 2u;
    if a.x >= a.y && a.x >= a.z {
        kz = 0u;
    } else if a.y >= a.z {
        kz = 1u;
    }
    var kx = (kz + 1u) % 3u;
    var ky = (kx + 1u) % 3u;
    if d[kz] < 0.0 {
        let tmp = kx;
        kx = ky;
        ky = tmp;
    }
    // 1/0 is +-infinity in IEEE arithmetic; Vulkan leaves division by zero undefined, so
    // the infinities are made explicit.
    var inv = 1.0 / d;
    for (var i = 0u; i < 3u; i++) {
        if d[i] == 0.0 {
            inv[i] = copysign(params.inf, d[i]);
        }
    }
    let shear = vec3<f32>(d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]);
    return Ray(o, d, inv, t_min, t_max, kx, ky, kz, shear);
}

fn ray_new(o: vec3<f32>, d: vec3<f32>) -> Ray {
    return make_ray(o, d, 0.0, params.inf);
}

// ---------------------------------------------------------------------------------------
// Intersection routines.

// `SlabRay::entry`: the entry distance into [lo, hi] clamped to [t_min, t_max], or -1.
fn box_entry(r: Ray, lo: vec3<f32>, hi: vec3<f32>, t_max: f32) -> f32 {
    let pos = r.inv >= vec3<f32>(0.0);
    let near = (select(hi, lo, pos) - r.o) * r.inv;
    let far = (select(lo, hi, pos) - r.o) * r.inv * params.far_scale;
    // 0 * inf = NaN: the ray lies in that slab's plane and the axis must not constrain it.
    var t0 = r.t_min;
    var t1 = t_max;
    for (var i = 0u; i < 3u; i++) {
        if !is_nan(near[i]) {
            t0 = max(t0, near[i]);
        }
        if !is_nan(far[i]) {
            t1 = min(t1, far[i]);
        }
    }
    if t0 <= t1 {
        return t0;
    }
    return -1.0;
}

// `Triangle::intersect` (watertight, Woop et al. 2013) without the double-precision retry
// and without the check that the ray enters the triangle's box (a grazing ray can be
// accepted beside a long, thin triangle; the GPU is held to a tolerance, not bit for bit):
// (t, u, v, 1) on a hit, w = 0 on a miss.
fn triangle_hit(r: Ray, v0: vec3<f32>, v1: vec3<f32>, v2: vec3<f32>, t_max: f32) -> vec4<f32> {
    let a = v0 - r.o;
    let b = v1 - r.o;
    let c = v2 - r.o;
    let ax = a[r.kx] - r.shear.x * a[r.kz];
    let ay = a[r.ky] - r.shear.y * a[r.kz];
    let bx = b[r.kx] - r.shear.x * b[r.kz];
    let by = b[r.ky] - r.shear.y * b[r.kz];
    let cx = c[r.kx] - r.shear.x * c[r.kz];
    let cy = c[r.ky] - r.shear.y * c[r.kz];
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    let any_negative = u < 0.0 || v < 0.0 || w < 0.0;
    let any_positive = u > 0.0 || v > 0.0 || w > 0.0;
    if any_negative && any_positive {
        return vec4<f32>(0.0);
    }
    let det = u + v + w;
    if det == 0.0 {
        return vec4<f32>(0.0);
    }
    let az = r.shear.z * a[r.kz];
    let bz = r.shear.z * b[r.kz];
    let cz = r.shear.z * c[r.kz];
    let t = (u * az + v * bz + w * cz) / det;
    if !(t >= r.t_min && t <= t_max) || is_nan(t) {
        return vec4<f32>(0.0);
    }
    return vec4<f32>(t, v / det, w / det, 1.0);
}

// `Sphere::intersect` (Ray Tracing Gems ch. 7): t, or -1 on a miss.
fn sphere_hit(r: Ray, center: vec3<f32>, radius: f32, t_max: f32) -> f32 {
    let f = r.o - center;
    let d = r.d;
    let a = dot(d, d);
    let b = -dot(f, d);
    let l = f + d * (b / a);
    let r2 = radius * radius;
    let disc = r2 - dot(l, l);
    if disc < 0.0 || is_nan(disc) {
        return -1.0;
    }
    let c = dot(f, f) - r2;
    let q = b + copysign(sqrt(a) * sqrt(disc), b);
    let t0 = c / q;
    let t1 = q / a;
    let near = select(t1, t0, t0 <= t1);
    let far = select(t0, t1, t0 <= t1);
    if near >= r.t_min && near <= t_max {
        return near;
    }
    if far >= r.t_min && far <= t_max {
        return far;
    }
    return -1.0;
}

// `Plane::intersect`: t, or -1 on a miss.
fn plane_hit(r: Ray, point: vec3<f32>, normal: vec3<f32>, t_max: f32) -> f32 {
    let denom = dot(normal, r.d);
    if denom == 0.0 || !is_finite(denom) {
        return -1.0;
    }
    let t = dot(normal, point - r.o) / denom;
    if t >= r.t_min && t <= t_max && is_finite(t) {
        return t;
    }
    return -1.0;
}

// A primitive's hit (`PrimHit`): `t`, the surface parameters, the sub-primitive id; `ok`
// false on a miss.
struct Cand {
    t: f32,
    u: f32,
    v: f32,
    sub: u32,
    ok: bool,
}

fn miss() -> Cand {
    return Cand(0.0, 0.0, 0.0, 0u, false);
}

// A hit at `t` without surface parameters or sub-primitive, or a miss when `t` < 0.
fn hit_at(t: f32) -> Cand {
    if t >= 0.0 && !is_nan(t) {
        return Cand(t, 0.0, 0.0, 0u, true);
    }
    return miss();
}

// `Shape::intersect` on prims[k] with the ray clipped to t_max. The kinds beyond triangles,
// spheres and planes live in files of their own (`kernels/*.wgsl`), each with a
// `*_hit(r, p, t_max) -> Cand` and a `*_normal(r, p, h) -> vec3<f32>`.
fn prim_hit(r: Ray, k: u32, t_max: f32) -> Cand {
    let p = prims[k];
    let kind = bitcast<u32>(p.a.w);
    if COUNT {
        n_tests += 1u;
    }
    switch kind {
        case KIND_TRIANGLE: {
            let h = triangle_hit(r, p.a.xyz, p.b.xyz, p.c.xyz, t_max);
            return Cand(h.x, h.y, h.z, 0u, h.w != 0.0);
        }
        case KIND_SPHERE: {
            return hit_at(sphere_hit(r, p.a.xyz, p.c.x, t_max));
        }
        case KIND_PLANE: {
            return hit_at(plane_hit(r, p.a.xyz, p.c.xyz, t_max));
        }
        case KIND_HEIGHTFIELD: {
            if HAS_HEIGHTFIELD {
                return heightfield_hit(r, p, t_max);
            }
            return miss();
        }
        case KIND_CSG: {
            if HAS_CSG {
                return csg_hit(r, p, t_max);
            }
            return miss();
        }
        case KIND_BEZIER: {
            if HAS_BEZIER {
                return bezier_hit(r, p, t_max);
            }
            return miss();
        }
        case KIND_SDF: {
            if HAS_SDF {
                return sdf_hit(r, p, t_max);
            }
            return miss();
        }
        default: {
            return miss();
        }
    }
}

// ---------------------------------------------------------------------------------------
// Traversal (raybench-bvh's `intersect` and `occluded`).

struct Hit {
    t: f32,
    id: u32,
    u: f32,
    v: f32,
    // Index of the primitive in `prims`.
    k: u32,
    // Sub-primitive id (a height-field triangle, a CSG leaf).
    sub: u32,
    // The instance hit, NO_HIT for the flat part.
    inst: u32,
}

// `cull_bound`: the limit beyond which a box cannot hold a closer hit.
fn cull_bound(t: f32) -> f32 {
    return t + abs(t) * params.cull_slack;
}

// Tests prims[k] against the best hit so far (`Geometry::test_closest`, and
// `keep_closer` for an instance's primitives, whose ids start at `base`): closest t wins,
// ties go to the smaller primitive id.
fn test_closest(r: Ray, k: u32, base: u32, inst: u32, best: ptr<function, Hit>) {
    let h = prim_hit(r, k, (*best).t);
    if !h.ok {
        return;
    }
    let id = base + bitcast<u32>(prims[k].b.w);
    if h.t < (*best).t || (h.t == (*best).t && id < (*best).id) {
        *best = Hit(h.t, id, h.u, h.v, k, h.sub, inst);
    }
}

// `test_closest` on the unbounded primitive prims[k], which is a plane (the only unbounded
// kind): the plane test alone, so that the kernels do not inline every kind's routine here
// too (shader compilers inline every call).
fn test_plane(r: Ray, k: u32, best: ptr<function, Hit>) {
    if COUNT {
        n_tests += 1u;
    }
    let p = prims[k];
    let h = hit_at(plane_hit(r, p.a.xyz, p.c.xyz, (*best).t));
    let id = bitcast<u32>(p.b.w);
    if h.ok && (h.t < (*best).t || (h.t == (*best).t && id < (*best).id)) {
        *best = Hit(h.t, id, h.u, h.v, k, h.sub, NO_HIT);
    }
}

// The closest hit of `r`: id NO_HIT when it hits nothing. The flat part (its unbounded
// primitives, then its tree), then the instances (`TwoLevel::intersect`).
fn closest(r: Ray) -> Hit {
    var best = Hit(r.t_max, NO_HIT, 0.0, 0.0, 0u, 0u, NO_HIT);
    for (var k = params.unbounded_first; k < params.unbounded_first + params.unbounded_count; k++) {
        test_plane(r, k, &best);
    }
    if params.node_count != 0u {
        best = closest_tree(r, 0u, 0u, NO_HIT, best);
    }
    if HAS_INSTANCES && params.instance_count != 0u {
        best = closest_instances(r, best);
    }
    return best;
}

// The closest hit of `r` in the tree rooted at node `root` (the flat part's, or an
// instance's mesh's with ids from `base`), from the best hit so far (raybench-bvh's
// `intersect`): a per-thread stack, near child first.
fn closest_tree(r: Ray, root: u32, base: u32, inst: u32, best_in: Hit) -> Hit {
    if WIDE {
        return closest_wide(r, root, base, inst, best_in);
    }
    var best = best_in;
    var stack_node: array<u32, STACK_SIZE>;
    var stack_t: array<f32, STACK_SIZE>;
    var sp = 0u;
    var limit = cull_bound(best.t);
    let top = nodes[root];
    let t_root = box_entry(r, top.min, top.max, limit);
    if t_root >= 0.0 {
        stack_node[0] = root;
        stack_t[0] = t_root;
        sp = 1u;
    }
    while sp > 0u {
        sp -= 1u;
        // Strict early exit: skip only entries beyond the limit (an equal one may hold a tie).
        if stack_t[sp] > limit {
            continue;
        }
        let index = stack_node[sp];
        if COUNT {
            n_visits += 1u;
        }
        let node = nodes[index];
        if node.count > 0u {
            for (var k = node.first_or_right; k < node.first_or_right + node.count; k++) {
                test_closest(r, k, base, inst, &best);
            }
            limit = cull_bound(best.t);
            continue;
        }
        let left = index + 1u;
        let right = node.first_or_right;
        let nl = nodes[left];
        let nr = nodes[right];
        let tl = box_entry(r, nl.min, nl.max, limit);
        let tr = box_entry(r, nr.min, nr.max, limit);
        // Near child first: the far child is pushed first and popped later.
        if tl >= 0.0 && tr >= 0.0 {
            if tl <= tr {
                stack_node[sp] = right;
                stack_t[sp] = tr;
                stack_node[sp + 1u] = left;
                stack_t[sp + 1u] = tl;
            } else {
                stack_node[sp] = left;
                stack_t[sp] = tl;
                stack_node[sp + 1u] = right;
                stack_t[sp + 1u] = tr;
            }
            sp += 2u;
        } else if tl >= 0.0 {
            stack_node[sp] = left;
            stack_t[sp] = tl;
            sp += 1u;
        } else if tr >= 0.0 {
            stack_node[sp] = right;
            stack_t[sp] = tr;
            sp += 1u;
        }
    }
    return best;
}

// Whether anything blocks `r` within [t_min, t_max]: the flat part, then the instances
// (`TwoLevel::occluded`).
fn occluded(r: Ray) -> bool {
    for (var k = params.unbounded_first; k < params.unbounded_first + params.unbounded_count; k++) {
        if COUNT {
            n_tests += 1u;
        }
        let p = prims[k];
        if plane_hit(r, p.a.xyz, p.c.xyz, r.t_max) >= 0.0 {
            return true;
        }
    }
    if params.node_count != 0u && occluded_tree(r, 0u) {
        return true;
    }
    return HAS_INSTANCES && params.instance_count != 0u && occluded_instances(r);
}

// Whether anything in the tree rooted at node `root` blocks `r` (raybench-bvh's
// `occluded`): the first hit ends the walk.
fn occluded_tree(r: Ray, root: u32) -> bool {
    if WIDE {
        return occluded_wide(r, root);
    }
    var stack: array<u32, STACK_SIZE>;
    var sp = 0u;
    let top = nodes[root];
    if box_entry(r, top.min, top.max, r.t_max) >= 0.0 {
        stack[0] = root;
        sp = 1u;
    }
    while sp > 0u {
        sp -= 1u;
        let index = stack[sp];
        if COUNT {
            n_visits += 1u;
        }
        let node = nodes[index];
        if node.count > 0u {
            for (var k = node.first_or_right; k < node.first_or_right + node.count; k++) {
                if prim_hit(r, k, r.t_max).ok {
                    return true;
                }
            }
            continue;
        }
        let right = node.first_or_right;
        let nr = nodes[right];
        if box_entry(r, nr.min, nr.max, r.t_max) >= 0.0 {
            stack[sp] = right;
            sp += 1u;
        }
        let nl = nodes[index + 1u];
        if box_entry(r, nl.min, nl.max, r.t_max) >= 0.0 {
            stack[sp] = index + 1u;
            sp += 1u;
        }
    }
    return false;
}

// ---------------------------------------------------------------------------------------
// Instances (`TwoLevel`; the buffers are laid out by `crates/wgpu/src/instances.rs`): the
// CPU's top-level tree in `nodes` from `params.top_root`, its leaves indexing the order
// list in `geo`; one record of INSTANCE_RECORD entries per instance in `geo`, in id order.

// `geo` index of instance k's record.
fn instance_record(k: u32) -> u32 {
    return params.instance_records + k * INSTANCE_RECORD;
}

// `Instance::local_ray`: `r` carried into instance k's mesh space by the inverse
// transform (the direction not renormalised, so `t` is the same), over [t_min, t_max].
fn instance_ray(r: Ray, k: u32, t_max: f32) -> Ray {
    let rec = instance_record(k);
    let m = mat3x3<f32>(geo[rec].xyz, geo[rec + 1u].xyz, geo[rec + 2u].xyz);
    return make_ray(m * r.o + geo[rec + 3u].xyz, m * r.d, r.t_min, t_max);
}

// Entry `j` of the top level's order list: an instance index.
fn instance_at(j: u32) -> u32 {
    return bitcast<u32>(geo[params.instance_order + j / 4u][j % 4u]);
}

// The top level's walk (`TopLevel::walk`) shared by both queries: returns the best hit
// (`any` false) or, with `any`, a hit whose id is not NO_HIT as soon as one blocks `r`.
fn walk_instances(r: Ray, best_in: Hit, any: bool) -> Hit {
    var best = best_in;
    var stack_node: array<u32, STACK_SIZE>;
    var stack_t: array<f32, STACK_SIZE>;
    var sp = 0u;
    let root = nodes[params.top_root];
    let t_root = box_entry(r, root.min, root.max, select(cull_bound(best.t), r.t_max, any));
    if t_root >= 0.0 {
        stack_node[0] = params.top_root;
        stack_t[0] = t_root;
        sp = 1u;
    }
    while sp > 0u {
        sp -= 1u;
        let limit = select(cull_bound(best.t), r.t_max, any);
        if stack_t[sp] > limit {
            continue;
        }
        if COUNT {
            n_visits += 1u;
        }
        let node = nodes[stack_node[sp]];
        if node.count > 0u {
            for (var j = node.first_or_right; j < node.first_or_right + node.count; j++) {
                let k = instance_at(j);
                let rec = instance_record(k);
                let root_k = bitcast<u32>(geo[rec].w);
                if any {
                    if box_entry(r, geo[rec + 7u].xyz, geo[rec + 8u].xyz, r.t_max) >= 0.0
                        && occluded_tree(instance_ray(r, k, r.t_max), root_k) {
                        best.id = 0u;
                        return best;
                    }
                } else if box_entry(r, geo[rec + 7u].xyz, geo[rec + 8u].xyz, cull_bound(best.t)) >= 0.0 {
                    let base = bitcast<u32>(geo[rec + 1u].w);
                    best = closest_tree(instance_ray(r, k, best.t), root_k, base, k, best);
                }
            }
            continue;
        }
        let bound = select(cull_bound(best.t), r.t_max, any);
        let a = node.first_or_right;
        let b = a + 1u;
        let na = nodes[a];
        let nb = nodes[b];
        let ta = box_entry(r, na.min, na.max, bound);
        let tb = box_entry(r, nb.min, nb.max, bound);
        // Near child first: the nearer is pushed last (the second child first on a tie,
        // as `TopLevel::walk` orders them).
        if ta >= 0.0 && tb >= 0.0 && tb > ta {
            stack_node[sp] = b;
            stack_t[sp] = tb;
            stack_node[sp + 1u] = a;
            stack_t[sp + 1u] = ta;
            sp += 2u;
        } else {
            if ta >= 0.0 {
                stack_node[sp] = a;
                stack_t[sp] = ta;
                sp += 1u;
            }
            if tb >= 0.0 {
                stack_node[sp] = b;
                stack_t[sp] = tb;
                sp += 1u;
            }
        }
    }
    return best;
}

// The instances' part of `TwoLevel::intersect`, from the flat part's best hit.
fn closest_instances(r: Ray, best: Hit) -> Hit {
    return walk_instances(r, best, false);
}

// The instances' part of `TwoLevel::occluded`.
fn occluded_instances(r: Ray) -> bool {
    return walk_instances(r, Hit(r.t_max, NO_HIT, 0.0, 0.0, 0u, 0u, NO_HIT), true).id != NO_HIT;
}

// The instance whose ids hold instanced primitive `id` (`Geometry::locate`: the last whose
// base is at most `id`).
fn instance_of(id: u32) -> u32 {
    var lo = 0u;
    var hi = params.instance_count;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if bitcast<u32>(geo[instance_record(mid) + 1u].w) <= id {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return lo - 1u;
}

// Whether `id` is an instanced primitive's.
fn is_instanced(id: u32) -> bool {
    return HAS_INSTANCES && params.instance_count != 0u && id >= params.flat_count;
}

// The `prim_info` entry of primitive `id` (`Scene::material_of`): a flat id's directly; an
// instanced one's from its instance (`instance_of`): the instance's material, or its mesh's
// material of the primitive.
fn info_of(id: u32) -> u32 {
    if !is_instanced(id) {
        return prim_info[id];
    }
    let rec = instance_record(instance_of(id));
    let own = bitcast<u32>(geo[rec + 2u].w);
    if own != NO_HIT {
        return own;
    }
    return prim_info[bitcast<u32>(geo[rec + 3u].w) + id - bitcast<u32>(geo[rec + 1u].w)];
}

// ---------------------------------------------------------------------------------------
// CWBVH traversal (the `wgpu-cwbvh` kernels; the tree is `cwbvh::Cwbvh`, raybench-bvh's
// BVH2 collapsed): the same contract as `closest` and `occluded` above, over 8-wide nodes.
//
// A node's eight child boxes are decoded (`p + q * 2^e`, exact products, so the CPU's
// check that they hold their children holds here) and tested with `box_entry`. Leaf
// children are tested at once, near to far; the hit interior children are pushed as one
// stack entry: the child base, the interior mask (bits 8-15) and the hit mask in visiting
// order (bits 0-7; step j visits slot j ^ octant, about near to far because children sit
// in slots by direction). The stack grows by at most one entry per level. Entries carry no
// distance, so a group is not culled again when the best hit improves; its children's
// boxes are, against the limit of their turn (less culling, never a lost hit).

// Byte `slot` of the eight bytes in `lo` (slots 0-3) and `hi` (slots 4-7).
fn slot_byte(lo: u32, hi: u32, slot: u32) -> u32 {
    return (select(lo, hi, slot >= 4u) >> ((slot & 3u) * 8u)) & 0xffu;
}

// `2^(e - 127)` from a biased exponent byte (made from the bits: exact).
fn exp2_bits(e: u32) -> f32 {
    return bitcast<f32>(e << 23u);
}

// The slots of node `n` whose decoded boxes `r` enters within `limit`, as a bit mask.
fn wide_hits(r: Ray, n: WideNode, limit: f32) -> u32 {
    let p = bitcast<vec3<f32>>(n.p_e.xyz);
    let s = vec3<f32>(exp2_bits(n.p_e.w & 0xffu), exp2_bits((n.p_e.w >> 8u) & 0xffu), exp2_bits((n.p_e.w >> 16u) & 0xffu));
    let imask = n.p_e.w >> 24u;
    var hits = 0u;
    for (var slot = 0u; slot < 8u; slot++) {
        if ((imask >> slot) & 1u) == 0u && slot_byte(n.base_meta.z, n.base_meta.w, slot) == 0u {
            continue;
        }
        let qlo = vec3<f32>(
            f32(slot_byte(n.q0.x, n.q0.y, slot)),
            f32(slot_byte(n.q0.z, n.q0.w, slot)),
            f32(slot_byte(n.q1.x, n.q1.y, slot)));
        let qhi = vec3<f32>(
            f32(slot_byte(n.q1.z, n.q1.w, slot)),
            f32(slot_byte(n.q2.x, n.q2.y, slot)),
            f32(slot_byte(n.q2.z, n.q2.w, slot)));
        if box_entry(r, p + qlo * s, p + qhi * s, limit) >= 0.0 {
            hits |= 1u << slot;
        }
    }
    return hits;
}

// The visiting order of `r`'s children: step j visits slot j ^ wide_order(r).
fn wide_order(r: Ray) -> u32 {
    return (select(0u, 1u, r.d.x < 0.0) | select(0u, 2u, r.d.y < 0.0) | select(0u, 4u, r.d.z < 0.0)) ^ 7u;
}

// The walk's stack: per level a child base and a mask (see above).
struct WideStack {
    base: array<u32, STACK_SIZE>,
    mask: array<u32, STACK_SIZE>,
    sp: u32,
}

// Pushes the hit interior children of `n` as one entry, then takes the next node to visit
// from the top entry into `index`; false when none is left.
fn wide_advance(stack: ptr<function, WideStack>, n: WideNode, hits: u32, order: u32, index: ptr<function, u32>) -> bool {
    let imask = n.p_e.w >> 24u;
    let inner = hits & imask;
    var visit = 0u;
    for (var j = 0u; j < 8u; j++) {
        visit |= ((inner >> (j ^ order)) & 1u) << j;
    }
    if visit != 0u {
        (*stack).base[(*stack).sp] = n.base_meta.x;
        (*stack).mask[(*stack).sp] = visit | (imask << 8u);
        (*stack).sp += 1u;
    }
    if (*stack).sp == 0u {
        return false;
    }
    let top = (*stack).sp - 1u;
    let mask = (*stack).mask[top];
    let slot = firstTrailingBit(mask & 0xffu) ^ order;
    *index = (*stack).base[top] + countOneBits((mask >> 8u) & ((1u << slot) - 1u));
    let rest = mask & (mask - 1u);
    if (rest & 0xffu) == 0u {
        (*stack).sp = top;
    } else {
        (*stack).mask[top] = rest;
    }
    return true;
}

// `closest_tree` over the CWBVH rooted at wide node `root`.
fn closest_wide(r: Ray, root: u32, base: u32, inst: u32, best_in: Hit) -> Hit {
    var best = best_in;
    var limit = cull_bound(best.t);
    let order = wide_order(r);
    var stack: WideStack;
    stack.sp = 0u;
    var index = root;
    loop {
        if COUNT {
            n_visits += 1u;
        }
        let n = wide_nodes[index];
        let hits = wide_hits(r, n, limit);
        let leaves = hits & ~(n.p_e.w >> 24u);
        if leaves != 0u {
            for (var j = 0u; j < 8u; j++) {
                let slot = j ^ order;
                if ((leaves >> slot) & 1u) == 0u {
                    continue;
                }
                let info = slot_byte(n.base_meta.z, n.base_meta.w, slot);
                let first = n.base_meta.y + (info & 31u);
                for (var k = first; k < first + (info >> 5u); k++) {
                    test_closest(r, k, base, inst, &best);
                }
            }
            limit = cull_bound(best.t);
        }
        if !wide_advance(&stack, n, hits, order, &index) {
            break;
        }
    }
    return best;
}

// `occluded_tree` over the CWBVH rooted at wide node `root`: the first hit ends.
fn occluded_wide(r: Ray, root: u32) -> bool {
    let order = wide_order(r);
    var stack: WideStack;
    stack.sp = 0u;
    var index = root;
    loop {
        if COUNT {
            n_visits += 1u;
        }
        let n = wide_nodes[index];
        let hits = wide_hits(r, n, r.t_max);
        let leaves = hits & ~(n.p_e.w >> 24u);
        for (var slot = 0u; slot < 8u; slot++) {
            if ((leaves >> slot) & 1u) == 0u {
                continue;
            }
            let info = slot_byte(n.base_meta.z, n.base_meta.w, slot);
            let first = n.base_meta.y + (info & 31u);
            for (var k = first; k < first + (info >> 5u); k++) {
                if prim_hit(r, k, r.t_max).ok {
                    return true;
                }
            }
        }
        if !wide_advance(&stack, n, hits, order, &index) {
            break;
        }
    }
    return false;
}

// The unit geometric normal at a hit (`Shape::complete_hit`); an instance's mesh normal is
// found on the instance-space ray and carried to the world by the normal matrix
// (`Geometry::complete_global`, `Instance::world_normal`).
fn hit_normal(r: Ray, h: Hit) -> vec3<f32> {
    if !HAS_INSTANCES || h.inst == NO_HIT {
        return prim_normal(r, h);
    }
    let rec = instance_record(h.inst);
    let n = prim_normal(instance_ray(r, h.inst, r.t_max), h);
    let m = mat3x3<f32>(geo[rec + 4u].xyz, geo[rec + 5u].xyz, geo[rec + 6u].xyz);
    return normalize_or(m * n, n);
}

// The unit geometric normal of prims[h.k] at a hit of `r` (`Shape::complete_hit`).
fn prim_normal(r: Ray, h: Hit) -> vec3<f32> {
    let p = prims[h.k];
    switch bitcast<u32>(p.a.w) {
        case KIND_TRIANGLE: {
            return normalize_or(cross(p.b.xyz - p.a.xyz, p.c.xyz - p.a.xyz), vec3<f32>(0.0, 1.0, 0.0));
        }
        case KIND_SPHERE: {
            let at = r.o + r.d * h.t;
            return normalize_or((at - p.a.xyz) / p.c.x, vec3<f32>(0.0, 1.0, 0.0));
        }
        case KIND_HEIGHTFIELD: {
            if HAS_HEIGHTFIELD {
                return heightfield_normal(r, p, h);
            }
            return p.c.xyz;
        }
        case KIND_CSG: {
            if HAS_CSG {
                return csg_normal(r, p, h);
            }
            return p.c.xyz;
        }
        case KIND_BEZIER: {
            if HAS_BEZIER {
                return bezier_normal(r, p, h);
            }
            return p.c.xyz;
        }
        case KIND_SDF: {
            if HAS_SDF {
                return sdf_normal(r, p, h);
            }
            return p.c.xyz;
        }
        default: {
            return p.c.xyz;
        }
    }
}

// ---------------------------------------------------------------------------------------
// Materials, lights and optics (`material`, `optics`).

struct Material {
    base_color: vec3<f32>,
    kind: u32,
    specular: vec3<f32>,
    shininess: f32,
    emission: vec3<f32>,
    ior: f32,
    checker_color: vec3<f32>,
    checker_size: f32,
    // `Material::base_color_texture` and `emission_texture` (NO_ENTRY: none).
    base_texture: u32,
    emission_texture: u32,
}

// `Scene::material_of` (five vectors per material, `data.rs`).
fn material_of(id: u32) -> Material {
    let m = (info_of(id) & ~EMITTER_BIT) * 5u;
    let m0 = shading[m];
    let m1 = shading[m + 1u];
    let m2 = shading[m + 2u];
    let m3 = shading[m + 3u];
    let m4 = shading[m + 4u];
    return Material(m0.xyz, bitcast<u32>(m0.w), m1.xyz, m1.w, m2.xyz, m2.w, m3.xyz, m3.w,
        bitcast<u32>(m4.x), bitcast<u32>(m4.y));
}

fn is_emitter(id: u32) -> bool {
    return (info_of(id) & EMITTER_BIT) != 0u;
}

// `Material::albedo_at`.
fn albedo_at(m: Material, p: vec3<f32>) -> vec3<f32> {
    if m.checker_size <= 0.0 {
        return m.base_color;
    }
    let s = floor(p.x / m.checker_size) + floor(p.z / m.checker_size);
    let parity = s - 2.0 * floor(s / 2.0);
    if parity < 0.5 {
        return m.base_color;
    }
    return m.checker_color;
}

fn reflect_dir(d: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return d - 2.0 * dot(d, n) * n;
}

// `optics::refract`: the refracted direction, or zero on total internal reflection.
fn refract_dir(d: vec3<f32>, n: vec3<f32>, n1: f32, n2: f32) -> vec4<f32> {
    let eta = n1 / n2;
    let cos_i = -dot(d, n);
    let sin2_t = eta * eta * max(1.0 - cos_i * cos_i, 0.0);
    if sin2_t > 1.0 {
        return vec4<f32>(0.0);
    }
    let cos_t = sqrt(1.0 - sin2_t);
    return vec4<f32>(eta * d + (eta * cos_i - cos_t) * n, 1.0);
}

fn fresnel_dielectric(cos_in: f32, n1: f32, n2: f32) -> f32 {
    let cos_i = clamp(cos_in, 0.0, 1.0);
    let sin_t = n1 / n2 * sqrt(max(1.0 - cos_i * cos_i, 0.0));
    if sin_t >= 1.0 {
        return 1.0;
    }
    let cos_t = sqrt(max(1.0 - sin_t * sin_t, 0.0));
    let r_s = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    let r_p = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t);
    return 0.5 * (r_s * r_s + r_p * r_p);
}

// `optics::offset_ray_origin` (Waechter and Binder, Ray Tracing Gems ch. 6).
fn offset_ray_origin(p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    var q = p;
    for (var i = 0u; i < 3u; i++) {
        if abs(p[i]) < 1.0 / 32.0 {
            q[i] = p[i] + (1.0 / 65536.0) * n[i];
        } else {
            var step = i32(256.0 * n[i]);
            if p[i] < 0.0 {
                step = -step;
            }
            q[i] = bitcast<f32>(bitcast<i32>(p[i]) + step);
        }
    }
    return q;
}

// `sampling::basis` (Duff et al. 2017): two unit vectors completing unit `n` to an
// orthonormal basis.
fn frame_basis(n: vec3<f32>) -> array<vec3<f32>, 2> {
    let sgn = copysign(1.0, n.z);
    let a = -1.0 / (sgn + n.z);
    let b = n.x * n.y * a;
    return array<vec3<f32>, 2>(
        vec3<f32>(1.0 + sgn * n.x * n.x * a, sgn * b, -sgn * n.x),
        vec3<f32>(b, sgn + n.y * n.y * a, -n.y));
}

// `optics::cosine_hemisphere`.
fn cosine_hemisphere(n: vec3<f32>, u1: f32, u2: f32) -> vec3<f32> {
    let tb = frame_basis(n);
    let t = tb[0];
    let bt = tb[1];
    let r = sqrt(u1);
    let phi = TAU * u2;
    let z = sqrt(max(1.0 - u1, 0.0));
    return normalize(t * (r * cos(phi)) + bt * (r * sin(phi)) + n * z);
}

// `sampling::triangle_point`.
fn triangle_point(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>, u1: f32, u2: f32) -> vec3<f32> {
    let s = sqrt(u1);
    let w0 = 1.0 - s;
    let w1 = u2 * s;
    return a * w0 + b * w1 + c * (1.0 - w0 - w1);
}

// `whitted::light_ray`: a shadow ray towards light j and the unshadowed irradiance (on the
// shading normal `ns`) and direction it would bring; `ok` is false when the light is behind
// the surface: below the shading normal's hemisphere or below the geometric surface (`n`,
// which also offsets the ray's origin), both facing the viewer.
struct LightSample {
    ray: Ray,
    irradiance: vec3<f32>,
    wi: vec3<f32>,
    ok: bool,
}

fn light_ray(j: u32, p: vec3<f32>, n: vec3<f32>, ns: vec3<f32>) -> LightSample {
    let l0 = shading[params.light_first + 2u * j];
    let l1 = shading[params.light_first + 2u * j + 1u];
    return light_sample(l0, l1, p, n, ns);
}

// Whitted's lights: the scene's point and directional lights, or where it has none the
// headlight (`integrator::whitted::headlight`): radiance 1 along the view direction.
fn whitted_light_count() -> u32 {
    return select(params.light_count, 1u, params.light_count == 0u);
}

fn whitted_light(j: u32, p: vec3<f32>, n: vec3<f32>, ns: vec3<f32>) -> LightSample {
    if params.light_count == 0u {
        let kind = bitcast<f32>(LIGHT_DIRECTIONAL);
        return light_sample(vec4<f32>(params.forward, kind), vec4<f32>(1.0), p, n, ns);
    }
    return light_ray(j, p, n, ns);
}

// Light `l0`, `l1` (as stored: position or direction with the kind, then the power).
fn light_sample(l0: vec4<f32>, l1: vec4<f32>, p: vec3<f32>, n: vec3<f32>, ns: vec3<f32>) -> LightSample {
    let origin = offset_ray_origin(p, n);
    var s: LightSample;
    s.ok = false;
    if bitcast<u32>(l0.w) == LIGHT_POINT {
        let position = l0.xyz;
        let to = position - p;
        let dist2 = dot(to, to);
        let dir = to / sqrt(dist2);
        let cos_l = dot(ns, dir);
        if !(cos_l > 0.0 && dist2 > 0.0 && dot(n, dir) > 0.0) {
            return s;
        }
        s.ray = make_ray(origin, position - origin, 0.0, 1.0);
        s.irradiance = l1.xyz * (cos_l / dist2);
        s.wi = dir;
    } else {
        let dir = -l0.xyz;
        let cos_l = dot(ns, dir);
        if !(cos_l > 0.0 && dot(n, dir) > 0.0) {
            return s;
        }
        s.ray = ray_new(origin, dir);
        s.irradiance = l1.xyz * cos_l;
        s.wi = dir;
    }
    s.ok = true;
    return s;
}

// ---------------------------------------------------------------------------------------
// Pixels.

struct Pixel {
    x: u32,
    y: u32,
    ok: bool,
}

// Thread i of this dispatch: 8 x 8 pixel blocks, row by row, over rows [y0, y0 + rows).
fn pixel_of(i: u32) -> Pixel {
    let blocks_per_row = (params.width + BLOCK - 1u) / BLOCK;
    let block = i / (BLOCK * BLOCK);
    let within = i % (BLOCK * BLOCK);
    let x = (block % blocks_per_row) * BLOCK + within % BLOCK;
    let y = params.y0 + (block / blocks_per_row) * BLOCK + within / BLOCK;
    return Pixel(x, y, x < params.width && y < params.y0 + params.rows);
}

// `CameraRays::ray`.
fn camera_ray(px: f32, py: f32) -> Ray {
    let sx = 2.0 * px * params.inv_width - 1.0;
    let sy = 1.0 - 2.0 * py * params.inv_height;
    let dir = normalize(params.forward + params.right * sx + params.up * sy);
    return ray_new(params.origin, dir);
}

fn out_index(p: Pixel) -> u32 {
    return (p.y - params.band_y0) * params.width + p.x;
}

// The pixel's centre ray, traced once per frame (the id and t buffers), in the dispatch of
// sample 0.
fn centre_ray(p: Pixel) -> Ray {
    return camera_ray(f32(p.x) + 0.5, f32(p.y) + 0.5);
}

// Records the centre ray's hit `h` in the id and t buffers.
fn record_centre(p: Pixel, h: Hit) {
    let o = out_index(p);
    out[o].id = h.id;
    out[o].v.w = select(h.t, params.inf, h.id == NO_HIT);
}

// How many rays a pixel traces before its samples in this dispatch: 1 for the centre ray
// when it is not sample 0's own camera ray (`in_sample` false), else 0. The kernels trace
// it in the same loop as their samples: shader compilers inline `closest` and `occluded` at
// every call site (Mesa's always), so each kernel calls each once, which keeps its compile
// time (seconds per pipeline on lavapipe) to one copy of each traversal.
fn centre_rays(in_sample: bool) -> u32 {
    return select(0u, 1u, params.s0 == 0u && !in_sample);
}

// The sample that pass `j` of a pixel's loop traces, after `first` passes for the centre
// ray (never read for those).
fn sample_of(j: u32, first: u32) -> u32 {
    return params.s0 + max(j, first) - first;
}

// Adds this dispatch's colour to the pixel's sum and flushes the counters.
fn finish_pixel(p: Pixel, color: vec3<f32>) {
    let o = out_index(p);
    out[o].v = vec4<f32>(out[o].v.xyz + color, out[o].v.w);
    flush_counters();
}

// `wavefront::Surface`: the material, the hit point, the unit geometric normal facing the
// incoming ray (`nf`), the unit shading normal flipped with it (`ns`), the diffuse colour
// and emission (textures applied), whether the ray arrived on the side the geometric
// normal points to, and the unit direction of the ray.
struct Surface {
    m: Material,
    at: vec3<f32>,
    nf: vec3<f32>,
    ns: vec3<f32>,
    albedo: vec3<f32>,
    emission: vec3<f32>,
    front: bool,
    d: vec3<f32>,
}

// `wavefront::facing`: the geometric normal `ng` and the shading normal `ns` (on `ng`'s
// side) flipped together to the side a ray of unit direction `d` comes from; where the
// shading normal then faces away from the ray, the geometric normal shades. Returns
struct Facing {
    nf: vec3<f32>,
    ns: vec3<f32>,
    front: bool,
}

fn facing(ng: vec3<f32>, ns: vec3<f32>, d: vec3<f32>) -> Facing {
    let front = dot(ng, d) < 0.0;
    let nf = select(-ng, ng, front);
    let s = select(-ns, ns, front);
    return Facing(nf, select(nf, s, dot(s, d) < 0.0), front);
}

// `Wavefront::surface` for a ray that hit something.
fn surface(r: Ray, h: Hit) -> Surface {
    let m = material_of(h.id);
    let at = r.o + r.d * h.t;
    let d = normalize(r.d);
    let gn = hit_normal(r, h);
    let sh = scene_shading(h, m, gn, at);
    let f = facing(gn, sh.normal, d);
    return Surface(m, at, f.nf, f.ns, sh.albedo, sh.emission, f.front, d);
}

// `integrator::shade_cast`: the base colour (texture applied, no checkerboard) times a mix
// of |cos| to the viewer and a directional light, with the shading normal, plus emission.
fn shade_cast(r: Ray, h: Hit) -> vec3<f32> {
    if h.id == NO_HIT {
        return background_along(r.d);
    }
    let m = material_of(h.id);
    let d = normalize_or(r.d, vec3<f32>(0.0));
    let gn = hit_normal(r, h);
    let sh = scene_shading(h, m, gn, r.o + r.d * h.t);
    let n = facing(gn, sh.normal, d).ns;
    let cos_view = -dot(n, d);
    let diffuse = max(dot(n, -params.cast_light), 0.0);
    var albedo = sh.base_color;
    if m.kind == MAT_MIRROR {
        albedo = max(m.specular, vec3<f32>(0.2));
    } else if m.kind == MAT_GLASS {
        albedo = vec3<f32>(0.75, 0.85, 0.9);
    }
    return albedo * (0.35 * abs(cos_view) + 0.65 * diffuse) + sh.emission;
}

// The shading of a camera ray in ray casting and the volume modes: `CAST`, `MIP` or
// `COMPOSITE`.
const CAST: u32 = 0u;
const MIP: u32 = 1u;
const COMPOSITE: u32 = 2u;

fn shade_camera_ray(r: Ray, h: Hit, mode: u32) -> vec3<f32> {
    if mode == CAST {
        return shade_cast(r, h);
    }
    return shade_volumes(r, h, mode == COMPOSITE);
}

// `integrator::cast_tile` for thread `i`, with the shading of `mode`: the centre ray's id and
// t, then the colour (the centre ray's, or the sum of this dispatch's jittered samples,
// which the renderer divides by spp after readback as the CPU does).
fn cast_pixel(i: u32, mode: u32) {
    let p = pixel_of(i);
    if !p.ok {
        return;
    }
    let pixel = p.y * params.width + p.x;
    // With one sample the centre ray is that sample; else it is traced for its id and t
    // only, and the jittered samples give the colour (ids and t stay the centre ray's).
    let jittered = params.spp > 1u;
    let first = centre_rays(!jittered);
    var color = vec3<f32>(0.0);
    for (var j = 0u; j < first + params.s1 - params.s0; j++) {
        let s = sample_of(j, first);
        var r = centre_ray(p);
        if jittered && j >= first {
            var rng = Sampler(pixel, s, 0u);
            let jx = next_f32(&rng);
            let jy = next_f32(&rng);
            r = camera_ray(f32(p.x) + jx, f32(p.y) + jy);
        }
        let h = closest(r);
        n_rays += 1u;
        if j < first || (!jittered && s == 0u) {
            record_centre(p, h);
        }
        if j >= first {
            color += shade_camera_ray(r, h, mode);
        }
    }
    finish_pixel(p, color);
}

@compute @workgroup_size(64)
fn cast_kernel(@builtin(global_invocation_id) gid: vec3<u32>) {
    cast_pixel(gid.x, CAST);
}

// ---------------------------------------------------------------------------------------
// Whitted ray tracing, depth first (`integrator::whitted`).

struct Segment {
    o: vec3<f32>,
    depth: u32,
    d: vec3<f32>,
    weight: vec3<f32>,
}

@compute @workgroup_size(64)
fn whitted_kernel(@builtin(global_invocation_id) gid: vec3<u32>) {
    let p = pixel_of(gid.x);
    if !p.ok {
        return;
    }
    let pixel = p.y * params.width + p.x;
    let sample_weight = vec3<f32>(1.0 / f32(params.spp));
    let cut = 1e-4 * sample_weight.x;
    var color = vec3<f32>(0.0);
    // With one sample the centre ray is that sample's camera ray; else a pass of its own,
    // for its id and t only.
    let jittered = params.spp > 1u;
    let first = centre_rays(!jittered);
    var stack: array<Segment, WHITTED_STACK>;
    for (var j = 0u; j < first + params.s1 - params.s0; j++) {
        let s = sample_of(j, first);
        var camera = centre_ray(p);
        if jittered && j >= first {
            var rng = Sampler(pixel, s, 0u);
            let jx = next_f32(&rng);
            let jy = next_f32(&rng);
            camera = camera_ray(f32(p.x) + jx, f32(p.y) + jy);
        }
        let is_centre = j < first || (!jittered && s == 0u);
        stack[0] = Segment(camera.o, 0u, camera.d, sample_weight);
        var sp = 1u;
        while sp > 0u {
            sp -= 1u;
            let seg = stack[sp];
            let r = ray_new(seg.o, seg.d);
            let h = closest(r);
            n_rays += 1u;
            if seg.depth == 0u && is_centre {
                record_centre(p, h);
                if j < first {
                    continue;
                }
            }
            if h.id == NO_HIT {
                color += seg.weight * background_along(r.d);
                continue;
            }
            let sf = surface(r, h);
            let m = sf.m;
            let at = sf.at;
            let front = sf.front;
            let nf = sf.nf;
            let ns = sf.ns;
            let d = sf.d;
            if front {
                color += seg.weight * sf.emission;
            }
            if m.kind == MAT_DIFFUSE {
                let albedo = sf.albedo;
                color += seg.weight * albedo * AMBIENT;
                for (var k = 0u; k < whitted_light_count(); k++) {
                    let l = whitted_light(k, at, nf, ns);
                    if !l.ok {
                        continue;
                    }
                    // Lambert plus a Blinn-Phong highlight.
                    let hv = normalize_or(l.wi - d, vec3<f32>(0.0));
                    let c = max(dot(ns, hv), 0.0);
                    var spec_pow = pow(c, m.shininess);
                    if c <= 0.0 {
                        spec_pow = select(0.0, 1.0, m.shininess == 0.0);
                    }
                    let spec = m.specular * spec_pow;
                    n_rays += 1u;
                    if !occluded(l.ray) {
                        color += seg.weight * l.irradiance * (albedo + spec);
                    }
                }
            } else if seg.depth < params.max_depth {
                // Mirror and glass rays bent by the shading normal below the geometric
                // surface on their side are dropped (pbrt's rule): they would start inside.
                if m.kind == MAT_MIRROR {
                    let w = seg.weight * m.specular;
                    let dir = reflect_dir(d, ns);
                    if max3(w) > cut && dot(dir, nf) >= 0.0 {
                        stack[sp] = Segment(offset_ray_origin(at, nf), seg.depth + 1u, dir, w);
                        sp += 1u;
                    }
                } else {
                    // Entering when the ray meets the side the normal points to.
                    let n1 = select(m.ior, 1.0, front);
                    let n2 = select(1.0, m.ior, front);
                    let fr = fresnel_dielectric(-dot(d, ns), n1, n2);
                    let wr = seg.weight * m.specular * fr;
                    let dr = reflect_dir(d, ns);
                    if max3(wr) > cut && dot(dr, nf) >= 0.0 {
                        stack[sp] = Segment(offset_ray_origin(at, nf), seg.depth + 1u, dr, wr);
                        sp += 1u;
                    }
                    let t = refract_dir(d, ns, n1, n2);
                    let wt = seg.weight * m.specular * (1.0 - fr);
                    if t.w != 0.0 && max3(wt) > cut && dot(t.xyz, -nf) >= 0.0 {
                        stack[sp] = Segment(offset_ray_origin(at, -nf), seg.depth + 1u, t.xyz, wt);
                        sp += 1u;
                    }
                }
            }
        }
        flush_counters();
    }
    finish_pixel(p, color);
}

// ---------------------------------------------------------------------------------------
// Path tracing (`integrator::path`, estimator in docs/sampling.md).

// `environment::luminance`.
fn luminance(c: vec3<f32>) -> f32 {
    return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
}

// `integrator::path::power_heuristic`.
fn power_heuristic(a: f32, b: f32) -> f32 {
    if a <= 0.0 {
        return 0.0;
    }
    let r = b / a;
    return 1.0 / (1.0 + r * r);
}

@compute @workgroup_size(64)
fn path_kernel(@builtin(global_invocation_id) gid: vec3<u32>) {
    let p = pixel_of(gid.x);
    if !p.ok {
        return;
    }
    let pixel = p.y * params.width + p.x;
    let sample_weight = vec3<f32>(1.0 / f32(params.spp));
    var color = vec3<f32>(0.0);
    // Every sample is jittered: the centre ray is a pass of its own, for its id and t only.
    let first = centre_rays(false);
    for (var j = 0u; j < first + params.s1 - params.s0; j++) {
        var rng = Sampler(pixel, sample_of(j, first), 0u);
        let jx = next_f32(&rng);
        let jy = next_f32(&rng);
        var r = camera_ray(f32(p.x) + jx, f32(p.y) + jy);
        if j < first {
            r = centre_ray(p);
        }
        var weight = sample_weight;
        var specular = true;
        var pdf_bsdf = 0.0;
        for (var depth = 0u; depth <= params.max_depth; depth++) {
            let h = closest(r);
            n_rays += 1u;
            if j < first {
                record_centre(p, h);
                break;
            }
            // What the ray found counts fully unless a light sample at the previous
            // (diffuse) vertex could have found it too.
            let weighted = params.mis != 0u && !specular;
            if h.id == NO_HIT {
                var w = 1.0;
                if weighted && params.env_width != 0u {
                    w = power_heuristic(pdf_bsdf, pdf_environment(normalize(r.d)));
                }
                color += weight * w * background_along(r.d);
                break;
            }
            let sf = surface(r, h);
            let m = sf.m;
            let at = sf.at;
            let front = sf.front;
            let nf = sf.nf;
            let ns = sf.ns;
            let d = sf.d;
            if front && max3(sf.emission) > 0.0 {
                var w = 1.0;
                if weighted && is_emitter(h.id) {
                    let light = pdf_light_hit(r.o, h.id, h.k, at, hit_normal(r, h));
                    w = power_heuristic(pdf_bsdf, light);
                }
                color += weight * w * sf.emission;
            }
            if depth == params.max_depth {
                break;
            }
            rng.dimension = 2u + depth * DIMENSIONS_PER_BOUNCE;
            let u_light = next_f32(&rng);
            let u_point0 = next_f32(&rng);
            let u_point1 = next_f32(&rng);
            let u_dir0 = next_f32(&rng);
            let u_dir1 = next_f32(&rng);
            let u_choice = next_f32(&rng);
            let u_roulette = next_f32(&rng);

            let previous = weight;
            var dir: vec3<f32>;
            var side: vec3<f32>;
            if m.kind == MAT_DIFFUSE {
                let albedo = sf.albedo;
                let brdf = albedo * INV_PI;
                // One shadow ray per point light, then, with MIS, one to a sampled point of
                // the lights; one loop, so that the kernel calls `occluded` once.
                let shadow_rays = params.light_count + select(0u, 1u, params.mis != 0u);
                for (var l = 0u; l < shadow_rays; l++) {
                    var shadow: Ray;
                    var value: vec3<f32>;
                    var ok: bool;
                    if l < params.light_count {
                        let ray = light_ray(l, at, nf, ns);
                        shadow = ray.ray;
                        value = weight * brdf * ray.irradiance;
                        ok = ray.ok;
                    } else {
                        let origin = offset_ray_origin(at, nf);
                        let ls = sample_light(origin, u_light, u_point0, u_point1);
                        // The shading normal's cosine; a light below the geometric surface
                        // does not light it.
                        let cos_x = dot(ns, ls.wi);
                        ok = ls.ok && cos_x > 0.0 && dot(nf, ls.wi) > 0.0 && ls.pdf > 0.0 && is_finite(ls.pdf);
                        let w = power_heuristic(ls.pdf, cos_x * INV_PI);
                        value = weight * brdf * ls.radiance * (cos_x * w / ls.pdf);
                        if is_finite(ls.dist) {
                            shadow = make_ray(origin, ls.wi * ls.dist, 0.0, SHADOW_SHORTEN);
                        } else {
                            shadow = ray_new(origin, ls.wi);
                        }
                    }
                    if ok {
                        n_rays += 1u;
                        if !occluded(shadow) {
                            color += value;
                        }
                    }
                }
                weight *= albedo;
                specular = false;
                dir = cosine_hemisphere(ns, u_dir0, u_dir1);
                pdf_bsdf = max(dot(ns, dir), 0.0) * INV_PI;
                side = nf;
            } else if m.kind == MAT_MIRROR {
                weight *= m.specular;
                specular = true;
                dir = reflect_dir(d, ns);
                side = nf;
            } else {
                let n1 = select(m.ior, 1.0, front);
                let n2 = select(1.0, m.ior, front);
                let fr = fresnel_dielectric(-dot(d, ns), n1, n2);
                weight *= m.specular;
                specular = true;
                let t = refract_dir(d, ns, n1, n2);
                if t.w != 0.0 && u_choice >= fr {
                    dir = t.xyz;
                    side = -nf;
                } else {
                    dir = reflect_dir(d, ns);
                    side = nf;
                }
            }
            // A direction the shading normal sent below the geometric surface on the side
            // it leaves from ends the path (pbrt's rule).
            if dot(dir, side) < 0.0 {
                break;
            }
            let next = ray_new(offset_ray_origin(at, side), dir);
            if depth >= ROULETTE_DEPTH {
                let q = clamp(max3(weight) / max(max3(previous), MIN_POSITIVE), 0.05, 0.95);
                if u_roulette >= q {
                    break;
                }
                weight /= q;
            }
            if max3(weight) <= 0.0 {
                break;
            }
            r = next;
        }
        flush_counters();
    }
    finish_pixel(p, color);
}

// ---------------------------------------------------------------------------------------
// Explicit rays (incoherent ray sets): closest hits as (t, u, v) and id.

// Explicit ray `i`, and whether it is valid (`Ray::is_valid`): rays with a NaN or infinite
// component, a direction whose squared length is 0 or overflows, or a NaN bound, miss
// (tested by the bits: the shader compiler may assume finite arithmetic).
struct ExplicitRay {
    r: Ray,
    valid: bool,
}

fn explicit_ray(i: u32) -> ExplicitRay {
    let q = rays_in[i];
    let length2 = dot(q.d.xyz, q.d.xyz);
    let valid = is_finite(q.o.x) && is_finite(q.o.y) && is_finite(q.o.z)
        && is_finite(length2) && length2 > 0.0 && !is_nan(q.o.w) && !is_nan(q.d.w);
    return ExplicitRay(make_ray(q.o.xyz, q.d.xyz, q.o.w, q.d.w), valid);
}

@compute @workgroup_size(64)
fn trace_kernel(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= params.ray_count {
        return;
    }
    let q = explicit_ray(i);
    var h = Hit(params.inf, NO_HIT, 0.0, 0.0, 0u, 0u, NO_HIT);
    if q.valid {
        h = closest(q.r);
    }
    n_rays += 1u;
    out[i].v = vec4<f32>(select(h.t, params.inf, h.id == NO_HIT), h.u, h.v, 0.0);
    out[i].id = h.id;
    out[i].sub = h.sub;
    flush_counters();
}

// Explicit any-hit rays (shadow and occlusion rays, `Accel::occluded`): the traversal stops
// at the first hit; id 0 when something blocks the ray, NO_HIT when nothing does.
@compute @workgroup_size(64)
fn occlude_kernel(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= params.ray_count {
        return;
    }
    let q = explicit_ray(i);
    let blocked = q.valid && occluded(q.r);
    n_rays += 1u;
    out[i].v = vec4<f32>(0.0);
    out[i].id = select(NO_HIT, 0u, blocked);
    flush_counters();
}
