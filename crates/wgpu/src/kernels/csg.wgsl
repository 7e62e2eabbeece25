// CSG trees (raybench-geometry's `csg` module): every solid, placed or not, under unions,
// intersections and differences. `geo/csg.rs` lays out the record and the tree in `geo`.
//
// Evaluation. The core combines span lists recursively (`Csg::spans`, `spans::combine`);
// WGSL has no recursion, and a stack of span lists sized for the loader's limits (256
// leaves of up to two spans) would need kilobytes per invocation. The kernels use what
// that algebra amounts to: a node's span ends are the times where its inside state,
// read on the open intervals between event times (every event at one `t` applied
// together), changes, and the end it reports there is its second operand's when that
// operand changed (negated under a difference), else its first's. So the root's first
// end at or after `t_min` is the first leaf end time at which the root's state changes:
// the kernels walk the event times upwards and evaluate the tree at each with a stack of
// packed per-node states (`CSG_STACK` entries: a post-order walk of a tree `n` levels
// deep holds at most `n`), keeping the span ends of the first `CSG_CACHE` leaves and
// evaluating any further leaves again at each event time. Same `t`s, leaves, normals as
// the core's, except in one case the core itself only meets by rounding: a torus leaf
// whose two spans touch at a `t` where another operand also changes (the core can then
// report the torus' end, these the other's).
// A one-leaf tree returns its leaf's first end, as the core's loop over the root's spans.
//
// f32 in place of the core's f64. The core computes the quadrics' coefficients and roots
// (cylinder, cone, paraboloid) and the torus quartic in f64 from the f32 ray. Here:
// - Cylinder side: the sphere primitive's form in the xz plane (Ray Tracing Gems ch. 7):
//   the discriminant is r^2 - |l|^2, with l the line's point closest to the axis, so
//   nothing cancels when the origin is far; t0 = c / q, t1 = q / a as the core's.
// - Cone and paraboloid: the origin is first moved along the ray to the point closest to
//   the solid's box centre (`ts`), so the quadric's coefficients are of the solid's size,
//   not the origin's distance; t = ts + s with s the shifted quadratic's stable roots.
// - Torus: the core's own formulation (origin moved to the line's point closest to the
//   centre, lengths in units of R + r, coefficients of order one) solved by the core's
//   derivative bracketing and safeguarded Newton, in f32, then each root polished by up
//   to two Newton steps on the quartic's factor that vanishes there (`csg_torus_polish`),
//   which f32 evaluates about 1 / S times more accurately than the quartic itself.
// Bound: for a crossing at angle theta to the surface, the ray's origin relative to the
// solid carries an f32 rounding of a few ulps of its distance |o - c|, and the solve adds
// a few ulps of the solid's size: |t - t_core| <~ 8 eps (|o - c| + size) / (|d| sin
// theta), eps = 2^-24 (the torus' quartic before polishing: about 1e-6 (R + r) / |d|).
// Relative to t that is about 1e-6 for the built-in scenes' camera rays (measured on
// lavapipe: largest relative dt 2.4e-7 on `csg`, 4.3e-7 on `quadrics`, against the
// tests' MAX_REL_DT of 1e-4); it grows as rays graze a surface (sin theta -> 0), where a
// quadric's or torus' two crossings merge into a double root and lose half the digits
// (|dt| <~ sqrt(8 eps) size / |d|; such rays lie within about 1e-5 of the solid's size
// of the silhouette, where CPU and GPU may also disagree on hit or miss), and relative to
// t it grows for rays that start within about 1e-4 of a surface, whose t is tiny while the
// absolute error stays at about 1e-7 of the scene's coordinates.

// The kernels' array sizes, equal to raybench-geometry's limits (`geo/csg.rs` checks the
// declarations against the Rust constants): `limits::MAX_CSG_DEPTH` results on the
// evaluation stack and `limits::MAX_CSG_LEAVES` leaves.
const CSG_STACK: u32 = 32u;
const CSG_MAX_LEAVES: u32 = 256u;
// Leaves whose span ends are kept between event times (larger trees evaluate the rest
// again at each: an array of 256 made lavapipe's compile take minutes).
const CSG_CACHE: u32 = 16u;
// Entries of `geo` per leaf, and the node code of a leaf (operators: 0 union,
// 1 intersection, 2 difference).
const CSG_LEAF_STRIDE: u32 = 8u;
const CSG_NODE_LEAF: u32 = 3u;

// Solid kinds (`geo/csg.rs` `solid_code`).
const CSG_SPHERE: u32 = 0u;
const CSG_BOX: u32 = 1u;
const CSG_CYLINDER: u32 = 2u;
const CSG_CONE: u32 = 3u;
const CSG_HALF_SPACE: u32 = 4u;
const CSG_ELLIPSOID: u32 = 5u;
const CSG_TORUS: u32 = 6u;
const CSG_PARABOLOID: u32 = 7u;

