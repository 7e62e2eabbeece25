// Height fields: ports of raybench-geometry's `HeightField` (crates/geometry/src/
// heightfield.rs): the closest hit (`HeightField::intersect` with the min-max tree walk
// `walk_tree` and the cell test `test_cell`, triangle or bilinear cells) and the shading
// normal (`HeightField::normal`).
// `geo/heightfield.rs` lays out the record and the `geo` data and documents the port.
//
// Record: a = (header, nx, nz, kind), b = (vertices, top level, smooth, id),
// c = (xs, zs, bilinear, emitter weight), integers by their bits. geo[header .. header + 3]: the
// columns of the normals' matrix (inverse transpose of the placement); then the level
// bases (level l's first box index in component (l - 1) % 4 of entry header + 3 +
// (l - 1) / 4). xs, zs: object-space vertex x and z, four to an entry. vertices: world
// position and object-space height per vertex, row by row. Level l >= 1: a block's box as
// two entries (minimum, maximum), blocks row-major.

// The walk's stack holds HF_STACK entries (generated from `geo::heightfield::HF_STACK`): at
// most three waiting siblings per level above the cells and the block being opened, for
// the deepest tree the vertex limit allows (25 levels).

// A height-field record, decoded.
struct HField {
    header: u32,
    nx: u32,
    nz: u32,
    vertices: u32,
    top: u32,
    smooth_normals: bool,
    xs: u32,
    zs: u32,
    bilinear: bool,
}

fn hf_field(p: Prim) -> HField {
    return HField(bitcast<u32>(p.a.x), bitcast<u32>(p.a.y), bitcast<u32>(p.a.z),
        bitcast<u32>(p.b.x), bitcast<u32>(p.b.y), bitcast<u32>(p.b.z) != 0u,
        bitcast<u32>(p.c.x), bitcast<u32>(p.c.y), bitcast<u32>(p.c.z) != 0u);
}

// Vertex (i, j): world position in xyz, object-space height in w (`HeightField::vertex`,
// `height`).
fn hf_vertex(f: HField, i: u32, j: u32) -> vec4<f32> {
    return geo[f.vertices + j * (f.nx + 1u) + i];
}

// `HeightField::dims`: blocks per side of level l (level 0: single cells).
fn hf_dims(f: HField, l: u32) -> vec2<u32> {
    return vec2<u32>(((f.nx - 1u) >> l) + 1u, ((f.nz - 1u) >> l) + 1u);
}

// `HeightField::node_box` of block (l, i, j), l >= 1, entered with `SlabRay::entry`: the
// entry distance, or -1 when the ray misses it within `limit`.
fn hf_block_entry(r: Ray, f: HField, l: u32, i: u32, j: u32, limit: f32) -> f32 {
    let base = bitcast<u32>(geo[f.header + 3u + (l - 1u) / 4u][(l - 1u) % 4u]);
    let k = base + 2u * (j * hf_dims(f, l).x + i);
    return box_entry(r, geo[k].xyz, geo[k + 1u].xyz, limit);
}

// `HeightField::test_cell`, with the cell's box test of the walk first (`node_box` of level
// 0: the bounds of its four world vertices, entered within `limit`): triangle cells test
// triangles 2c = (p00, p01, p11) and 2c + 1 = (p00, p11, p10), bilinear cells the patch
// through p00, p10, p11, p01 (`cell_patch`) as sub-primitive 2c, each clipped to the best t
// so far (inclusive), the closer kept by `keep_closer` (smaller t, ties to the smaller
// sub-primitive id).
fn hf_test_cell(r: Ray, f: HField, i: u32, j: u32, t_max: f32, limit: f32, best: ptr<function, Cand>) {
    let p00 = hf_vertex(f, i, j).xyz;
    let p10 = hf_vertex(f, i + 1u, j).xyz;
    let p01 = hf_vertex(f, i, j + 1u).xyz;
    let p11 = hf_vertex(f, i + 1u, j + 1u).xyz;
    let lo = min(min(p00, p10), min(p01, p11));
    let hi = max(max(p00, p10), max(p01, p11));
    if box_entry(r, lo, hi, limit) < 0.0 {
        return;
    }
    let base = 2u * (j * f.nx + i);
    if f.bilinear {
        let clip = select(t_max, (*best).t, (*best).ok);
        let h = bilinear_hit(r.o, r.d, r.t_min, p00, p10, p11, p01);
        if h.w != 0.0 && h.x <= clip && (!(*best).ok || h.x < (*best).t || (h.x == (*best).t && base < (*best).sub)) {
            *best = Cand(h.x, h.y, h.z, base, true);
        }
        return;
    }
    for (var k = 0u; k < 2u; k++) {
        let clip = select(t_max, (*best).t, (*best).ok);
        var h: vec4<f32>;
        if k == 0u {
            h = triangle_hit(r, p00, p01, p11, clip);
        } else {
            h = triangle_hit(r, p00, p11, p10, clip);
        }
        let sub = base + k;
        if h.w != 0.0 && (!(*best).ok || h.x < (*best).t || (h.x == (*best).t && sub < (*best).sub)) {
            *best = Cand(h.x, h.y, h.z, sub, true);
        }
    }
}

