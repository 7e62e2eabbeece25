// The volume modes: maximum-intensity projection (`mip_kernel`) and emission-absorption
// compositing (`composite_kernel`) of the scene's voxel volumes along each camera ray, cut
// by the first surface (`integrator::mip_composite` and `voxels` of raybench-core). The
// volumes are laid out in `geo` by `crates/wgpu/src/volume.rs` (its module documentation
// gives the layout and the precision argument); `params.volume_first` indexes their table.
// Each function names the core routine it ports and keeps its operations in order.

// `voxels::VolumeSample`: what one ray gathers through the volumes.
struct VolumeSample {
    crossed: bool,
    max: f32,
    color: vec3<f32>,
    transmittance: f32,
}

// `VolumeSample::default`.
fn volume_sample_new() -> VolumeSample {
    return VolumeSample(false, -params.inf, vec3<f32>(0.0), 1.0);
}

// A volume's header (`volume.rs` writes it; the fields of `voxels::Volume`).
struct VolumeHeader {
    // World to object: the matrix's columns and the translation.
    m0: vec3<f32>,
    m1: vec3<f32>,
    m2: vec3<f32>,
    mt: vec3<f32>,
    trilinear: bool,
    // The object-space box's minimum and 1 / spacing.
    box_min: vec3<f32>,
    skip_empty: bool,
    inv_s: vec3<f32>,
    n_points: u32,
    dims: vec3<u32>,
    // Index in `geo` of the transfer function's points.
    points: u32,
    coarse_dims: vec3<u32>,
    // Index in `geo` of the coarse min-max grid.
    coarse: u32,
    // The MIP window.
    window: vec2<f32>,
    // Index in `geo` of the voxels.
    voxels: u32,
}

// The header of volume k of the scene.
fn volume_header(k: u32) -> VolumeHeader {
    let h = bitcast<u32>(geo[params.volume_first + k].x);
    let e3 = geo[h + 3u];
    let e4 = geo[h + 4u];
    let e5 = geo[h + 5u];
    let e6 = bitcast<vec4<u32>>(geo[h + 6u]);
    let e7 = bitcast<vec4<u32>>(geo[h + 7u]);
    let e8 = geo[h + 8u];
    return VolumeHeader(
        geo[h].xyz,
        geo[h + 1u].xyz,
        geo[h + 2u].xyz,
        e3.xyz,
        bitcast<u32>(e3.w) != 0u,
        e4.xyz,
        bitcast<u32>(e4.w) != 0u,
        e5.xyz,
        bitcast<u32>(e5.w),
        e6.xyz,
        e6.w,
        e7.xyz,
        e7.w,
        e8.xy,
        bitcast<u32>(e8.z),
    );
}

// `Volume::voxel`: the value of voxel c.
fn volume_voxel(v: VolumeHeader, c: vec3<u32>) -> f32 {
    let i = (c.z * v.dims.y + c.y) * v.dims.x + c.x;
    return geo[v.voxels + i / 4u][i % 4u];
}

// The closure `lerp` of `Volume::trilinear`.
fn volume_lerp(a: f32, b: f32, t: f32) -> f32 {
    return a + (b - a) * t;
}

// `Volume::trilinear`: interpolation at grid point p (voxel centres at i + 0.5), clamped
// at the borders.
fn volume_trilinear(v: VolumeHeader, p: vec3<f32>) -> f32 {
    let q = p - 0.5;
    var i0 = vec3<u32>(0u);
    var i1 = vec3<u32>(0u);
    var f = vec3<f32>(0.0);
    for (var a = 0u; a < 3u; a++) {
        let top = f32(v.dims[a]) - 1.0;
        // `f32::clamp`, which NaN passes through (and `as u32` maps to 0).
        var x = q[a];
        if x < 0.0 {
            x = 0.0;
        }
        if x > top {
            x = top;
        }
        let fl = floor(x);
        if !is_nan(fl) {
            i0[a] = u32(fl);
        }
        i1[a] = min(i0[a] + 1u, v.dims[a] - 1u);
        f[a] = x - fl;
    }
    let c00 = volume_lerp(volume_voxel(v, vec3<u32>(i0.x, i0.y, i0.z)), volume_voxel(v, vec3<u32>(i1.x, i0.y, i0.z)), f.x);
    let c10 = volume_lerp(volume_voxel(v, vec3<u32>(i0.x, i1.y, i0.z)), volume_voxel(v, vec3<u32>(i1.x, i1.y, i0.z)), f.x);
    let c01 = volume_lerp(volume_voxel(v, vec3<u32>(i0.x, i0.y, i1.z)), volume_voxel(v, vec3<u32>(i1.x, i0.y, i1.z)), f.x);
    let c11 = volume_lerp(volume_voxel(v, vec3<u32>(i0.x, i1.y, i1.z)), volume_voxel(v, vec3<u32>(i1.x, i1.y, i1.z)), f.x);
    return volume_lerp(volume_lerp(c00, c10, f.y), volume_lerp(c01, c11, f.y), f.z);
}