const CSG_Y: vec3<f32> = vec3<f32>(0.0, 1.0, 0.0);

fn csg_nan() -> f32 {
    return bitcast<f32>(0x7fc00000u);
}

// `spans::Span`: an entry and an exit with their normals; `ok` false for none.
struct CsgSpan {
    ok: bool,
    t0: f32,
    n0: vec3<f32>,
    t1: f32,
    n1: vec3<f32>,
}

fn csg_none() -> CsgSpan {
    return CsgSpan(false, 0.0, vec3<f32>(0.0), 0.0, vec3<f32>(0.0));
}

// `spans::finish`: drops zero-length (tangent) and NaN spans.
fn csg_finish(s: CsgSpan) -> CsgSpan {
    if s.ok && s.t0 < s.t1 && !is_nan(s.t0) && !is_nan(s.t1) {
        return s;
    }
    return csg_none();
}

// `spans::LeafSpans`: a leaf's span ends, ascending (`t[0]` entry, `t[1]` exit, `t[2]`,
// `t[3]` the second span's), +inf past `count`, with their outward normals.
struct CsgEnds {
    count: u32,
    t: vec4<f32>,
    n: array<vec3<f32>, 4>,
}

// `LeafSpans::push`: appends `s` when it has positive length.
fn csg_push(e: ptr<function, CsgEnds>, s: CsgSpan) {
    let f = csg_finish(s);
    if !f.ok || (*e).count >= 4u {
        return;
    }
    let k = (*e).count;
    (*e).t[k] = f.t0;
    (*e).n[k] = f.n0;
    (*e).t[k + 1u] = f.t1;
    (*e).n[k + 1u] = f.n1;
    (*e).count = k + 2u;
}

// Roots of a quadratic, ascending; `ok` false for none.
struct CsgRoots {
    ok: bool,
    t0: f32,
    t1: f32,
}

// `solid::quadratic`: the roots of `a t^2 - 2 b t + c` in the stable form, or none when
// there are none or `a` is zero (in f32 from coefficients of the solid's size: the callers
// shift the origin first).
fn csg_quadratic(a: f32, b: f32, c: f32) -> CsgRoots {
    let disc = b * b - a * c;
    if is_nan(disc) || disc < 0.0 || a == 0.0 {
        return CsgRoots(false, 0.0, 0.0);
    }
    let q = b + copysign(sqrt(disc), b);
    var t0 = 0.0;
    var t1 = 0.0;
    if q != 0.0 {
        t0 = c / q;
        t1 = q / a;
    }
    if t0 <= t1 {
        return CsgRoots(true, t0, t1);
    }
    return CsgRoots(true, t1, t0);
}

// `sphere::line_in_ball`: the line `f + t d` inside the ball of `radius` about the origin, as the
// sphere primitive computes it.
fn csg_ball(f: vec3<f32>, d: vec3<f32>, radius: f32) -> CsgRoots {
    let a = dot(d, d);
    let b = -dot(f, d);
    let l = f + d * (b / a);
    let r2 = radius * radius;
    let disc = r2 - dot(l, l);
    if is_nan(disc) || disc < 0.0 {
        return CsgRoots(false, 0.0, 0.0);
    }
    let c = dot(f, f) - r2;
    let q = b + copysign(sqrt(a) * sqrt(disc), b);
    let t0 = c / q;
    let t1 = q / a;
    if t0 <= t1 {
        return CsgRoots(true, t0, t1);
    }
    return CsgRoots(true, t1, t0);
}

// `solid::slab`: the line inside `lo <= o + t d <= hi` on one axis: (t_enter, t_exit,
// the entry's outward normal sign, 1) or w = 0 when it misses; the whole line when it is
// parallel and strictly inside.
fn csg_slab(o: f32, d: f32, lo: f32, hi: f32) -> vec4<f32> {
    if d == 0.0 {
        if o > lo && o < hi {
            return vec4<f32>(-params.inf, params.inf, 0.0, 1.0);
        }
        return vec4<f32>(0.0);
    }
    let t_lo = (lo - o) / d;
    let t_hi = (hi - o) / d;
    if d > 0.0 {
        return vec4<f32>(t_lo, t_hi, -1.0, 1.0);
    }
    return vec4<f32>(t_hi, t_lo, 1.0, 1.0);
}

// `solid::capped` for a solid of revolution about y: the side's interval (s0, s1) cut by
// the slab (y0, y1) whose caps have the normals (0, sign, 0) and (0, -sign, 0); `side0`,
// `side1` are the side's normals at s0 and s1. On a tie the side keeps the boundary.
fn csg_capped(y: vec4<f32>, s0: f32, s1: f32, side0: vec3<f32>, side1: vec3<f32>) -> CsgSpan {
    let cap = vec3<f32>(0.0, y.z, 0.0);
    var out = CsgSpan(true, s0, side0, s1, side1);
    if y.x > s0 {
        out.t0 = y.x;
        out.n0 = cap;
    }
    if y.y < s1 {
        out.t1 = y.y;
        out.n1 = -cap;
    }
    return out;
}

