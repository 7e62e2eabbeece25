// Bicubic Bezier patches: a port of `raybench_geometry::BezierPatch::intersect_counted`
// (the region tree's nearest-first walk, Newton's method in each leaf region the ray's box
// test lets through, the fallback subdivision below a region where Newton fails, and the
// bilinear last resort at its deepest level) and of `BezierPatch::normal`.
// `geo/bezier.rs` lays out the record and the patch's data in `geo` (the control points
// relative to the patch centre c, the derivatives' control points, the region tree's
// boxes, which are the CPU's bit for bit); the depths, the iteration limit and the stack
// size come from the Rust constants (`BEZIER_*`, constants.rs).
//
// The walk is the CPU's: the same boxes and slab test, children nearest first, a region
// skipped when its box starts beyond the best hit, the same Newton start (the region's
// centre, the box's entry t), the same tests for a singular Jacobian, for leaving the
// region and for the margin of [0, 1]^2, the same fallback order; the search ignores
// t_max (one answer per ray, whichever order the traversal tests primitives in). The
// CPU's recursion (`solve_region`) becomes one explicit stack shared with the tree walk:
// at most three siblings wait per level, REGION_DEPTH + FALLBACK_DEPTH levels, plus the
// four children being pushed (BEZIER_STACK = 3 (REGION_DEPTH + FALLBACK_DEPTH) + 1 = 22).
//
// f32 in place of f64 (Newton, the fallback's boxes, the bilinear corners). Newton solves
// F(u, v, t) = S(u, v) - c - (o - c) - t d = 0 in coordinates relative to c, with S_u and
// S_v from their own control points (exactly zero at a collapsed edge, as the CPU's f64
// derivatives are there to their precision). Evaluating F in f32 rounds it by at most
// about 2^-20 M (Bernstein weights summing to 1, maximum norms), where
//     M = E + |o - c| + |S - c - (o - c)|,
// E the largest control-point coordinate relative to c (record c.x). The CPU's test
// |F| < 1e-7 extent (record b.y) lies below that floor when the ray starts far from the
// patch, so a step converges when |F| < max(1e-7 extent, 2^-18 M) (BEZIER_NOISE), and
// then takes one more Newton step (the polish: the step the CPU would take next, kept when
// it moves the point by no more than 64 times that threshold). Bound: the hit accepted has
// a true residual |F| <= 2^-17 M (the threshold plus the rounding of the last evaluation;
// after the polish it is typically the rounding floor, about 2^-20 M), so to first order
//     |t_gpu - t_exact| <= 2^-17 M / (|d| |cos theta|),
//     |(u, v)_gpu - (u, v)_exact| <= 2^-17 M / (sigma_min(S_u, S_v) |cos theta|),
// theta the angle between the ray and the surface normal, sigma_min the smaller singular
// value of [S_u S_v]. The CPU's own result is exact within 1e-7 extent / (|d| |cos theta|).
// For a camera ray from outside the patch (|o - c| and |t d| about the distance D,
// E << D) the relative bound on t is about 2^-16 / |cos theta| = 1.5e-5 / |cos theta|.
// Seen from secondary rays, which start off the surface by the Waechter-Binder offset
// (hundreds of ulps of the coordinates, at least 2^-16 near zero), M is a few E and the
// bound is at least an order of magnitude below the offset, so the ray's own surface
// solves to t < 0 as on the CPU.

// 2^-18: the convergence threshold relative to M (see above).
const BEZIER_NOISE: f32 = 3.814697265625e-6;

// How a Newton solve ended (`bezier::Newton`).
const BEZIER_CONVERGED: u32 = 0u;
const BEZIER_LEFT: u32 = 1u;
const BEZIER_FAILED: u32 = 2u;

// `S(u, v)` relative to the patch centre and its partial derivatives.
struct BezierEval {
    s: vec3<f32>,
    su: vec3<f32>,
    sv: vec3<f32>,
}