// `TransferFunction::eval`: colour (xyz) and extinction (w) at `value`, piecewise linear,
// constant beyond the first and last points.
fn transfer_eval(v: VolumeHeader, value: f32) -> vec4<f32> {
    let first = geo[v.points];
    // NaN values read as the first point.
    if value <= first.x || is_nan(value) {
        return vec4<f32>(geo[v.points + 1u].xyz, first.y);
    }
    for (var k = 1u; k < v.n_points; k++) {
        let a = geo[v.points + 2u * (k - 1u)];
        let b = geo[v.points + 2u * k];
        if value <= b.x {
            let f = (value - a.x) / (b.x - a.x);
            // `Vec3::lerp`: a * (1 - f) + b * f.
            let ca = geo[v.points + 2u * (k - 1u) + 1u].xyz;
            let cb = geo[v.points + 2u * k + 1u].xyz;
            return vec4<f32>(ca * (1.0 - f) + cb * f, a.y + (b.y - a.y) * f);
        }
    }
    let last = v.points + 2u * (v.n_points - 1u);
    return vec4<f32>(geo[last + 1u].xyz, geo[last].y);
}

// `TransferFunction::max_sigma`: the largest extinction over values in [lo, hi] (the ends
// and the points between).
fn transfer_max_sigma(v: VolumeHeader, lo: f32, hi: f32) -> f32 {
    var m = max(transfer_eval(v, lo).w, transfer_eval(v, hi).w);
    for (var k = 0u; k < v.n_points; k++) {
        let p = geo[v.points + 2u * k];
        if p.x > lo && p.x < hi {
            m = max(m, p.y);
        }
    }
    return m;
}

// `Volume::grid_ray`'s answer: the ray in grid units (go + t gd, the world ray's t) and
// the interval [t0, t1] where it is inside the grid; ok false where it crosses nothing.
struct GridRay {
    go: vec3<f32>,
    gd: vec3<f32>,
    t0: f32,
    t1: f32,
    ok: bool,
}

// `Volume::grid_ray`: the ray in grid units, clipped to [r.t_min, t_max].
fn volume_grid_ray(v: VolumeHeader, r: Ray, t_max: f32) -> GridRay {
    // `Affine3A::transform_point3` and `transform_vector3`, column by column.
    let o = v.m0 * r.o.x + v.m1 * r.o.y + v.m2 * r.o.z + v.mt;
    let d = v.m0 * r.d.x + v.m1 * r.d.y + v.m2 * r.d.z;
    let go = (o - v.box_min) * v.inv_s;
    let gd = d * v.inv_s;
    var g = GridRay(go, gd, r.t_min, t_max, false);
    // NaN or infinite rays, and zero directions (which never leave), cross nothing.
    for (var a = 0u; a < 3u; a++) {
        if !is_finite(go[a]) || !is_finite(gd[a]) {
            return g;
        }
    }
    if all(gd == vec3<f32>(0.0)) {
        return g;
    }
    let dims = vec3<f32>(v.dims);
    for (var a = 0u; a < 3u; a++) {
        if gd[a] == 0.0 {
            if !(go[a] >= 0.0 && go[a] <= dims[a]) {
                return g;
            }
            continue;
        }
        let ta = (0.0 - go[a]) / gd[a];
        let tb = (dims[a] - go[a]) / gd[a];
        g.t0 = max(g.t0, min(ta, tb));
        g.t1 = min(g.t1, max(ta, tb));
    }
    g.ok = g.t0 < g.t1 && is_finite(g.t1);
    return g;
}

// One walk of `raybench_core::dda` (the 3D-DDA of Amanatides and Woo) over a grid of
// `dims` cells along o + t d from t0 to t1. WGSL has no closures: `dda_next` hands out
// one cell at a time and the caller's loop is the visitor.
struct Dda {
    o: vec3<f32>,
    d: vec3<f32>,
    dims: vec3<i32>,
    cell: vec3<i32>,
    step: vec3<i32>,
    // Distance at which the ray leaves `cell` across each axis' border.
    tn: vec3<f32>,
    t: f32,
    t1: f32,
    done: bool,
}

