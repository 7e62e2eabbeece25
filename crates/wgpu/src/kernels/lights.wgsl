// Lights, environment, textures and shading attributes: ports of raybench-core's
// `emitters`, `environment`, `texture` and `attributes` (and `Scene::shading`), reading the
// tables `crates/wgpu/src/shading.rs` appends to `geo` (its documentation gives the layout
// and the f32 formulation).

// Float `i` of `geo` (four to an entry).
fn shading_f32(i: u32) -> f32 {
    return geo[i / 4u][i % 4u];
}

// f32's `rem_euclid(1.0)` (Rust: the truncated remainder, made non-negative).
fn rem_euclid1(x: f32) -> f32 {
    let r = x - trunc(x);
    return select(r, r + 1.0, r < 0.0);
}

// glam's `unit_or_zero`: the unit vector, or zero when there is none.
fn unit_or_zero(v: vec3<f32>) -> vec3<f32> {
    return normalize_or(v, vec3<f32>(0.0));
}

// ---------------------------------------------------------------------------------------
// Shading attributes (`ShadingAttributes::at`) and textures (`Texture::sample`).

// What the attributes say at a point (`AttributesAt`): `has_*` false where they say nothing.
struct AttributesAt {
    normal: vec3<f32>,
    has_normal: bool,
    uv: vec2<f32>,
    has_uv: bool,
}

// `Scene::attributes_at`: primitive `id`'s vertex normals and texture coordinates at
// barycentric weights u (vertex 1) and v (vertex 2); an instanced primitive's from its
// mesh's table, the normal carried to the world by the instance's normal matrix
// (`Scene::instanced_attributes_at`, `Instance::world_normal`).
fn attributes_at(id: u32, u: f32, v: f32) -> AttributesAt {
    if !is_instanced(id) {
        return table_attributes(params.attr_table, params.attr_count, id, u, v);
    }
    return instanced_attributes(instance_of(id), id, u, v);
}

// `attributes_at` for a hit: an instanced hit already knows its instance (`Hit::inst`), so
// the search by base id is left out.
fn hit_attributes(h: Hit) -> AttributesAt {
    if HAS_INSTANCES && h.inst != NO_HIT {
        return instanced_attributes(h.inst, h.id, h.u, h.v);
    }
    return table_attributes(params.attr_table, params.attr_count, h.id, h.u, h.v);
}

// `Scene::instanced_attributes_at`: instanced primitive `id` of instance `k`.
fn instanced_attributes(k: u32, id: u32, u: f32, v: f32) -> AttributesAt {
    let rec = instance_record(k);
    let table = bitcast<u32>(geo[rec + 5u].w);
    let count = bitcast<u32>(geo[rec + 4u].w);
    var a = table_attributes(table, count, id - bitcast<u32>(geo[rec + 1u].w), u, v);
    if a.has_normal {
        let m = mat3x3<f32>(geo[rec + 4u].xyz, geo[rec + 5u].xyz, geo[rec + 6u].xyz);
        a.normal = normalize_or(m * a.normal, a.normal);
    }
    return a;
}

// `ShadingAttributes::at` over the table at float index `table` (`NO_ENTRY`: none) of
// `count` primitive ids (`crates/wgpu/src/shading.rs`).
fn table_attributes(table: u32, count: u32, id: u32, u: f32, v: f32) -> AttributesAt {
    var a = AttributesAt(vec3<f32>(0.0), false, vec2<f32>(0.0), false);
    if table == NO_ENTRY || id >= count {
        return a;
    }
    let rec = bitcast<u32>(shading_f32(table + id));
    if rec == 0u {
        return a;
    }
    let r0 = geo[rec];
    let r1 = geo[rec + 1u];
    let r2 = geo[rec + 2u];
    let r3 = geo[rec + 3u];
    let flags = bitcast<u32>(r3.w);
    let w = 1.0 - u - v;
    if (flags & 1u) != 0u {
        // Opposite normals may cancel: then the geometric normal.
        a.normal = unit_or_zero(r0.xyz * w + r1.xyz * u + r2.xyz * v);
        a.has_normal = any(a.normal != vec3<f32>(0.0));
    }
    if (flags & 2u) != 0u {
        a.uv = vec2<f32>(r0.w, r1.w) * w + vec2<f32>(r2.w, r3.x) * u + vec2<f32>(r3.y, r3.z) * v;
        a.has_uv = true;
    }
    return a;
}

