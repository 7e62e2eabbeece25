//! What Rust shares with the kernels (`kernels/*.wgsl`), below every other module of the
//! crate: the `#[repr(C)]` + `bytemuck::Pod` records laid out as WGSL lays out the
//! matching structs, the `geo` buffer's type, the numbers the kernels give primitive,
//! material and light kinds, and the pipeline-override constants. `wgsl_constants`
//! (`constants.rs`) writes the numbers into the kernels' source; the modules that fill the buffers
//! (`data.rs`, `geo/`, `shading.rs`, `instances.rs`, `volume.rs`) read them from here.

use bytemuck::{Pod, Zeroable};
use raybench_core::limits::MAX_DEPTH;
use raybench_core::{PrimitiveKind, Scene};

/// The override constant of [`Features`] that says whether a scene has instances.
pub(crate) const HAS_INSTANCES: &str = "HAS_INSTANCES";

/// The kernels' names of a primitive kind: its `KIND_*` constant (whose value is
/// [`kind_number`]) and, for the kinds whose routines a pipeline carries only when its scene
/// holds them, the `HAS_*` pipeline-override constant ([`Features`]); triangles, spheres and
/// planes are always carried.
#[must_use]
pub(crate) const fn kind_names(kind: PrimitiveKind) -> (&'static str, Option<&'static str>) {
    match kind {
        PrimitiveKind::Triangle => ("KIND_TRIANGLE", None),
        PrimitiveKind::Sphere => ("KIND_SPHERE", None),
        PrimitiveKind::Plane => ("KIND_PLANE", None),
        PrimitiveKind::HeightField => ("KIND_HEIGHTFIELD", Some("HAS_HEIGHTFIELD")),
        PrimitiveKind::Csg => ("KIND_CSG", Some("HAS_CSG")),
        PrimitiveKind::Bezier => ("KIND_BEZIER", Some("HAS_BEZIER")),
        PrimitiveKind::Sdf => ("KIND_SDF", Some("HAS_SDF")),
    }
}

/// A primitive kind as the kernels number it (`KIND_*`, in a record's `a.w`): its
/// [`PrimitiveKind::index`].
#[must_use]
pub(crate) const fn kind_number(kind: PrimitiveKind) -> u32 {
    kind.index()
}

/// Material kinds as the shaders number them (`MAT_*`).
pub(crate) const MAT_DIFFUSE: u32 = 0;
/// See [`MAT_DIFFUSE`].
pub(crate) const MAT_MIRROR: u32 = 1;
/// See [`MAT_DIFFUSE`].
pub(crate) const MAT_GLASS: u32 = 2;
/// Light kinds as the shaders number them (`LIGHT_*`).
pub(crate) const LIGHT_POINT: u32 = 0;
/// See [`LIGHT_POINT`].
pub(crate) const LIGHT_DIRECTIONAL: u32 = 1;
/// Set in `prim_info` for primitives that next-event estimation samples (`EMITTER_BIT`).
pub(crate) const EMITTER_BIT: u32 = 1 << 31;
/// Entries of the kernels' traversal stack (`STACK_SIZE`): near-child-first traversal
/// holds at most one entry per level plus one, so the BVH's depth must stay below.
pub(crate) const STACK_SIZE: u32 = 64;
/// Whitted's depth-first stack: a popped segment pushes at most two children, so the stack
/// holds at most one entry per bounce plus one, plus one for the camera segment.
pub(crate) const WHITTED_STACK: u32 = MAX_DEPTH + 2;

/// No entry (a texture index, an attribute record).
pub(crate) const NONE: u32 = u32::MAX;

/// The `geo` buffer being filled (the kinds' own data, `geo/`, and the shading, instance
/// and volume tables): 16-byte entries (`array<vec4<f32>>` in WGSL); integers
/// are stored by their bits.
pub(crate) type Geo = Vec<[f32; 4]>;

/// Index of the next entry of `geo`, as the kernels address it.
///
/// # Errors
/// When the buffer has grown past `u32` entries.
pub(crate) fn next_index(geo: &Geo) -> Result<u32, String> {
    u32::try_from(geo.len()).map_err(|_| "the GPU's primitive data exceeds 2^32 entries".into())
}