// One cell of a walk: the cell and its segment [ta, tb]; ok false once the walk is over.
struct DdaCell {
    cell: vec3<u32>,
    ta: f32,
    tb: f32,
    ok: bool,
}

// The closure `next` of `dda`: where the ray leaves `cell` across axis a's border.
fn dda_border(w: Dda, a: u32) -> f32 {
    if w.step[a] == 0 {
        return params.inf;
    }
    return (f32(w.cell[a] + select(0, 1, w.step[a] > 0)) - w.o[a]) / w.d[a];
}

// The start of `dda`: the cell where the ray is at t0 (clamped into the grid).
fn dda_begin(dims: vec3<u32>, o: vec3<f32>, d: vec3<f32>, t0: f32, t1: f32) -> Dda {
    var w: Dda;
    w.o = o;
    w.d = d;
    w.dims = vec3<i32>(dims);
    w.t = t0;
    w.t1 = t1;
    // Also refuses NaN intervals.
    w.done = !(t0 < t1) || is_nan(t0) || is_nan(t1) || any(dims == vec3<u32>(0u));
    if w.done {
        return w;
    }
    let p = o + d * t0;
    for (var a = 0u; a < 3u; a++) {
        // `as i64` maps NaN to 0; the clamp keeps rounding inside.
        let fl = floor(p[a]);
        var c = 0;
        if !is_nan(fl) {
            c = i32(clamp(fl, -1.0, f32(dims[a])));
        }
        w.cell[a] = clamp(c, 0, w.dims[a] - 1);
        w.step[a] = select(select(0, -1, d[a] < 0.0), 1, d[a] > 0.0);
    }
    for (var a = 0u; a < 3u; a++) {
        w.tn[a] = dda_border(w, a);
    }
    return w;
}

// One step of `dda`'s loop: the current cell and its segment, then the move across the
// border crossed first.
fn dda_next(w: ptr<function, Dda>) -> DdaCell {
    var out = DdaCell(vec3<u32>(0u), 0.0, 0.0, false);
    if (*w).done {
        return out;
    }
    let tn = (*w).tn;
    // One comparison per axis: the border crossed first.
    var axis = 2u;
    if tn.x <= tn.y && tn.x <= tn.z {
        axis = 0u;
    } else if tn.y <= tn.z {
        axis = 1u;
    }
    let te = max(min(tn[axis], (*w).t1), (*w).t);
    out = DdaCell(vec3<u32>((*w).cell), (*w).t, te, true);
    (*w).t = te;
    if tn[axis] >= (*w).t1 || is_nan(tn[axis]) {
        (*w).done = true;
        return out;
    }
    (*w).cell[axis] += (*w).step[axis];
    if (*w).cell[axis] < 0 || (*w).cell[axis] >= (*w).dims[axis] {
        (*w).done = true;
        return out;
    }
    (*w).tn[axis] = dda_border(*w, axis);
    return out;
}

// `Segment::visit`: accumulates voxel c over [ta, tb] into acc; false once compositing
// is opaque (the walk stops).
fn volume_visit(v: VolumeHeader, g: GridRay, world_len: f32, composite: bool, acc: ptr<function, VolumeSample>, c: vec3<u32>, ta: f32, tb: f32) -> bool {
    var value = 0.0;
    if v.trilinear {
        value = volume_trilinear(v, g.go + g.gd * (0.5 * (ta + tb)));
    } else {
        value = volume_voxel(v, c);
    }
    (*acc).crossed = true;
    (*acc).max = max((*acc).max, value);
    if composite {
        let e = transfer_eval(v, value);
        let alpha = 1.0 - exp(-e.w * (tb - ta) * world_len);
        (*acc).color += e.xyz * (alpha * (*acc).transmittance);
        (*acc).transmittance *= 1.0 - alpha;
        if (*acc).transmittance < 1.0 - EARLY_TERMINATION {
            return false;
        }
    }
    return true;
}