// Roots of a shifted quadric: the origin moved to `o + d ts`, `ts` the point of the line
// closest to `centre` (all relative to the solid's own origin).
fn csg_shift(f: vec3<f32>, d: vec3<f32>, centre: vec3<f32>) -> f32 {
    return dot(centre - f, d) / dot(d, d);
}

// The cylinder's normal at `p` (relative to the base): `solid_span`'s `side`.
fn csg_cylinder_normal(p: vec3<f32>) -> vec3<f32> {
    return normalize_or(vec3<f32>(p.x, 0.0, p.z), vec3<f32>(1.0, 0.0, 0.0));
}

// `solid::solid_span`, Solid::Cylinder: the side in the sphere primitive's form (see the
// file's header) capped by the slab.
fn csg_cylinder(o: vec3<f32>, d: vec3<f32>, base: vec3<f32>, radius: f32, height: f32) -> CsgSpan {
    let y = csg_slab(o.y, d.y, base.y, base.y + height);
    if y.w == 0.0 {
        return csg_none();
    }
    let f = o - base;
    let r2 = radius * radius;
    var s0 = -params.inf;
    var s1 = params.inf;
    if d.x == 0.0 && d.z == 0.0 {
        let c = f.x * f.x + f.z * f.z - r2;
        if is_nan(c) || c > 0.0 {
            return csg_none();
        }
    } else {
        let f2 = f.xz;
        let d2 = d.xz;
        let a = dot(d2, d2);
        let b = -dot(f2, d2);
        let l = f2 + d2 * (b / a);
        let disc = r2 - dot(l, l);
        if is_nan(disc) || disc < 0.0 {
            return csg_none();
        }
        let c = dot(f2, f2) - r2;
        let q = b + copysign(sqrt(a) * sqrt(disc), b);
        var t0 = 0.0;
        var t1 = 0.0;
        if q != 0.0 {
            t0 = c / q;
            t1 = q / a;
        }
        s0 = min(t0, t1);
        s1 = max(t0, t1);
    }
    let n0 = csg_cylinder_normal(o + d * s0 - base);
    let n1 = csg_cylinder_normal(o + d * s1 - base);
    return csg_capped(y, s0, s1, n0, n1);
}

// The cone's normal at `p` (relative to the apex): `solid_span`'s `normal`.
fn csg_cone_normal(p: vec3<f32>, k2: f32) -> vec3<f32> {
    return normalize_or(vec3<f32>(p.x, -k2 * p.y, p.z), CSG_Y);
}

// `solid::solid_span`, Solid::Cone: the double cone x^2 + z^2 <= k^2 y^2 about the apex,
// its quadratic solved from the shifted origin (see the file's header), its nappe below
// the apex cut by the slab.
fn csg_cone(o: vec3<f32>, d: vec3<f32>, base: vec3<f32>, radius: f32, height: f32) -> CsgSpan {
    let y = csg_slab(o.y, d.y, base.y, base.y + height);
    if y.w == 0.0 {
        return csg_none();
    }
    let k2 = (radius / height) * (radius / height);
    let apex = base + vec3<f32>(0.0, height, 0.0);
    let f = o - apex;
    let ts = csg_shift(f, d, vec3<f32>(0.0, -0.5 * height, 0.0));
    let g = f + d * ts;
    let a = d.x * d.x + d.z * d.z - k2 * d.y * d.y;
    let bh = -(g.x * d.x + g.z * d.z - k2 * g.y * d.y);
    let c = g.x * g.x + g.z * g.z - k2 * g.y * g.y;
    let cap = vec3<f32>(0.0, y.z, 0.0);
    // The line's parts inside the double cone: one interval, or two rays.
    var p0 = vec2<f32>(csg_nan(), csg_nan());
    var p1 = vec2<f32>(csg_nan(), csg_nan());
    if a == 0.0 {
        if bh == 0.0 {
            if is_nan(c) || c > 0.0 {
                return csg_none();
            }
            p0 = vec2<f32>(-params.inf, params.inf);
        } else {
            let t = ts + c / (2.0 * bh);
            if bh > 0.0 {
                p0 = vec2<f32>(t, params.inf);
            } else {
                p0 = vec2<f32>(-params.inf, t);
            }
        }
    } else {
        let r = csg_quadratic(a, bh, c);
        if !r.ok {
            // No real roots: the quadratic keeps the sign of `a` everywhere.
            if a > 0.0 || is_nan(a) {
                return csg_none();
            }
            return csg_finish(CsgSpan(true, y.x, cap, y.y, -cap));
        }
        let r0 = ts + r.t0;
        let r1 = ts + r.t1;
        if a > 0.0 {
            p0 = vec2<f32>(r0, r1);
        } else {
            p0 = vec2<f32>(-params.inf, r0);
            p1 = vec2<f32>(r1, params.inf);
        }
    }
    // Only the nappe below the apex lies in the slab: the first non-empty piece.
    for (var k = 0u; k < 2u; k++) {
        let piece = select(p1, p0, k == 0u);
        let n0 = csg_cone_normal(f + d * piece.x, k2);
        let n1 = csg_cone_normal(f + d * piece.y, k2);
        let span = csg_capped(y, piece.x, piece.y, n0, n1);
        if span.t0 < span.t1 {
            return span;
        }
    }
    return csg_none();
}

