// Bilinear patches: a port of raybench-geometry's `BilinearPatch` (crates/geometry/src/
// bilinear.rs), shared by the Bezier patches' last resort (`bezier.wgsl`) and the height
// fields' bilinear cells (`heightfield.wgsl`).

// `BilinearPatch::intersect` (Reshetov 2019) of the ray (o, d) clipped to [t_min, inf) with
// the patch through q00, q10, q11, q01: (t, u, v, 1), w = 0 on a miss.
fn bilinear_hit(o: vec3<f32>, d: vec3<f32>, t_min: f32, q00: vec3<f32>, q10: vec3<f32>, q11: vec3<f32>, q01: vec3<f32>) -> vec4<f32> {
    let e10 = q10 - q00;
    let e11 = q11 - q10;
    let e00 = q01 - q00;
    let qn = cross(e10, q01 - q11);
    let a00 = q00 - o;
    let a10 = q10 - o;
    let a = dot(cross(a00, d), e00);
    let c = dot(qn, d);
    let b = dot(cross(a10, d), e11) - (a + c);
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 || is_nan(disc) {
        return vec4<f32>(0.0);
    }
    var roots = array<f32, 2>(0.0, 0.0);
    var valid = array<bool, 2>(true, false);
    if c == 0.0 {
        if b == 0.0 {
            return vec4<f32>(0.0);
        }
        roots[0] = -a / b;
    } else {
        let q = -0.5 * (b + copysign(sqrt(disc), b));
        roots[0] = q / c;
        if q != 0.0 {
            roots[1] = a / q;
            valid[1] = true;
        }
    }
    var best = vec4<f32>(0.0);
    for (var k = 0u; k < 2u; k++) {
        let u = roots[k];
        if !valid[k] || !(u >= 0.0 && u <= 1.0) {
            continue;
        }
        let pa = mix(a00, a10, u);
        let pb = mix(e00, e11, u);
        let n = cross(d, pb);
        let det = dot(n, n);
        if det == 0.0 {
            continue;
        }
        let m = cross(n, pa);
        let t = dot(m, pb) / det;
        let v = dot(m, d);
        if v >= 0.0 && v <= det && t >= t_min && !is_nan(t) && (best.w == 0.0 || t < best.x) {
            best = vec4<f32>(t, u, v / det, 1.0);
        }
    }
    return best;
}

// `BilinearPatch::normal`: the unit normal dP/du x dP/dv at (u, v), +Y where it vanishes.
fn bilinear_normal(q00: vec3<f32>, q10: vec3<f32>, q11: vec3<f32>, q01: vec3<f32>, u: f32, v: f32) -> vec3<f32> {
    let du = mix(q10 - q00, q11 - q01, v);
    let dv = mix(q01 - q00, q11 - q10, u);
    return normalize_or(cross(du, dv), vec3<f32>(0.0, 1.0, 0.0));
}