// `bezier::Newton`: the state and the final (u, v, t).
struct BezierNewton {
    state: u32,
    u: f32,
    v: f32,
    t: f32,
}

// The closest hit so far (`best` in `BezierPatch::intersect_counted`).
struct BezierBest {
    found: bool,
    u: f32,
    v: f32,
    t: f32,
}

// The search's stack: regions as level | iu << 4 | iv << 12 with their entry distance
// (`NodeStack` of the region tree, and the fallback's recursion).
struct BezierStack {
    code: array<u32, BEZIER_STACK>,
    t: array<f32, BEZIER_STACK>,
    sp: u32,
}

// Up to four child regions, sorted by entry distance.
struct BezierKids {
    code: array<u32, 4>,
    t: array<f32, 4>,
    n: u32,
}

// `bezier::bernstein`'s values: the cubic Bernstein polynomials at x.
fn bezier_b3(x: f32) -> vec4<f32> {
    let y = 1.0 - x;
    return vec4<f32>(y * y * y, 3.0 * x * y * y, 3.0 * x * x * y, x * x * x);
}

// `bezier::bernstein`'s derivatives in hodograph form: the quadratic Bernstein polynomials,
// which weight the derivative's control points 3 (P[i + 1] - P[i]).
fn bezier_b2(x: f32) -> vec3<f32> {
    let y = 1.0 - x;
    return vec3<f32>(y * y, 2.0 * x * y, x * x);
}

// `BezierPatch::eval`: S (relative to the centre), S_u and S_v at (u, v).
fn bezier_eval(base: u32, u: f32, v: f32) -> BezierEval {
    let bu = bezier_b3(u);
    let bv = bezier_b3(v);
    let cu = bezier_b2(u);
    let cv = bezier_b2(v);
    var s = vec3<f32>(0.0);
    var su = vec3<f32>(0.0);
    var sv = vec3<f32>(0.0);
    for (var j = 0u; j < 4u; j++) {
        let row = base + 4u * j;
        let pt = geo[row].xyz * bu.x + geo[row + 1u].xyz * bu.y + geo[row + 2u].xyz * bu.z
            + geo[row + 3u].xyz * bu.w;
        let drow = base + BEZIER_DU + 3u * j;
        let dp = geo[drow].xyz * cu.x + geo[drow + 1u].xyz * cu.y + geo[drow + 2u].xyz * cu.z;
        s += pt * bv[j];
        su += dp * bv[j];
    }
    for (var j = 0u; j < 3u; j++) {
        let row = base + BEZIER_DV + 4u * j;
        let dp = geo[row].xyz * bu.x + geo[row + 1u].xyz * bu.y + geo[row + 2u].xyz * bu.z
            + geo[row + 3u].xyz * bu.w;
        sv += dp * cv[j];
    }
    return BezierEval(s, su, sv);
}

// One step of `BezierPatch::newton`: J = [S_u, S_v, -d], J x = -F by Cramer's rule, as
// (du, dv, dt, 1); w = 0 when the Jacobian is singular (|det| <= 1e-12 |S_u| |S_v| |d|).
fn bezier_step(e: BezierEval, f: vec3<f32>, d: vec3<f32>, d_len: f32) -> vec4<f32> {
    let c = -d;
    let sv_c = cross(e.sv, c);
    let det = dot(e.su, sv_c);
    if abs(det) <= 1e-12 * length(e.su) * length(e.sv) * d_len || !is_finite(det) {
        return vec4<f32>(0.0);
    }
    let r = -f;
    return vec4<f32>(dot(r, sv_c) / det, dot(e.su, cross(r, c)) / det, dot(e.su, cross(e.sv, r)) / det, 1.0);
}

// `Region::contains`: (u, v) inside the region [reg.x, reg.y] x [reg.z, reg.w] widened by
// `margin` of its size (false for NaN).
fn bezier_contains(reg: vec4<f32>, u: f32, v: f32, margin: f32) -> bool {
    let mu = margin * (reg.y - reg.x);
    let mv = margin * (reg.w - reg.z);
    return u >= reg.x - mu && u <= reg.y + mu && v >= reg.z - mv && v <= reg.w + mv;
}