// The culling limit of `walk_tree`: `cull_bound` of the best t, or the ray's t_max.
fn hf_limit(t_max: f32, best: Cand) -> f32 {
    return select(t_max, cull_bound(best.t), best.ok);
}

// `HeightField::intersect` with `walk_tree`: the closest cell triangle of `r` within
// [t_min, t_max], ties to the smaller sub-primitive id; (t, u, v) of that triangle's test
// and its id. Depth first from the top block, children nearest first by the signs of the
// object-space direction's x and z; a level-1 block's cells are tested as it is opened (the
// CPU pushes them and pops them at once: the same cells in the same order, each against the
// same limit).
fn heightfield_hit(r: Ray, p: Prim, t_max: f32) -> Cand {
    let f = hf_field(p);
    var best = miss();
    if f.top == 0u {
        hf_test_cell(r, f, 0u, 0u, t_max, t_max, &best);
        return best;
    }
    let t0 = hf_block_entry(r, f, f.top, 0u, 0u, t_max);
    if t0 < 0.0 {
        return best;
    }
    // Object-space x and z of the direction (rows 0 and 2 of the inverse placement: the
    // columns of its transpose).
    let dx = dot(geo[f.header].xyz, r.d);
    let dz = dot(geo[f.header + 2u].xyz, r.d);
    let ox = select(0u, 1u, dx < 0.0);
    let oz = select(0u, 1u, dz < 0.0);
    // The CPU's push order (far to near): (1 - ox, 1 - oz), (ox, 1 - oz), (1 - ox, oz),
    // (ox, oz).
    var order_i = array<u32, 4>(1u - ox, ox, 1u - ox, ox);
    var order_j = array<u32, 4>(1u - oz, 1u - oz, oz, oz);
    // Entries: (i, j << 5 | level) and the entry distance.
    var stack_ij: array<vec2<u32>, HF_STACK>;
    var stack_t: array<f32, HF_STACK>;
    stack_ij[0] = vec2<u32>(0u, f.top);
    stack_t[0] = t0;
    var sp = 1u;
    while sp > 0u {
        sp -= 1u;
        // Strict: skip only entries beyond the limit (an equal one may hold a tie).
        if stack_t[sp] > hf_limit(t_max, best) {
            continue;
        }
        let e = stack_ij[sp];
        let l = e.y & 31u;
        let i = e.x;
        let j = e.y >> 5u;
        let cd = hf_dims(f, l - 1u);
        if l == 1u {
            // The cells, nearest first (the CPU's pop order), each against the limit of its
            // turn.
            for (var k = 0u; k < 4u; k++) {
                let ci = 2u * i + order_i[3u - k];
                let cj = 2u * j + order_j[3u - k];
                if ci < cd.x && cj < cd.y {
                    hf_test_cell(r, f, ci, cj, t_max, hf_limit(t_max, best), &best);
                }
            }
            continue;
        }
        let lim = hf_limit(t_max, best);
        for (var k = 0u; k < 4u; k++) {
            let ci = 2u * i + order_i[k];
            let cj = 2u * j + order_j[k];
            if ci < cd.x && cj < cd.y {
                let ct = hf_block_entry(r, f, l - 1u, ci, cj, lim);
                if ct >= 0.0 {
                    stack_ij[sp] = vec2<u32>(ci, (cj << 5u) | (l - 1u));
                    stack_t[sp] = ct;
                    sp += 1u;
                }
            }
        }
    }
    return best;
}

// Object-space x of vertex column i (`HeightField::x`).
fn hf_x(f: HField, i: u32) -> f32 {
    return geo[f.xs + i / 4u][i % 4u];
}