// `Wrap::index`: texel index `i` of an axis of `n` texels wrapped by mode `mode`
// (`shading::wrap_code`).
fn texel_wrap(mode: u32, i: i32, n: i32) -> i32 {
    if mode == 1u {
        return clamp(i, 0, n - 1);
    }
    if mode == 2u {
        let m = 2 * n;
        let k = ((i % m) + m) % m;
        return select(k, m - 1 - k, k >= n);
    }
    return ((i % n) + n) % n;
}

// `Texture::texel`: texel (i, j) of texture `t` (its table entry), indices wrapped.
fn texture_texel(t: vec4<f32>, i: i32, j: i32) -> vec3<f32> {
    let w = i32(bitcast<u32>(t.y));
    let h = i32(bitcast<u32>(t.z));
    let wrap = bitcast<u32>(t.w);
    let x = texel_wrap(wrap & 0xffu, i, w);
    let y = texel_wrap((wrap >> 8u) & 0xffu, j, h);
    return geo[bitcast<u32>(t.x) + u32(y * w + x)].xyz;
}

// One more than `i`, saturating (the CPU's `saturating_add`).
fn texel_next(i: i32) -> i32 {
    return select(i + 1, i, i == 2147483647);
}

// `Texture::sample`: texture `k` at `uv`, bilinearly filtered. The CPU forms the texel
// coordinate in f64; here in f32 (error about 2^-24 of uv x size in the blend weights).
// WGSL's f32 to i32 conversion saturates, as Rust's does; a non-finite coordinate reads
// index 0 of its axis.
fn texture_sample(k: u32, uv: vec2<f32>) -> vec3<f32> {
    let t = geo[params.tex_table + k];
    let x = uv.x * f32(bitcast<u32>(t.y)) - 0.5;
    let y = uv.y * f32(bitcast<u32>(t.z)) - 0.5;
    let x0 = floor(x);
    let y0 = floor(y);
    let fx = x - x0;
    let fy = y - y0;
    let i = select(0, i32(x0), is_finite(x0));
    let j = select(0, i32(y0), is_finite(y0));
    let top = texture_texel(t, i, j) * (1.0 - fx) + texture_texel(t, texel_next(i), j) * fx;
    let j1 = texel_next(j);
    let bottom = texture_texel(t, i, j1) * (1.0 - fx) + texture_texel(t, texel_next(i), j1) * fx;
    let v = top * (1.0 - fy) + bottom * fy;
    if is_finite(v.x) && is_finite(v.y) && is_finite(v.z) {
        return v;
    }
    return geo[bitcast<u32>(t.x)].xyz;
}

// `Scene::texel`: texture `k` at `uv`, or 1 without texture or coordinates.
fn texel_or_one(k: u32, a: AttributesAt) -> vec3<f32> {
    if k == NO_ENTRY || !a.has_uv {
        return vec3<f32>(1.0);
    }
    return texture_sample(k, a.uv);
}

// `SurfaceShading`: the unit shading normal on the geometric normal's side, the diffuse
// colour (checkerboard and texture), the base colour times its texture (ray casting's) and
// the emitted radiance (emission texture applied).
struct SurfaceShading {
    normal: vec3<f32>,
    albedo: vec3<f32>,
    base_color: vec3<f32>,
    emission: vec3<f32>,
}