/// Per-dispatch parameters: 256 bytes, one 256-byte-aligned slot per dispatch of a frame.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Params {
    /// Camera origin.
    pub origin: [f32; 3],
    /// `1 / width`.
    pub inv_width: f32,
    /// Unit view direction.
    pub forward: [f32; 3],
    /// `1 / height`.
    pub inv_height: f32,
    /// Right, scaled to half the image width.
    pub right: [f32; 3],
    /// Seed of the random numbers.
    pub seed: u32,
    /// Up, scaled to half the image height.
    pub up: [f32; 3],
    /// Samples per pixel of the frame.
    pub spp: u32,
    /// Background radiance.
    pub background: [f32; 3],
    /// Maximum bounces.
    pub max_depth: u32,
    /// Light direction of ray-casting shading.
    pub cast_light: [f32; 3],
    /// `f32::INFINITY` (WGSL has no infinite literal).
    pub inf: f32,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// First row of the band held by the output buffer.
    pub band_y0: u32,
    /// First row of this dispatch.
    pub y0: u32,
    /// Rows of this dispatch.
    pub rows: u32,
    /// First sample of this dispatch.
    pub s0: u32,
    /// One past its last sample.
    pub s1: u32,
    /// Nodes of the BVH2 or the CWBVH (0: no bounded primitive).
    pub node_count: u32,
    /// Index of the first unbounded primitive (planes) in the primitive buffer.
    pub unbounded_first: u32,
    /// How many.
    pub unbounded_count: u32,
    /// Index of the first entry of the emitter list in the primitive buffer.
    pub emitter_first: u32,
    /// How many.
    pub emitter_count: u32,
    /// Index of the first light in the shading buffer (after the materials).
    pub light_first: u32,
    /// How many lights.
    pub light_count: u32,
    /// Total choice weight of the emitters (area x luminance, `Emitters::total_weight`);
    /// the kernels choose lights with [`Params::light_total`], which adds the environment.
    pub emitter_weight: f32,
    /// Explicit rays in this dispatch.
    pub ray_count: u32,
    /// [`raybench_core::FAR_SCALE`] of the conservative slab test.
    pub far_scale: f32,
    /// [`raybench_core::CULL_SLACK`] of the early exits.
    pub cull_slack: f32,
    /// 1 when `path` mode samples the emitters (`LightSampling::Mis` and at least one).
    pub mis: u32,
    /// Instances ([`Instancing`]; 0: none).
    pub instance_count: u32,
    /// Index of the top level's root in the BVH2 node buffer.
    pub top_root: u32,
    /// Index in `geo` of the first instance record.
    pub instance_records: u32,
    /// Index in `geo` of the top level's order list.
    pub instance_order: u32,
    /// Ids below this are the flat part's.
    pub flat_count: u32,
    /// Lights, environment, textures, attributes: where their tables are in `geo`.
    pub shading: ShadingBlock,
    /// The volume modes: index of the volume table in `geo` (`volume.rs`).
    pub volume_first: u32,
    /// How many volumes (0 where they were not uploaded).
    pub volume_count: u32,
    /// Padding to a multiple of 16 bytes.
    pub volume_pad: [u32; 2],
}

const _: () = assert!(std::mem::size_of::<Params>() == 256);

/// 32-byte BVH2 node, raybench-bvh's [`raybench_bvh::Node`] (Wald's layout).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuNode {
    /// Box minimum.
    pub min: [f32; 3],
    /// Leaf: first index into the primitive buffer. Interior: the second child.
    pub first_or_right: u32,
    /// Box maximum.
    pub max: [f32; 3],
    /// Leaf: primitive count. Interior: 0.
    pub count: u32,
}

const _: () = assert!(std::mem::size_of::<GpuNode>() == 32);

/// 48-byte primitive: `a.w` holds the kind, `b.w` the primitive id (as bits). Triangle:
/// vertices in `a`, `b`, `c`; sphere:
/// centre `a`, radius `c.x`; plane: point `a`, unit normal `c`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuPrim {
    /// First vector.
    pub a: [f32; 4],
    /// Second vector.
    pub b: [f32; 4],
    /// Third vector.
    pub c: [f32; 4],
}

const _: () = assert!(std::mem::size_of::<GpuPrim>() == 48);

/// 32-byte output record: colour sum and `t` (pixels) or `t, u, v` (explicit rays), and
/// the primitive id.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuOut {
    /// Colour and `t`, or `t, u, v`.
    pub v: [f32; 4],
    /// Primitive id ([`raybench_core::NO_HIT`] for a miss).
    pub id: u32,
    /// Explicit rays: the sub-primitive id.
    pub sub: u32,
    /// Padding.
    pub pad: [u32; 2],
}

const _: () = assert!(std::mem::size_of::<GpuOut>() == 32);

/// 32-byte explicit ray: origin and `t_min`, direction and `t_max`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuRay {
    /// Origin and `t_min`.
    pub o: [f32; 4],
    /// Direction and `t_max`.
    pub d: [f32; 4],
}