// The paraboloid's normal at `p` (relative to the apex): `solid_span`'s `normal`.
fn csg_paraboloid_normal(p: vec3<f32>, k: f32) -> vec3<f32> {
    return normalize_or(vec3<f32>(2.0 * k * p.x, -1.0, 2.0 * k * p.z), -CSG_Y);
}

// `solid::solid_span`, Solid::Paraboloid: inside where k (x^2 + z^2) - y <= 0 about the
// apex, its quadratic solved from the shifted origin, capped at the top.
fn csg_paraboloid(o: vec3<f32>, d: vec3<f32>, base: vec3<f32>, radius: f32, height: f32) -> CsgSpan {
    let f = o - base;
    let y = csg_slab(f.y, d.y, -params.inf, height);
    if y.w == 0.0 {
        return csg_none();
    }
    let k = height / (radius * radius);
    let ts = csg_shift(f, d, vec3<f32>(0.0, 0.5 * height, 0.0));
    let g = f + d * ts;
    let a = k * (d.x * d.x + d.z * d.z);
    let bh = 0.5 * d.y - k * (g.x * d.x + g.z * d.z);
    let c = k * (g.x * g.x + g.z * g.z) - g.y;
    var s0 = -params.inf;
    var s1 = params.inf;
    if d.x == 0.0 && d.z == 0.0 {
        // Along the axis: the linear -2 b' t + c <= 0.
        if bh == 0.0 {
            if is_nan(c) || c > 0.0 {
                return csg_none();
            }
        } else if bh > 0.0 {
            s0 = ts + c / (2.0 * bh);
        } else {
            s1 = ts + c / (2.0 * bh);
        }
    } else {
        let r = csg_quadratic(a, bh, c);
        if !r.ok {
            return csg_none();
        }
        s0 = ts + r.t0;
        s1 = ts + r.t1;
    }
    let n0 = csg_paraboloid_normal(f + d * s0, k);
    let n1 = csg_paraboloid_normal(f + d * s1, k);
    return csg_capped(y, s0, s1, n0, n1);
}

// `solid::solid_span`, Solid::Box: the slabs' overlap; on a tie (an edge) the lower axis
// keeps it.
fn csg_box(o: vec3<f32>, d: vec3<f32>, lo: vec3<f32>, hi: vec3<f32>) -> CsgSpan {
    var out = CsgSpan(true, -params.inf, vec3<f32>(0.0), params.inf, vec3<f32>(0.0));
    for (var axis = 0u; axis < 3u; axis++) {
        let s = csg_slab(o[axis], d[axis], lo[axis], hi[axis]);
        if s.w == 0.0 {
            return csg_none();
        }
        var n = vec3<f32>(0.0);
        n[axis] = s.z;
        if s.x > out.t0 {
            out.t0 = s.x;
            out.n0 = n;
        }
        if s.y < out.t1 {
            out.t1 = s.y;
            out.n1 = -n;
        }
    }
    return out;
}

// `solid::solid_span`, Solid::HalfSpace: `dot(p - point, normal) <= 0`.
fn csg_half_space(o: vec3<f32>, d: vec3<f32>, point: vec3<f32>, normal: vec3<f32>) -> CsgSpan {
    let dn = dot(d, normal);
    let dist = dot(o - point, normal);
    if dn == 0.0 {
        if is_nan(dist) || dist > 0.0 {
            return csg_none();
        }
        return CsgSpan(true, -params.inf, -normal, params.inf, normal);
    }
    let t = -dist / dn;
    if dn > 0.0 {
        return CsgSpan(true, -params.inf, -normal, t, normal);
    }
    return CsgSpan(true, t, normal, params.inf, -normal);
}

// ---------------------------------------------------------------------------------------
// The torus (`quartic.rs`): real roots by derivative bracketing, in f32.

// `quartic::eval`: p (coefficients from the constant term up, degree n) at x by Horner.
fn csg_poly(p_in: array<f32, 5>, n: u32, x: f32) -> f32 {
    var p = p_in;
    var acc = 0.0;
    for (var k = 0; k <= i32(n); k++) {
        acc = acc * x + p[i32(n) - k];
    }
    return acc;
}