// `Scene::shading` at hit `h` of primitive material `m`, geometric normal `gn`, point `p`.
fn scene_shading(h: Hit, m: Material, gn: vec3<f32>, p: vec3<f32>) -> SurfaceShading {
    let a = hit_attributes(h);
    var normal = gn;
    if a.has_normal {
        normal = select(a.normal, -a.normal, dot(a.normal, gn) < 0.0);
    }
    let tex = texel_or_one(m.base_texture, a);
    return SurfaceShading(normal, albedo_at(m, p) * tex, m.base_color * tex, m.emission * texel_or_one(m.emission_texture, a));
}

// `Scene::emission_at`: the radiance primitive `id` emits at surface parameters (u, v).
fn emission_at(id: u32, u: f32, v: f32) -> vec3<f32> {
    let m = material_of(id);
    if m.emission_texture == NO_ENTRY {
        return m.emission;
    }
    return m.emission * texel_or_one(m.emission_texture, attributes_at(id, u, v));
}

// ---------------------------------------------------------------------------------------
// The environment map (`Environment`).

// `Environment::to_map`: world direction to map direction.
fn env_to_map(d: vec3<f32>) -> vec3<f32> {
    let c = params.env_cos;
    let s = params.env_sin;
    return vec3<f32>(c * d.x - s * d.z, d.y, s * d.x + c * d.z);
}

// `Environment::to_world`: map direction to world direction.
fn env_to_world(d: vec3<f32>) -> vec3<f32> {
    let c = params.env_cos;
    let s = params.env_sin;
    return vec3<f32>(c * d.x + s * d.z, d.y, -s * d.x + c * d.z);
}

// `Environment::texel_of`: column, row and sin θ of unit map direction `d`.
struct EnvTexel {
    x: u32,
    y: u32,
    sin: f32,
}

fn env_texel_of(d: vec3<f32>) -> EnvTexel {
    let u = rem_euclid1(atan2(d.z, d.x) / TAU);
    let cos = clamp(d.y, -1.0, 1.0);
    let v = acos(cos) / PI;
    let x = min(u32(u * f32(params.env_width)), params.env_width - 1u);
    let y = min(u32(v * f32(params.env_height)), params.env_height - 1u);
    return EnvTexel(x, y, sqrt(max(1.0 - cos * cos, 0.0)));
}

// `Scene::background_along`: the radiance arriving along a ray of direction `dir` that
// hits nothing (`Environment::radiance`, or the constant background).
fn background_along(dir: vec3<f32>) -> vec3<f32> {
    if params.env_width == 0u {
        return params.background;
    }
    let d = unit_or_zero(dir);
    if all(d == vec3<f32>(0.0)) {
        return vec3<f32>(0.0);
    }
    let t = env_texel_of(env_to_map(d));
    return geo[params.env_first + t.y * params.env_width + t.x].xyz;
}

// `Environment::texel_pdf`: the density of texel (x, y) per solid angle at sin θ = `sin`
// (the texel's density over (u, v), precomputed in f64, over the Jacobian 2π² sin θ).
fn env_texel_pdf(x: u32, y: u32, sin: f32) -> f32 {
    if sin <= 0.0 {
        return 0.0;
    }
    let pdf_uv = geo[params.env_first + y * params.env_width + x].w;
    return pdf_uv / (2.0 * PI * PI * sin);
}

// `Environment::pdf`: the density with which `env_sample` picks world direction `dir`.
fn env_pdf(dir: vec3<f32>) -> f32 {
    let d = unit_or_zero(dir);
    if all(d == vec3<f32>(0.0)) {
        return 0.0;
    }
    let t = env_texel_of(env_to_map(d));
    return env_texel_pdf(t.x, t.y, t.sin);
}

// `environment::pick`: the interval of the cumulative table of `n` floats from float index
// `first` holding `goal`, and the position of `goal` in it, in [0, 1).
struct Picked {
    i: u32,
    frac: f32,
}