// `BezierPatch::newton`: Newton's method on F(u, v, t) = S(u, v) - o - t d (o relative to
// the centre) from (u, v, t) in region `reg`, converged at |F| < max(tol, 2^-18 M) and then
// polished by one step (see the file header); Left when an iterate leaves the region by
// more than its size or a converged point lies outside [0, 1]^2 by more than `margin`.
fn bezier_newton(base: u32, o: vec3<f32>, d: vec3<f32>, u0: f32, v0: f32, t0: f32, reg: vec4<f32>, tol: f32, scale: f32, margin: f32) -> BezierNewton {
    var u = u0;
    var v = v0;
    var t = t0;
    let d_len = length(d);
    let o_scale = scale + max3(abs(o));
    for (var i = 0u; i < BEZIER_NEWTON_ITERATIONS; i++) {
        let e = bezier_eval(base, u, v);
        let f = e.s - o - d * t;
        let limit = max(tol, BEZIER_NOISE * (o_scale + max3(abs(e.s - o))));
        if length(f) < limit {
            let p = bezier_step(e, f, d, d_len);
            let moved = max(max(length(e.su * p.x), length(e.sv * p.y)), length(d * p.z));
            if p.w != 0.0 && moved <= 64.0 * limit {
                u += p.x;
                v += p.y;
                t += p.z;
            }
            if bezier_contains(vec4<f32>(0.0, 1.0, 0.0, 1.0), u, v, margin) {
                return BezierNewton(BEZIER_CONVERGED, u, v, t);
            }
            return BezierNewton(BEZIER_LEFT, u, v, t);
        }
        let p = bezier_step(e, f, d, d_len);
        if p.w == 0.0 {
            return BezierNewton(BEZIER_FAILED, u, v, t);
        }
        u += p.x;
        v += p.y;
        t += p.z;
        if !bezier_contains(reg, u, v, 1.0) {
            return BezierNewton(BEZIER_LEFT, u, v, t);
        }
    }
    return BezierNewton(BEZIER_FAILED, u, v, t);
}

// `bezier::blossom`: de Casteljau with one parameter per level (glam's lerp is WGSL's mix).
fn bezier_blossom(c: array<vec3<f32>, 4>, t0: f32, t1: f32, t2: f32) -> vec3<f32> {
    let a = mix(c[0], c[1], t0);
    let b = mix(c[1], c[2], t0);
    let e = mix(c[2], c[3], t0);
    return mix(mix(a, b, t1), mix(b, e, t1), t2);
}

// `bezier::restrict_curve`: a cubic's control points over [a, b].
fn bezier_restrict_curve(c: array<vec3<f32>, 4>, a: f32, b: f32) -> array<vec3<f32>, 4> {
    return array<vec3<f32>, 4>(
        bezier_blossom(c, a, a, a),
        bezier_blossom(c, a, a, b),
        bezier_blossom(c, a, b, b),
        bezier_blossom(c, b, b, b));
}

// `bezier::control_box(&restrict(..))`: the box of the sub-patch's control points over
// `reg`, relative to the centre (unpadded), as (lo, hi) in a 2-column matrix.
fn bezier_sub_box(base: u32, reg: vec4<f32>) -> mat2x3<f32> {
    var rows: array<vec3<f32>, 16>;
    for (var j = 0u; j < 4u; j++) {
        let row = base + 4u * j;
        var c = bezier_restrict_curve(
            array<vec3<f32>, 4>(geo[row].xyz, geo[row + 1u].xyz, geo[row + 2u].xyz, geo[row + 3u].xyz),
            reg.x, reg.y);
        for (var i = 0u; i < 4u; i++) {
            rows[4u * j + i] = c[i];
        }
    }
    var lo = vec3<f32>(params.inf);
    var hi = vec3<f32>(-params.inf);
    for (var i = 0u; i < 4u; i++) {
        var c = bezier_restrict_curve(
            array<vec3<f32>, 4>(rows[i], rows[4u + i], rows[8u + i], rows[12u + i]),
            reg.z, reg.w);
        for (var j = 0u; j < 4u; j++) {
            lo = min(lo, c[j]);
            hi = max(hi, c[j]);
        }
    }
    return mat2x3<f32>(lo, hi);
}