// `quartic::bracketed`: the root of p in [a, b], where p(a) and p(b) have opposite signs,
// by Newton steps kept inside the shrinking bracket (bisection when a step leaves it).
fn csg_bracketed(p: array<f32, 5>, dp: array<f32, 5>, n: u32, a_in: f32, b_in: f32) -> f32 {
    var a = a_in;
    var b = b_in;
    let rising = csg_poly(p, n, a) < 0.0;
    var x = 0.5 * (a + b);
    for (var it = 0u; it < 100u; it++) {
        let fx = csg_poly(p, n, x);
        if fx == 0.0 {
            return x;
        }
        if (fx < 0.0) == rising {
            a = x;
        } else {
            b = x;
        }
        let newton = x - fx / csg_poly(dp, n - 1u, x);
        var next = 0.5 * (a + b);
        if newton > a && newton < b {
            next = newton;
        }
        if next == x || (b - a) <= 4.0 * 1.1920929e-7 * max(abs(x), MIN_POSITIVE) {
            return next;
        }
        x = next;
    }
    return x;
}

// `quartic::roots` for the quartic `q` (leading coefficient one): its roots in (lo, hi)
// where it changes sign, ascending, in `out`; returns how many. The recursion over the
// derivatives runs upwards: the roots of the third derivative (linear) bracket those of
// the second, which bracket the first's, which bracket the quartic's.
fn csg_quartic_roots(q: array<f32, 5>, lo: f32, hi: f32, out: ptr<function, vec4<f32>>) -> u32 {
    // The derivatives: polys[4 - n] has degree n.
    var polys: array<array<f32, 5>, 4>;
    polys[0] = q;
    for (var m = 1u; m < 4u; m++) {
        // The previous polynomial's degree: its derivative's coefficient k - 1 is k c_k.
        let deg = 5u - m;
        for (var k = 1u; k <= deg; k++) {
            polys[m][k - 1u] = f32(k) * polys[m - 1u][k];
        }
    }
    // Degree 1.
    var crit = vec4<f32>(0.0);
    var count = 0u;
    let p1 = polys[3];
    let x = -p1[0] / p1[1];
    if x > lo && x < hi {
        crit[0] = x;
        count = 1u;
    }
    // Degrees 2, 3, 4: each bracketed by the previous one's roots.
    for (var deg = 2u; deg <= 4u; deg++) {
        let p = polys[4u - deg];
        let dp = polys[5u - deg];
        var found = vec4<f32>(0.0);
        var n = 0u;
        var a = lo;
        var fa = csg_poly(p, deg, a);
        for (var k = 0u; k <= count; k++) {
            let b = select(hi, crit[min(k, 3u)], k < count);
            let fb = csg_poly(p, deg, b);
            // Zero counts as positive (outside), so crossings pair up.
            if (fa < 0.0) != (fb < 0.0) && n < 4u {
                found[n] = csg_bracketed(p, dp, deg, a, b);
                n += 1u;
            }
            a = b;
            fa = fb;
        }
        crit = found;
        count = n;
    }
    *out = crit;
    return count;
}

// The torus' outward normal (unnormalised) at `q` in units of R + r (`quartic::torus`).
fn csg_torus_normal(q: vec3<f32>, big: f32, small: f32) -> vec3<f32> {
    let r2 = 4.0 * big * big;
    let n = q * (4.0 * (dot(q, q) + big * big - small * small)) - vec3<f32>(q.x, 0.0, q.z) * (2.0 * r2);
    return normalize_or(n, CSG_Y);
}

// Newton polishing of a torus crossing `s` (no core counterpart: the core's f64 quartic
// needs none). The quartic factors as G H with G = (rho - B)^2 + y^2 - S^2 (the tube's
// surface) and H = (rho + B)^2 + y^2 - S^2 (its mirror image through the axis, which
// bounds a spindle torus' inner lemon), rho = |q.xz|. Near the surface the factor that
// vanishes is evaluated with an error of about eps S instead of the quartic's eps (order
// one), so up to two Newton steps on it take the root from the quartic's f32 accuracy
// (about 1e-6 of R + r) to about 1e-7. Steps larger than 1e-3 (a tangent ray, where the
// root is ill-conditioned anyway) and non-finite ones are not taken.
fn csg_torus_polish(p: vec3<f32>, u: vec3<f32>, big: f32, small: f32, s: f32) -> f32 {
    var x = s;
    for (var it = 0u; it < 2u; it++) {
        let q = p + u * x;
        let rho = length(q.xz);
        if !(rho > 0.0) {
            break;
        }
        let drho = dot(q.xz, u.xz) / rho;
        let g = (rho - big) * (rho - big) + q.y * q.y - small * small;
        let h = (rho + big) * (rho + big) + q.y * q.y - small * small;
        var f = g;
        var df = 2.0 * ((rho - big) * drho + q.y * u.y);
        if abs(h) < abs(g) {
            f = h;
            df = 2.0 * ((rho + big) * drho + q.y * u.y);
        }
        if df == 0.0 {
            break;
        }
        let step = f / df;
        if !(abs(step) < 1e-3) {
            break;
        }
        x -= step;
    }
    return x;
}

