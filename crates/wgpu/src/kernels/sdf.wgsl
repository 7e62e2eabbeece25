// SDF models (raybench-geometry's `sdf/`, sphere tracing): `geo/sdf.rs` lays out the
// record (the padded box in a.xyz and b.xyz; c = program start and end as bits, the hit
// tolerance eps, the Lipschitz bound L) and the program in `geo` (a header with the step
// limit, then the tree as postfix instructions: opcode bits in x, parameters after).
//
// The march and the normal are the CPU's rules step for step (`Sdf::march`, `Sdf::normal`),
// in f32 as on the CPU. The distances differ from the CPU's only by the GPU's rounding of
// sqrt, division and fused multiply-adds (a few ulps of each operand); a step that lands
// within those ulps of the acceptance test `|f| < eps` may then stop one step earlier or
// later than the CPU: the two t then differ by at most one step of at most eps / (L |dir|)
// (the last step before a hit is below eps in distance), and both hits are within the
// tolerance of the surface. Elsewhere t agrees to the accumulated rounding of the steps.

// Opcodes and stack sizes (`geo/sdf.rs` has the same; a test there compares them).
const SDF_SPHERE: u32 = 0u;
const SDF_BOX: u32 = 1u;
const SDF_TORUS: u32 = 2u;
const SDF_CAPSULE: u32 = 3u;
const SDF_CYLINDER: u32 = 4u;
const SDF_UNION: u32 = 5u;
const SDF_INTERSECTION: u32 = 6u;
const SDF_SUBTRACTION: u32 = 7u;
const SDF_SMOOTH_UNION: u32 = 8u;
const SDF_BLEND: u32 = 9u;
const SDF_ENTER: u32 = 10u;
const SDF_LEAVE: u32 = 11u;
const SDF_VALUES: u32 = 32u;
const SDF_POINTS: u32 = 32u;

// `primitive_distance` (Quilez's exact distances) for the primitive with opcode `op`,
// first entry's parameters `h` (a centre or a capsule's end a) and second entry `e`.
fn sdf_primitive(op: u32, h: vec3<f32>, e: vec4<f32>, p: vec3<f32>) -> f32 {
    switch op {
        case SDF_SPHERE: {
            return length(p - h) - e.x;
        }
        case SDF_BOX: {
            let q = abs(p - h) - (e.xyz - vec3<f32>(e.w));
            return length(max(q, vec3<f32>(0.0))) + min(max3(q), 0.0) - e.w;
        }
        case SDF_TORUS: {
            let q = p - h;
            return length(vec2<f32>(length(q.xz) - e.x, q.y)) - e.y;
        }
        case SDF_CAPSULE: {
            let pa = p - h;
            let ba = e.xyz - h;
            let len2 = dot(ba, ba);
            var t = 0.0;
            if len2 > 0.0 {
                t = clamp(dot(pa, ba) / len2, 0.0, 1.0);
            }
            return length(pa - ba * t) - e.w;
        }
        default: {
            // SDF_CYLINDER.
            let q = p - h;
            let d = abs(vec2<f32>(length(q.xz), q.y)) - e.xy;
            return min(max(d.x, d.y), 0.0) + length(max(d, vec2<f32>(0.0)));
        }
    }
}

// `SdfOp::apply`: the operation with opcode `op` and parameter `k` (smooth-union radius or
// blend weight) on the operands' values.
fn sdf_apply(op: u32, k: f32, a: f32, b: f32) -> f32 {
    switch op {
        case SDF_UNION: {
            return min(a, b);
        }
        case SDF_INTERSECTION: {
            return max(a, b);
        }
        case SDF_SUBTRACTION: {
            return max(a, -b);
        }
        case SDF_SMOOTH_UNION: {
            let h = max(k - abs(a - b), 0.0) / k;
            return min(a, b) - h * h * k * 0.25;
        }
        default: {
            // SDF_BLEND.
            return (1.0 - k) * a + k * b;
        }
    }
}