// Object-space z of vertex row j (`HeightField::z`).
fn hf_z(f: HField, j: u32) -> f32 {
    return geo[f.zs + j / 4u][j % 4u];
}

// `HeightField::object_normal`: the object-space vertex normal from central (one-sided at
// the borders) differences of the heights.
fn hf_object_normal(f: HField, i: u32, j: u32) -> vec3<f32> {
    let i0 = select(i - 1u, 0u, i == 0u);
    let i1 = min(i + 1u, f.nx);
    let j0 = select(j - 1u, 0u, j == 0u);
    let j1 = min(j + 1u, f.nz);
    let dhdx = (hf_vertex(f, i1, j).w - hf_vertex(f, i0, j).w) / (hf_x(f, i1) - hf_x(f, i0));
    let dhdz = (hf_vertex(f, i, j1).w - hf_vertex(f, i, j0).w) / (hf_z(f, j1) - hf_z(f, j0));
    return normalize_or(vec3<f32>(-dhdx, 1.0, -dhdz), vec3<f32>(0.0, 1.0, 0.0));
}

// `HeightField::normal`. Bilinear cells: the negated patch normal at the hit's (u, v) (dP/dv
// x dP/du turns as the triangles' winding does), or with smooth normals the bilinear blend
// of the four vertex normals, carried and oriented as below. Triangle cells: the triangle's
// geometric normal
// (`Triangle::normal`), or with smooth normals the barycentric blend (weights 1 - u - v, u,
// v) of its vertices' object-space normals carried to world space by the inverse transpose
// of the placement, normalised (the geometric normal where that fails) and on the geometric
// normal's side (`oriented_world_normal`).
fn heightfield_normal(r: Ray, p: Prim, h: Hit) -> vec3<f32> {
    let f = hf_field(p);
    let cell = h.sub / 2u;
    let i = cell % f.nx;
    let j = cell / f.nx;
    if f.bilinear {
        let q00 = hf_vertex(f, i, j).xyz;
        let q10 = hf_vertex(f, i + 1u, j).xyz;
        let q11 = hf_vertex(f, i + 1u, j + 1u).xyz;
        let q01 = hf_vertex(f, i, j + 1u).xyz;
        let geometric = -bilinear_normal(q00, q10, q11, q01, h.u, h.v);
        if !f.smooth_normals {
            return geometric;
        }
        var n = hf_object_normal(f, i, j) * ((1.0 - h.u) * (1.0 - h.v));
        n += hf_object_normal(f, i + 1u, j) * (h.u * (1.0 - h.v));
        n += hf_object_normal(f, i + 1u, j + 1u) * (h.u * h.v);
        n += hf_object_normal(f, i, j + 1u) * ((1.0 - h.u) * h.v);
        return hf_oriented_world_normal(f, n, geometric);
    }
    let odd = (h.sub & 1u) != 0u;
    // Vertices of the triangle: (i, j), (i, j + 1), (i + 1, j + 1) for the even one,
    // (i, j), (i + 1, j + 1), (i + 1, j) for the odd one.
    let i1 = select(i, i + 1u, odd);
    let j1 = j + 1u;
    let i2 = i + 1u;
    let j2 = select(j + 1u, j, odd);
    let v0 = hf_vertex(f, i, j).xyz;
    let v1 = hf_vertex(f, i1, j1).xyz;
    let v2 = hf_vertex(f, i2, j2).xyz;
    let geometric = normalize_or(cross(v1 - v0, v2 - v0), vec3<f32>(0.0, 1.0, 0.0));
    if !f.smooth_normals {
        return geometric;
    }
    var n = vec3<f32>(0.0);
    n += hf_object_normal(f, i, j) * (1.0 - h.u - h.v);
    n += hf_object_normal(f, i1, j1) * h.u;
    n += hf_object_normal(f, i2, j2) * h.v;
    return hf_oriented_world_normal(f, n, geometric);
}

// `HeightField::oriented_world_normal`: the object-space normal n carried to world space by
// the inverse transpose of the placement, normalised (the geometric normal where that
// fails) and on the geometric normal's side.
fn hf_oriented_world_normal(f: HField, n: vec3<f32>, geometric: vec3<f32>) -> vec3<f32> {
    let world = geo[f.header].xyz * n.x + geo[f.header + 1u].xyz * n.y + geo[f.header + 2u].xyz * n.z;
    let nw = normalize_or(world, geometric);
    if dot(nw, geometric) < 0.0 {
        return -nw;
    }
    return nw;
}