// `quartic::torus` and `solid::solid_spans` for a torus: the crossings of `o + t d` (o
// relative to the centre) in pairs, spans appended to `e`. The origin moves to the line's
// point closest to the centre and lengths are in units of R + r, so the quartic's
// coefficients are of order one (see the file's header for the bound in f32).
fn csg_torus(e: ptr<function, CsgEnds>, o: vec3<f32>, d: vec3<f32>, major: f32, minor: f32) {
    let unit = major + minor;
    let dd = length(d);
    if !(dd > 0.0 && is_finite(dd) && is_finite(o.x) && is_finite(o.y) && is_finite(o.z)) {
        return;
    }
    let u = d / dd;
    let t0 = -dot(o, u);
    let p = (o + u * t0) / unit;
    if dot(p, p) >= 1.0 {
        return;
    }
    let big = major / unit;
    let small = minor / unit;
    let r2 = 4.0 * big * big;
    let h = dot(p, u);
    let g = dot(p, p) + big * big - small * small;
    let uxz = u.x * u.x + u.z * u.z;
    let pu = p.x * u.x + p.z * u.z;
    let pxz = p.x * p.x + p.z * p.z;
    let q = array<f32, 5>(
        g * g - r2 * pxz,
        4.0 * h * g - 2.0 * r2 * pu,
        4.0 * h * h + 2.0 * g - r2 * uxz,
        4.0 * h,
        1.0,
    );
    var s: vec4<f32>;
    let n = csg_quartic_roots(q, -1.25, 1.25, &s);
    // Polish each root on the factor of the quartic that vanishes there (see
    // `csg_torus_polish`), keeping the roots' order.
    var polished = s;
    var ordered = true;
    for (var k = 0u; k < n; k++) {
        polished[k] = csg_torus_polish(p, u, big, small, s[k]);
        if k > 0u && !(polished[k] > polished[k - 1u]) {
            ordered = false;
        }
    }
    if ordered {
        s = polished;
    }
    for (var k = 0u; k + 1u < n; k += 2u) {
        let sa = s[k];
        let sb = s[k + 1u];
        let na = csg_torus_normal(p + u * sa, big, small);
        let nb = csg_torus_normal(p + u * sb, big, small);
        csg_push(e, CsgSpan(true, (t0 + sa * unit) / dd, na, (t0 + sb * unit) / dd, nb));
    }
}

// ---------------------------------------------------------------------------------------
// Leaves and the tree.

// `placement::leaf_spans`: the span ends of leaf `k` (its record at `base`): the ray taken
// to the solid's local space when it is placed, its normals brought back (`t` unchanged).
fn csg_leaf(o_world: vec3<f32>, d_world: vec3<f32>, base: u32) -> CsgEnds {
    let g0 = geo[base];
    let g1 = geo[base + 1u];
    let placed = bitcast<u32>(g1.w) != 0u;
    var o = o_world;
    var d = d_world;
    if placed {
        let c0 = geo[base + 2u];
        let c1 = geo[base + 3u];
        let c2 = geo[base + 4u];
        o = c0.xyz * o_world.x + c1.xyz * o_world.y + c2.xyz * o_world.z + vec3<f32>(c0.w, c1.w, c2.w);
        d = c0.xyz * d_world.x + c1.xyz * d_world.y + c2.xyz * d_world.z;
    }
    var e: CsgEnds;
    e.count = 0u;
    e.t = vec4<f32>(params.inf);
    switch bitcast<u32>(g0.w) {
        case CSG_SPHERE: {
            let r = csg_ball(o - g0.xyz, d, g1.x);
            if r.ok {
                let n0 = normalize_or((o + d * r.t0 - g0.xyz) / g1.x, CSG_Y);
                let n1 = normalize_or((o + d * r.t1 - g0.xyz) / g1.x, CSG_Y);
                csg_push(&e, CsgSpan(true, r.t0, n0, r.t1, n1));
            }
        }
        case CSG_ELLIPSOID: {
            let f = (o - g0.xyz) / g1.xyz;
            let du = d / g1.xyz;
            let r = csg_ball(f, du, 1.0);
            if r.ok {
                let n0 = normalize_or((f + du * r.t0) / g1.xyz, CSG_Y);
                let n1 = normalize_or((f + du * r.t1) / g1.xyz, CSG_Y);
                csg_push(&e, CsgSpan(true, r.t0, n0, r.t1, n1));
            }
        }
        case CSG_BOX: {
            csg_push(&e, csg_box(o, d, g0.xyz, g1.xyz));
        }
        case CSG_CYLINDER: {
            csg_push(&e, csg_cylinder(o, d, g0.xyz, g1.x, g1.y));
        }
        case CSG_CONE: {
            csg_push(&e, csg_cone(o, d, g0.xyz, g1.x, g1.y));
        }
        case CSG_HALF_SPACE: {
            csg_push(&e, csg_half_space(o, d, g0.xyz, g1.xyz));
        }
        case CSG_TORUS: {
            csg_torus(&e, o - g0.xyz, d, g1.x, g1.y);
        }
        case CSG_PARABOLOID: {
            csg_push(&e, csg_paraboloid(o, d, g0.xyz, g1.x, g1.y));
        }
        default: {}
    }
    if placed {
        let m0 = geo[base + 5u].xyz;
        let m1 = geo[base + 6u].xyz;
        let m2 = geo[base + 7u].xyz;
        for (var k = 0u; k < e.count; k++) {
            let n = e.n[k];
            e.n[k] = normalize_or(m0 * n.x + m1 * n.y + m2 * n.z, n);
        }
    }
    return e;
}