// `BezierPatch::keep`: records (u, v, t) when t lies in [t_min, inf) and is closer.
fn bezier_keep(best: ptr<function, BezierBest>, t_min: f32, u: f32, v: f32, t: f32) {
    if t < t_min || !is_finite(t) {
        return;
    }
    if !(*best).found || t < (*best).t {
        *best = BezierBest(true, u, v, t);
    }
}

// The CPU's child sorting (`sort_unstable_by`, an insertion sort at four elements, so
// stable): inserts (code, t) after the entries it does not precede, in descending order
// of t (the region tree's, pushed as they come) or ascending (the fallback's, pushed in
// reverse).
fn bezier_insert(kids: ptr<function, BezierKids>, code: u32, t: f32, descending: bool) {
    var k = (*kids).n;
    while k > 0u {
        let prev = (*kids).t[k - 1u];
        let before = select((t < prev), (t > prev), descending);
        if !before {
            break;
        }
        (*kids).code[k] = (*kids).code[k - 1u];
        (*kids).t[k] = prev;
        k -= 1u;
    }
    (*kids).code[k] = code;
    (*kids).t[k] = t;
    (*kids).n += 1u;
}

// `BezierPatch::intersect_counted` with `solve_region` unrolled into the walk's stack: the
// closest hit in [t_min, inf), reported when it is at most t_max; u and v are the patch
// parameters, clamped to [0, 1].
fn bezier_hit(r: Ray, p: Prim, t_max: f32) -> Cand {
    let base = bitcast<u32>(p.b.x);
    let centre = p.a.xyz;
    let tol = p.b.y;
    let pad = p.b.z;
    let scale = p.c.x;
    let margin = p.c.y;
    let o = r.o - centre;
    let boxes = base + BEZIER_BOXES;
    let t_root = box_entry(r, geo[boxes].xyz, geo[boxes + 1u].xyz, params.inf);
    if t_root < 0.0 {
        return miss();
    }
    var best = BezierBest(false, 0.0, 0.0, params.inf);
    var st: BezierStack;
    st.code[0] = 0u;
    st.t[0] = t_root;
    st.sp = 1u;
    while st.sp > 0u {
        st.sp -= 1u;
        let entry = st.t[st.sp];
        // `pop_within`: strict, so an entry at the best distance may still hold a tie.
        if entry > best.t {
            continue;
        }
        let code = st.code[st.sp];
        let level = code & 15u;
        let iu = (code >> 4u) & 255u;
        let iv = code >> 12u;
        let size = 1.0 / f32(1u << level);
        let reg = vec4<f32>(f32(iu) * size, f32(iu + 1u) * size, f32(iv) * size, f32(iv + 1u) * size);
        var kids: BezierKids;
        kids.n = 0u;
        if level < BEZIER_REGION_DEPTH {
            // The precomputed children, pushed far to near.
            let n = 1u << level;
            let first = boxes + 2u * (((1u << (2u * (level + 1u))) - 1u) / 3u);
            for (var k = 0u; k < 4u; k++) {
                let cu = 2u * iu + (k & 1u);
                let cv = 2u * iv + (k >> 1u);
                let b = first + 2u * (cv * 2u * n + cu);
                let t = box_entry(r, geo[b].xyz, geo[b + 1u].xyz, best.t);
                if t >= 0.0 {
                    bezier_insert(&kids, (level + 1u) | (cu << 4u) | (cv << 12u), t, true);
                }
            }
            for (var k = 0u; k < kids.n; k++) {
                st.code[st.sp] = kids.code[k];
                st.t[st.sp] = kids.t[k];
                st.sp += 1u;
            }
            continue;
        }
        // `solve_region` with `depth` fallback levels left.
        let depth = BEZIER_REGION_DEPTH + BEZIER_FALLBACK_DEPTH - level;
        let nw = bezier_newton(base, o, r.d, 0.5 * (reg.x + reg.y), 0.5 * (reg.z + reg.w), entry, reg, tol, scale, margin);
        if nw.state == BEZIER_CONVERGED {
            bezier_keep(&best, r.t_min, nw.u, nw.v, nw.t);
            continue;
        }
        if nw.state == BEZIER_LEFT {
            continue;
        }
        if depth == 0u {
            // The region's corners as a bilinear patch, polished by Newton.
            let q00 = bezier_eval(base, reg.x, reg.z).s;
            let q10 = bezier_eval(base, reg.y, reg.z).s;
            let q11 = bezier_eval(base, reg.y, reg.w).s;
            let q01 = bezier_eval(base, reg.x, reg.w).s;
            let h = bilinear_hit(o, r.d, r.t_min, q00, q10, q11, q01);
            if h.w == 0.0 {
                continue;
            }
            let u = reg.x + h.y * (reg.y - reg.x);
            let v = reg.z + h.z * (reg.w - reg.z);
            let polished = bezier_newton(base, o, r.d, u, v, h.x, reg, tol, scale, margin);
            if polished.state == BEZIER_CONVERGED {
                bezier_keep(&best, r.t_min, polished.u, polished.v, polished.t);
            } else {
                bezier_keep(&best, r.t_min, u, v, h.x);
            }
            continue;
        }
        // Newton failed: the four quarters' boxes (de Casteljau, padded), nearest first.
        for (var k = 0u; k < 4u; k++) {
            let cu = 2u * iu + (k & 1u);
            let cv = 2u * iv + (k >> 1u);
            let half = 0.5 * size;
            let q = vec4<f32>(f32(cu) * half, f32(cu + 1u) * half, f32(cv) * half, f32(cv + 1u) * half);
            let b = bezier_sub_box(base, q);
            let t = box_entry(r, b[0] + centre - vec3<f32>(pad), b[1] + centre + vec3<f32>(pad), best.t);
            if t >= 0.0 {
                bezier_insert(&kids, (level + 1u) | (cu << 4u) | (cv << 12u), t, false);
            }
        }
        for (var k = kids.n; k > 0u; k--) {
            st.code[st.sp] = kids.code[k - 1u];
            st.t[st.sp] = kids.t[k - 1u];
            st.sp += 1u;
        }
    }
    if !best.found || best.t < r.t_min || best.t > t_max {
        return miss();
    }
    return Cand(best.t, clamp(best.u, 0.0, 1.0), clamp(best.v, 0.0, 1.0), 0u, true);
}

// `BezierPatch::normal`: the unit S_u x S_v at the hit's (u, v); where it vanishes
// (|S_u x S_v| <= 1e-9 max(|S_u|^2, |S_v|^2), a collapsed edge) the normal at the point
// moved 1e-3 of the way toward the patch centre.
fn bezier_normal(r: Ray, p: Prim, h: Hit) -> vec3<f32> {
    let base = bitcast<u32>(p.b.x);
    let e = bezier_eval(base, h.u, h.v);
    var n = cross(e.su, e.sv);
    let scale = max(dot(e.su, e.su), dot(e.sv, e.sv));
    if !(length(n) > 1e-9 * scale) {
        let m = bezier_eval(base, h.u + (0.5 - h.u) * 1e-3, h.v + (0.5 - h.v) * 1e-3);
        n = cross(m.su, m.sv);
    }
    return normalize_or(n, vec3<f32>(0.0, 1.0, 0.0));
}