/// The shading block of [`Params`] (48 bytes, laid out as the kernels' `Params`
/// fields `light_total` to `tex_table`): where the tables above start and the light
/// choice's totals.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ShadingBlock {
    /// Total choice weight of every light, the environment included (`Emitters::total`).
    pub light_total: f32,
    /// The probability of choosing the environment (0 without one).
    pub env_choice: f32,
    /// First texel of the environment map.
    pub env_first: u32,
    /// Its width in texels (0: no environment map).
    pub env_width: u32,
    /// Its height.
    pub env_height: u32,
    /// Float index of its marginal table, followed by the conditional ones.
    pub env_cdf: u32,
    /// Its rotation about `+y`: cosine.
    pub env_cos: f32,
    /// Sine.
    pub env_sin: f32,
    /// First entry of the emitter table.
    pub emitter_table: u32,
    /// Float index of the per-primitive attribute offsets ([`NONE`]: no attributes).
    pub attr_table: u32,
    /// Primitive ids the attribute table covers.
    pub attr_count: u32,
    /// First entry of the texture table.
    pub tex_table: u32,
}

/// `geo` entries per instance record.
pub(crate) const RECORD: u32 = 9;

/// Where the instances live in the buffers (all zero for a scene without instances).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Instancing {
    /// Index of the top level's root in the BVH2 node buffer.
    pub top_root: u32,
    /// Index in `geo` of the first instance record.
    pub records: u32,
    /// Instances.
    pub count: u32,
    /// Index in `geo` of the top level's order list (four ids per entry).
    pub order: u32,
    /// Ids below this are the flat part's (`prim_info` holds them directly).
    pub flat_count: u32,
}

/// The tree the kernels walk (the `WIDE` pipeline-override constant), a parameter of
/// `WgpuRenderer`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Layout {
    /// raybench-bvh's BVH2 (default build), 32-byte nodes, a per-thread stack of nodes,
    /// near child first.
    #[default]
    Bvh2,
    /// The same builder's BVH2 (leaves of up to three) collapsed into a compressed 8-wide
    /// BVH (Ylitie, Karras and Laine 2017; `cwbvh.rs`): 80-byte nodes with quantised child
    /// boxes, a stack of child groups in octant order.
    Cwbvh,
}

/// What a scene needs of the kernels beyond the kinds they always carry: each is a
/// pipeline-override constant (`HAS_*`, declared by `wgsl_constants` from
/// [`kind_names`]), so a pipeline carries only the intersection routines of the kinds its
/// scene holds. Shader compilers inline every routine at every call site (Mesa's always),
/// so a kernel with every kind compiled for minutes on lavapipe.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub(crate) struct Features {
    /// Bit [`PrimitiveKind::index`] set for every kind with a `HAS_*` constant that the
    /// scene holds (only those: scenes that differ in the other kinds share pipelines).
    kinds: u32,
    /// Whether the scene has instances (`HAS_INSTANCES`).
    instances: bool,
}

const _: () = assert!(PrimitiveKind::ALL.len() <= 32, "Features::kinds is one u32");

impl Features {
    /// The features of `scene`.
    pub(crate) fn of(scene: &Scene) -> Self {
        let g = &scene.geometry;
        let kinds = g
            .shapes()
            .iter()
            .chain(g.meshes().iter().flat_map(|m| m.shapes()))
            .map(|shape| shape.kind())
            .filter(|&k| kind_names(k).1.is_some())
            .fold(0, |bits, k| bits | (1 << k.index()));
        Self {
            kinds,
            instances: g.has_instances(),
        }
    }

    /// The override constants: one `HAS_*` per kind that has one, and `HAS_INSTANCES`.
    pub(crate) fn constants(self) -> Vec<(&'static str, f64)> {
        let flag = |b: bool| if b { 1.0 } else { 0.0 };
        PrimitiveKind::ALL
            .iter()
            .filter_map(|&k| {
                let (_, has) = kind_names(k);
                has.map(|name| (name, flag(self.kinds & (1 << k.index()) != 0)))
            })
            .chain([(HAS_INSTANCES, flag(self.instances))])
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every kind has its own number and names, and the names follow one pattern.
    #[test]
    fn kind_names_are_distinct_and_regular() {
        let mut numbers: Vec<u32> = PrimitiveKind::ALL.iter().map(|&k| kind_number(k)).collect();
        numbers.sort_unstable();
        numbers.dedup();
        assert_eq!(numbers.len(), PrimitiveKind::ALL.len());
        for k in PrimitiveKind::ALL {
            let (kind, has) = kind_names(k);
            let suffix = kind.strip_prefix("KIND_").expect("a KIND_ constant");
            if let Some(has) = has {
                assert_eq!(has.strip_prefix("HAS_"), Some(suffix), "{k:?}");
            }
        }
    }
}