// The end a tree reports: `t`, the leaf, which of the leaf's ends (0..3), and whether its
// normal is negated (an odd number of subtractions); `ok` false when there is none.
struct CsgEnd {
    ok: bool,
    t: f32,
    leaf: u32,
    slot: u32,
    flip: bool,
    // With `want_normal`: the outward normal there.
    normal: vec3<f32>,
}

// A node's state at an event time, packed: bit 0 inside before it, bit 1 inside after it,
// bits 2-9 the leaf of the end it reports (when the two differ), bits 10-11 the leaf's end,
// bit 12 the normal's negation.
fn csg_leaf_state(e: vec4<f32>, t: f32, leaf: u32) -> u32 {
    let before = (e.x < t && t <= e.y) || (e.z < t && t <= e.w);
    let after = (e.x <= t && t < e.y) || (e.z <= t && t < e.w);
    var slot = 0u;
    if after {
        slot = select(2u, 0u, e.x == t);
    } else {
        slot = select(3u, 1u, e.y == t);
    }
    return select(0u, 1u, before) | select(0u, 2u, after) | (leaf << 2u) | (slot << 10u);
}

// `CsgOp::apply`.
fn csg_apply(op: u32, a: bool, b: bool) -> bool {
    switch op {
        case 0u: {
            return a || b;
        }
        case 1u: {
            return a && b;
        }
        default: {
            return a && !b;
        }
    }
}

// `spans::combine` at one event time: the operator's state before and after from its
// operands', and the end it reports: the second operand's when that one changed (its
// events are applied last; negated under a difference), else the first's.
fn csg_op_state(op: u32, a: u32, b: u32) -> u32 {
    let before = csg_apply(op, (a & 1u) != 0u, (b & 1u) != 0u);
    let after = csg_apply(op, (a & 2u) != 0u, (b & 2u) != 0u);
    var s = select(0u, 1u, before) | select(0u, 2u, after);
    if before != after {
        let b_changed = (b & 1u) != ((b >> 1u) & 1u);
        if b_changed {
            s |= (b & 0x1ffcu) ^ select(0u, 0x1000u, op == 2u);
        } else {
            s |= a & 0x1ffcu;
        }
    }
    return s;
}

// The smallest finite end of `e` after `lo` (at or after it when `!strict`), or `best`.
fn csg_next(e: vec4<f32>, lo: f32, strict: bool, best: f32) -> f32 {
    var t = best;
    for (var j = 0u; j < 4u; j++) {
        let x = e[j];
        if is_finite(x) && (x > lo || (!strict && x == lo)) && x < t {
            t = x;
        }
    }
    return t;
}