// `Volume::integrate`: integrates r through volume v over [r.t_min, t_max] into acc,
// walking every voxel or, with empty-space skipping, the coarse grid's blocks and the
// voxels of those that can contribute (compositing: some extinction in the block's value
// range; MIP: a value above the maximum so far).
fn volume_integrate(v: VolumeHeader, r: Ray, t_max: f32, composite: bool, acc: ptr<function, VolumeSample>) {
    let g = volume_grid_ray(v, r, t_max);
    if !g.ok {
        return;
    }
    // `Vec3::length`.
    let world_len = sqrt(dot(r.d, r.d));
    if !v.skip_empty {
        var w = dda_begin(v.dims, g.go, g.gd, g.t0, g.t1);
        loop {
            let s = dda_next(&w);
            if !s.ok {
                return;
            }
            // `segments`: cells crossed for a zero length hold nothing.
            if s.tb > s.ta && !volume_visit(v, g, world_len, composite, acc, s.cell, s.ta, s.tb) {
                return;
            }
        }
    }
    let scale = 1.0 / f32(SKIP_BLOCK);
    var blocks = dda_begin(v.coarse_dims, g.go * scale, g.gd * scale, g.t0, g.t1);
    loop {
        let b = dda_next(&blocks);
        if !b.ok {
            return;
        }
        if !(b.tb > b.ta) {
            continue;
        }
        let i = (b.cell.z * v.coarse_dims.y + b.cell.y) * v.coarse_dims.x + b.cell.x;
        let pair = geo[v.coarse + i / 2u];
        let range = select(pair.xy, pair.zw, (i & 1u) == 1u);
        var skip = false;
        if composite {
            skip = transfer_max_sigma(v, range.x, range.y) == 0.0;
        } else {
            skip = range.y <= (*acc).max;
        }
        if skip {
            (*acc).crossed = true;
            continue;
        }
        // The voxels of this block along [ta, tb].
        let lo = b.cell * SKIP_BLOCK;
        let sub = min(v.dims - lo, vec3<u32>(SKIP_BLOCK));
        let origin = g.go - vec3<f32>(lo);
        var w = dda_begin(sub, origin, g.gd, b.ta, b.tb);
        loop {
            let s = dda_next(&w);
            if !s.ok {
                break;
            }
            if s.tb > s.ta && !volume_visit(v, g, world_len, composite, acc, s.cell + lo, s.ta, s.tb) {
                return;
            }
        }
    }
}

// `integrator::shade_volumes`: the surface behind shaded as in ray casting, every volume
// integrated from where the ray enters it to where it leaves it or meets that surface.
// MIP: the grey level of the largest value met, through each volume's window, where it is
// brighter than the surface, channel by channel. Compositing: C + T * surface, front to
// back through the volumes in the order the ray enters them (ties by scene order).
fn shade_volumes(r: Ray, h: Hit, composite: bool) -> vec3<f32> {
    let surface = shade_cast(r, h);
    let n = params.volume_count;
    if n == 0u {
        return surface;
    }
    let t_max = select(h.t, r.t_max, h.id == NO_HIT);
    if !composite {
        var grey = -params.inf;
        for (var k = 0u; k < n; k++) {
            let v = volume_header(k);
            var acc = volume_sample_new();
            volume_integrate(v, r, t_max, false, &acc);
            if acc.crossed {
                let lo = v.window.x;
                let hi = v.window.y;
                grey = max(grey, clamp((acc.max - lo) / (hi - lo), 0.0, 1.0));
            }
        }
        if grey >= 0.0 {
            return max(surface, vec3<f32>(grey));
        }
        return surface;
    }
    // The CPU sorts the volumes by (entry t, index); here each pass picks the least pair
    // after the last one taken, which needs no array.
    var acc = volume_sample_new();
    var prev_t = 0.0;
    var prev_k = 0u;
    var started = false;
    loop {
        var best_k = n;
        var best_t = 0.0;
        for (var k = 0u; k < n; k++) {
            let g = volume_grid_ray(volume_header(k), r, t_max);
            if !g.ok {
                continue;
            }
            let after = !started || g.t0 > prev_t || (g.t0 == prev_t && k > prev_k);
            let before = best_k == n || g.t0 < best_t || (g.t0 == best_t && k < best_k);
            if after && before {
                best_k = k;
                best_t = g.t0;
            }
        }
        if best_k == n {
            break;
        }
        volume_integrate(volume_header(best_k), r, t_max, true, &acc);
        if acc.transmittance < 1.0 - EARLY_TERMINATION {
            break;
        }
        prev_t = best_t;
        prev_k = best_k;
        started = true;
    }
    return acc.color + surface * acc.transmittance;
}

// `Mode::Mip`: maximum-intensity projection (`cast_pixel` in main.wgsl, `integrator::cast_tile`, with
// `shade_volumes` as its shading).
@compute @workgroup_size(64)
fn mip_kernel(@builtin(global_invocation_id) gid: vec3<u32>) {
    cast_pixel(gid.x, MIP);
}

// `Mode::Composite`: emission-absorption compositing.
@compute @workgroup_size(64)
fn composite_kernel(@builtin(global_invocation_id) gid: vec3<u32>) {
    cast_pixel(gid.x, COMPOSITE);
}
