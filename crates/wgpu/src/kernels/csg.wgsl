// CSG trees (`geo/csg.rs` lays out the record and the `geo` data): not ported yet.

fn csg_hit(r: Ray, p: Prim, t_max: f32) -> Cand {
    return miss();
}

fn csg_normal(r: Ray, p: Prim, h: Hit) -> vec3<f32> {
    return vec3<f32>(0.0, 1.0, 0.0);
}