// `Csg::first_end` (and, with `want_normal`, `Csg::normal`): the first end of the
// combined solid inside [r.t_min, t_max], from the tree at geo[b.x] (`b.y` nodes, `b.z`
// leaves); rays missing the tree's box miss without evaluating it.
//
// One loop with one call of `csg_leaf` (so that the compiler inlines the solids once) runs
// three phases: 0 evaluates every leaf, keeps the ends of the first `CSG_CACHE` and finds
// the first event time at or after t_min; 1 evaluates the tree at an event time in a walk
// over the nodes that also finds the next event time, and pauses at a leaf past the cache
// to have it evaluated again; 2 evaluates the found end's leaf once more for its normal.
// Trees of at most `CSG_CACHE` leaves (every built-in scene's) evaluate each leaf once.
fn csg_first(r: Ray, p: Prim, t_max: f32, want_normal: bool) -> CsgEnd {
    var found = CsgEnd(false, 0.0, 0u, 0u, false, CSG_Y);
    if box_entry(r, p.a.xyz, p.c.xyz, t_max) < 0.0 {
        return found;
    }
    let start = bitcast<u32>(p.b.x);
    let count = bitcast<u32>(p.b.y);
    let leaves = bitcast<u32>(p.b.z);
    let leaf_base = start + (count + 3u) / 4u;
    var cache: array<vec4<f32>, CSG_CACHE>;
    var stack: array<u32, CSG_STACK>;
    var phase = 0u;
    var request = 0u;
    // The event time evaluated and the next one; the walk's node, stack top and leaf.
    var t = 0.0;
    var t_next = params.inf;
    var i = 0u;
    var sp = 0u;
    var leaf = 0u;
    var rounds = 0u;
    loop {
        let e = csg_leaf(r.o, r.d, leaf_base + request * CSG_LEAF_STRIDE);
        if phase == 2u {
            let n = e.n[min(found.slot, 3u)];
            found.normal = select(n, -n, found.flip);
            return found;
        }
        var have = false;
        if phase == 0u {
            if count == 1u {
                // One leaf: its own spans are the root's.
                found = csg_leaf_first(r, e.t, t_max);
                if found.ok && want_normal {
                    phase = 2u;
                    continue;
                }
                return found;
            }
            if request < CSG_CACHE {
                cache[request] = e.t;
            }
            t_next = csg_next(e.t, r.t_min, false, t_next);
            request += 1u;
            if request < leaves {
                continue;
            }
            phase = 1u;
            i = count;
        } else {
            have = true;
        }
        // The walk, until it needs a leaf evaluated again or finds the end.
        loop {
            if i >= count {
                // A round ends: the root's state at t, then the next event time.
                if rounds > 0u {
                    let root = stack[0];
                    if (root & 1u) != ((root >> 1u) & 1u) {
                        found = CsgEnd(true, t, (root >> 2u) & 0xffu, (root >> 10u) & 3u, (root & 0x1000u) != 0u, CSG_Y);
                        if !want_normal {
                            return found;
                        }
                        phase = 2u;
                        request = found.leaf;
                        break;
                    }
                }
                if !is_finite(t_next) || t_next > t_max || rounds > 4u * leaves {
                    return CsgEnd(false, 0.0, 0u, 0u, false, CSG_Y);
                }
                t = t_next;
                t_next = params.inf;
                i = 0u;
                sp = 0u;
                leaf = 0u;
                rounds += 1u;
            }
            let code = bitcast<u32>(geo[start + i / 4u][i % 4u]);
            if code == CSG_NODE_LEAF {
                var ends = vec4<f32>(0.0);
                if leaf < CSG_CACHE {
                    ends = cache[leaf];
                } else if have {
                    ends = e.t;
                    have = false;
                } else {
                    request = leaf;
                    break;
                }
                stack[min(sp, CSG_STACK - 1u)] = csg_leaf_state(ends, t, leaf);
                t_next = csg_next(ends, t, true, t_next);
                sp += 1u;
                leaf += 1u;
            } else if sp >= 2u {
                let b = stack[min(sp - 1u, CSG_STACK - 1u)];
                let a = stack[min(sp - 2u, CSG_STACK - 1u)];
                sp -= 1u;
                stack[min(sp - 1u, CSG_STACK - 1u)] = csg_op_state(code, a, b);
            }
            i += 1u;
        }
    }
    return found;
}

// `Csg::first_end` for a one-leaf tree: the leaf's first end inside [r.t_min, t_max].
fn csg_leaf_first(r: Ray, t: vec4<f32>, t_max: f32) -> CsgEnd {
    for (var k = 0u; k < 4u; k++) {
        let x = t[k];
        if x > t_max {
            break;
        }
        if x >= r.t_min && is_finite(x) {
            return CsgEnd(true, x, 0u, k, false, CSG_Y);
        }
    }
    return CsgEnd(false, 0.0, 0u, 0u, false, CSG_Y);
}

// `Csg::intersect`: the first boundary inside [r.t_min, t_max]; the sub-primitive id is
// the leaf's (leaves numbered left to right), u = v = 0.
fn csg_hit(r: Ray, p: Prim, t_max: f32) -> Cand {
    let e = csg_first(r, p, t_max, false);
    if !e.ok {
        return miss();
    }
    return Cand(e.t, 0.0, 0.0, e.leaf, true);
}

// `Csg::normal`: the outward normal of the combined solid at the hit, by evaluating the
// tree again (unclipped: the first end at or after t_min is the hit's, and an evaluation
// that rounds the hit's `t` a little differently still finds it); `Y` if it is not found.
fn csg_normal(r: Ray, p: Prim, h: Hit) -> vec3<f32> {
    return csg_first(r, p, params.inf, true).normal;
}