// `Sdf::distance` (the recursive `Sdf::eval`): the program in geo[first..end] run at `x`.
// Values are pushed by primitives and combined by operations; a transform saves the point
// on entry (`Similarity::local` maps it) and restores it on exit, scaling the value.
fn sdf_distance(first: u32, end: u32, x: vec3<f32>) -> f32 {
    var values: array<f32, SDF_VALUES>;
    var points: array<vec3<f32>, SDF_POINTS>;
    var sv = 0u;
    var sp = 0u;
    var p = x;
    var pc = first;
    while pc < end {
        let e = geo[pc];
        let op = bitcast<u32>(e.x);
        if op <= SDF_CYLINDER {
            values[sv] = sdf_primitive(op, e.yzw, geo[pc + 1u], p);
            sv += 1u;
            pc += 2u;
        } else if op <= SDF_BLEND {
            sv -= 1u;
            values[sv - 1u] = sdf_apply(op, e.y, values[sv - 1u], values[sv]);
            pc += 1u;
        } else if op == SDF_ENTER {
            points[sp] = p;
            sp += 1u;
            // Column by column, then the translation, as `Affine3A::transform_point3`.
            p = geo[pc + 1u].xyz * p.x + geo[pc + 2u].xyz * p.y + geo[pc + 3u].xyz * p.z + e.yzw;
            pc += 4u;
        } else {
            // SDF_LEAVE.
            sp -= 1u;
            p = points[sp];
            values[sv - 1u] = e.y * values[sv - 1u];
            pc += 1u;
        }
    }
    return values[0];
}

// `Sdf::march` (through `Sdf::intersect`): the first surface point of `r` within
// [r.t_min, t_max] inside the padded box (`Sdf::clip`), under the marching rules of
// `sdf/mod.rs`: steps of |f| / (L |dir|), a hit where |f| < eps, fixed steps of eps while the
// ray starts within eps of the surface, then the side fixed by the sign of f.
fn sdf_hit(r: Ray, p: Prim, t_max: f32) -> Cand {
    // `Ray::is_valid` (by the bits: the compiler may assume finite arithmetic).
    let length2 = dot(r.d, r.d);
    if !(is_finite(r.o.x) && is_finite(r.o.y) && is_finite(r.o.z) && is_finite(length2) && length2 > 0.0) {
        return miss();
    }
    // `Sdf::clip`.
    var t0 = r.t_min;
    var t1 = t_max;
    for (var i = 0u; i < 3u; i++) {
        let o = r.o[i];
        let d = r.d[i];
        let lo = p.a[i];
        let hi = p.b[i];
        if d == 0.0 {
            if !(o >= lo && o <= hi) {
                return miss();
            }
            continue;
        }
        let a = (lo - o) / d;
        let b = (hi - o) / d;
        t0 = max(t0, min(a, b));
        t1 = min(t1, max(a, b));
    }
    if !(t0 <= t1) {
        return miss();
    }
    let start = bitcast<u32>(p.c.x);
    let end = bitcast<u32>(p.c.y);
    let eps = p.c.z;
    let max_steps = bitcast<u32>(geo[start].x);
    let per_unit = 1.0 / (sqrt(length2) * p.c.w);
    let leave = eps * per_unit;
    var t = t0;
    // 0 while leaving the surface band, then the sign of f on the ray's side.
    var side = 0.0;
    var steps = 0u;
    while steps < max_steps {
        steps += 1u;
        let f = sdf_distance(start + 1u, end, r.o + r.d * t);
        if side == 0.0 && abs(f) >= eps {
            // `f32::signum` (f is not NaN here).
            side = copysign(1.0, f);
        }
        if side == 0.0 {
            t += leave;
        } else {
            let g = side * f;
            if g < eps {
                return Cand(t, 0.0, 0.0, 0u, true);
            }
            t += g * per_unit;
        }
        if t > t1 || is_nan(t) {
            break;
        }
    }
    return miss();
}

// `Sdf::normal` at the hit point (`Shape::complete_hit`: `ray.at(t)`): the gradient by the
// tetrahedron technique with step eps, normalised; `Y` where it vanishes.
fn sdf_normal(r: Ray, p: Prim, h: Hit) -> vec3<f32> {
    let x = r.o + r.d * h.t;
    let first = bitcast<u32>(p.c.x) + 1u;
    let end = bitcast<u32>(p.c.y);
    let eps = p.c.z;
    let k0 = vec3<f32>(1.0, -1.0, -1.0);
    let k1 = vec3<f32>(-1.0, -1.0, 1.0);
    let k2 = vec3<f32>(-1.0, 1.0, -1.0);
    let k3 = vec3<f32>(1.0, 1.0, 1.0);
    let n = k0 * sdf_distance(first, end, x + k0 * eps)
        + k1 * sdf_distance(first, end, x + k1 * eps)
        + k2 * sdf_distance(first, end, x + k2 * eps)
        + k3 * sdf_distance(first, end, x + k3 * eps);
    return normalize_or(n, vec3<f32>(0.0, 1.0, 0.0));
}