fn cdf_pick(first: u32, n: u32, goal: f32) -> Picked {
    var lo = 0u;
    var hi = n;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if shading_f32(first + mid) <= goal {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    let i = min(lo, n - 1u);
    var below = 0.0;
    if i > 0u {
        below = shading_f32(first + i - 1u);
    }
    let w = shading_f32(first + i) - below;
    var frac = 0.5;
    if w > 0.0 {
        frac = (goal - below) / w;
    }
    // `1 - f32::EPSILON / 2`.
    return Picked(i, clamp(frac, 0.0, 0.99999994));
}

// `Environment::sample`: a world direction from the piecewise-constant distribution, its
// radiance and solid-angle pdf; `ok` false for a black map or a pole.
struct EnvSample {
    wi: vec3<f32>,
    radiance: vec3<f32>,
    pdf: f32,
    ok: bool,
}

fn env_sample(u0: f32, u1: f32) -> EnvSample {
    var s = EnvSample(vec3<f32>(0.0), vec3<f32>(0.0), 0.0, false);
    let w = params.env_width;
    let h = params.env_height;
    let total = shading_f32(params.env_cdf + h - 1u);
    if !(total > 0.0) {
        return s;
    }
    let py = cdf_pick(params.env_cdf, h, u0 * total);
    let row = params.env_cdf + h + py.i * w;
    let px = cdf_pick(row, w, u1 * shading_f32(row + w - 1u));
    let u = (f32(px.i) + px.frac) / f32(w);
    let v = (f32(py.i) + py.frac) / f32(h);
    let theta = v * PI;
    let phi = u * TAU;
    let sin_t = sin(theta);
    let d = vec3<f32>(sin_t * cos(phi), cos(theta), sin_t * sin(phi));
    let pdf = env_texel_pdf(px.i, py.i, sin_t);
    if !(pdf > 0.0) || !is_finite(pdf) {
        return s;
    }
    s.wi = env_to_world(d);
    s.radiance = geo[params.env_first + py.i * w + px.i].xyz;
    s.pdf = pdf;
    s.ok = true;
    return s;
}

// `Emitters::pdf_environment`: the density with which light sampling picks the environment
// along unit direction `dir`.
fn pdf_environment(dir: vec3<f32>) -> f32 {
    if params.env_width == 0u || !(params.env_choice > 0.0) {
        return 0.0;
    }
    return env_pdf(dir) * params.env_choice;
}

// ---------------------------------------------------------------------------------------
// Emitters as lights (`Emitters`).

// Entry `e` of the emitter table: the bounding sphere, the cumulative weight, the choice
// probability, a triangle's area.
struct EmitterInfo {
    center: vec3<f32>,
    radius: f32,
    cdf: f32,
    choice: f32,
    area: f32,
}

fn emitter_info(e: u32) -> EmitterInfo {
    let a = geo[params.emitter_table + 2u * e];
    let b = geo[params.emitter_table + 2u * e + 1u];
    return EmitterInfo(a.xyz, a.w, b.x, b.y, b.z);
}

// `Emitters::pick`: the emitter entry whose interval of the cumulative weights holds
// u x total, `emitter_count` for the environment, NO_ENTRY when there is no light.
fn pick_light(u: f32) -> u32 {
    let total = params.light_total;
    if !(total > 0.0) {
        return NO_ENTRY;
    }
    let target_cdf = u * total;
    var lo = 0u;
    var hi = params.emitter_count;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if emitter_info(mid).cdf <= target_cdf {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    if lo < params.emitter_count {
        return lo;
    }
    if params.env_choice > 0.0 {
        return params.emitter_count;
    }
    if params.emitter_count > 0u {
        return params.emitter_count - 1u;
    }
    return NO_ENTRY;
}

// `Emitters::contains`: the emitter entry of primitive `id` (binary search over the
// emitter list's ascending ids), `emitter_count` when it is not a light.
fn emitter_of(id: u32) -> u32 {
    var lo = 0u;
    var hi = params.emitter_count;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if bitcast<u32>(prims[params.emitter_first + mid].b.w) < id {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    if lo < params.emitter_count && bitcast<u32>(prims[params.emitter_first + lo].b.w) == id {
        return lo;
    }
    return params.emitter_count;
}

// `emitters::Cone`: the cone of directions from a point towards a sphere outside it.
struct LightCone {
    axis: vec3<f32>,
    sin2_max: f32,
    one_minus_cos: f32,
    ok: bool,
}

// `Cone::towards`: `ok` false from inside the sphere.
fn light_cone_towards(origin: vec3<f32>, center: vec3<f32>, radius: f32) -> LightCone {
    var c = LightCone(vec3<f32>(0.0), 0.0, 0.0, false);
    let to = center - origin;
    let d2 = dot(to, to);
    let r2 = radius * radius;
    if !(d2 > r2 && is_finite(d2)) {
        return c;
    }
    c.sin2_max = r2 / d2;
    let cos_max = sqrt(max(1.0 - c.sin2_max, 0.0));
    c.axis = to / sqrt(d2);
    c.one_minus_cos = c.sin2_max / (1.0 + cos_max);
    c.ok = true;
    return c;
}

// `Cone::pdf` (infinite for a cone too thin for f32: WGSL leaves 1/0 undefined).
fn light_cone_pdf(c: LightCone) -> f32 {
    let s = TAU * c.one_minus_cos;
    if !(s > 0.0) {
        return params.inf;
    }
    return 1.0 / s;
}

// `Cone::theta`: (cos θ, sin² θ) of a uniform direction in the cone.
fn light_cone_theta(c: LightCone, u: f32) -> vec2<f32> {
    let one_minus = u * c.one_minus_cos;
    return vec2<f32>(1.0 - one_minus, one_minus * (2.0 - one_minus));
}

// `Cone::direction`: the unit vector at (cos, sin) from the axis (flipped by `sign`) and
// azimuth `phi`.
fn light_cone_direction(c: LightCone, cos_a: f32, sin_a: f32, phi: f32, sign: f32) -> vec3<f32> {
    let tb = frame_basis(c.axis);
    return normalize(tb[0] * (sin_a * cos(phi)) + tb[1] * (sin_a * sin(phi)) + c.axis * (sign * cos_a));
}

// `LightSample` (the emitters' `sample`): unit direction, distance (infinite for the
// environment), radiance, solid-angle pdf with the light's choice; `ok` false for none.
struct LightSampleOut {
    wi: vec3<f32>,
    dist: f32,
    radiance: vec3<f32>,
    pdf: f32,
    ok: bool,
}

// `Emitters::sample`: a light chosen with `u_light`, a point or direction on it from
// (u0, u1), seen from `origin` (already offset from its surface). Triangles by area,
// spheres by their cone, every other bounded kind by the cone of its bounding sphere and
// its own intersection routine (`prim_hit` on the emitter list's copy of its record).
fn sample_light(origin: vec3<f32>, u_light: f32, u0: f32, u1: f32) -> LightSampleOut {
    var out = LightSampleOut(vec3<f32>(0.0), 0.0, vec3<f32>(0.0), 0.0, false);
    let e = pick_light(u_light);
    if e == NO_ENTRY {
        return out;
    }
    if e == params.emitter_count {
        let s = env_sample(u0, u1);
        if !s.ok {
            return out;
        }
        return LightSampleOut(s.wi, params.inf, s.radiance, s.pdf * params.env_choice, true);
    }
    let k = params.emitter_first + e;
    let p = prims[k];
    let id = bitcast<u32>(p.b.w);
    let info = emitter_info(e);
    var y: vec3<f32>;
    var normal: vec3<f32>;
    var uv: vec2<f32>;
    var pdf: f32;
    switch bitcast<u32>(p.a.w) {
        case KIND_TRIANGLE: {
            let s = sqrt(u0);
            let w0 = 1.0 - s;
            let w1 = u1 * s;
            y = triangle_point(p.a.xyz, p.b.xyz, p.c.xyz, u0, u1);
            normal = normalize_or(cross(p.b.xyz - p.a.xyz, p.c.xyz - p.a.xyz), vec3<f32>(0.0, 1.0, 0.0));
            let to = y - origin;
            let d2 = dot(to, to);
            let cos_y = -dot(normal, to) / sqrt(d2);
            if !(cos_y > 0.0 && d2 > 0.0) {
                return out;
            }
            uv = vec2<f32>(w1, 1.0 - w0 - w1);
            pdf = d2 / (cos_y * info.area);
        }
        case KIND_SPHERE: {
            let cone = light_cone_towards(origin, p.a.xyz, p.c.x);
            if !cone.ok {
                return out;
            }
            let th = light_cone_theta(cone, u0);
            // pbrt-v4: the angle alpha at the centre between the axis and the point.
            let sin_max = sqrt(cone.sin2_max);
            let cos_alpha = th.y / sin_max + th.x * sqrt(max(1.0 - th.y / cone.sin2_max, 0.0));
            let sin_alpha = sqrt(max(1.0 - cos_alpha * cos_alpha, 0.0));
            normal = light_cone_direction(cone, cos_alpha, sin_alpha, TAU * u1, -1.0);
            y = p.a.xyz + normal * p.c.x;
            // Spheres have no shading attributes: their (u, v) reads no texture.
            uv = vec2<f32>(0.0);
            pdf = light_cone_pdf(cone);
        }
        case KIND_PLANE: {
            return out;
        }
        default: {
            let cone = light_cone_towards(origin, info.center, info.radius);
            if !cone.ok {
                return out;
            }
            let th = light_cone_theta(cone, u0);
            let wi = light_cone_direction(cone, th.x, sqrt(max(th.y, 0.0)), TAU * u1, 1.0);
            let r = ray_new(origin, wi);
            let c = prim_hit(r, k, params.inf);
            if !c.ok {
                return out;
            }
            normal = hit_normal(r, Hit(c.t, id, c.u, c.v, k, c.sub, NO_HIT));
            y = r.o + r.d * c.t;
            uv = vec2<f32>(c.u, c.v);
            pdf = light_cone_pdf(cone);
        }
    }
    let to = y - origin;
    let dist = length(to);
    let wi = to / dist;
    // One-sided: the light's front faces the reference point.
    if !(dot(normal, wi) < 0.0 && dist > 0.0 && is_finite(dist)) {
        return out;
    }
    pdf = pdf * info.choice;
    if !(pdf > 0.0) || !is_finite(pdf) {
        return out;
    }
    return LightSampleOut(wi, dist, emission_at(id, uv.x, uv.y), pdf, true);
}

// `Emitters::pdf_hit`: the density with which `sample_light` from `origin` would have
// produced the hit of primitive `id` (record `prims[k]`) at `p` with unit geometric normal
// `normal`; 0 when it would not.
fn pdf_light_hit(origin: vec3<f32>, id: u32, k: u32, p: vec3<f32>, normal: vec3<f32>) -> f32 {
    let e = emitter_of(id);
    if e == params.emitter_count {
        return 0.0;
    }
    let info = emitter_info(e);
    if !(info.choice > 0.0) {
        return 0.0;
    }
    var pdf = 0.0;
    switch bitcast<u32>(prims[k].a.w) {
        case KIND_TRIANGLE: {
            let to = p - origin;
            let d2 = dot(to, to);
            let cos_y = abs(dot(normal, to)) / sqrt(d2);
            if is_nan(cos_y) || cos_y <= 0.0 {
                return 0.0;
            }
            pdf = d2 / (cos_y * info.area);
        }
        case KIND_PLANE: {
            return 0.0;
        }
        default: {
            // A sphere's own sphere is its bounding sphere in the table.
            let cone = light_cone_towards(origin, info.center, info.radius);
            if !cone.ok {
                return 0.0;
            }
            pdf = light_cone_pdf(cone);
        }
    }
    // A density that overflowed is one `sample_light` discards: BSDF sampling alone then.
    pdf = pdf * info.choice;
    return select(0.0, pdf, is_finite(pdf));
}
