//! The scene flattened once per `prepare` into the records the shaders read
//! ([`crate::records`]), and the kernels' entry points.

use raybench_bvh::Bvh;
use raybench_core::{
    CULL_SLACK, CameraRays, FAR_SCALE, Light, LightSampling, MaterialKind, Mode, RenderError,
    RenderSettings, Scene, Shape, Vec3,
};

use crate::cwbvh::WideNode;
use crate::geo;
use crate::records::{
    EMITTER_BIT, Geo, GpuNode, GpuPrim, Instancing, LIGHT_DIRECTIONAL, LIGHT_POINT, MAT_DIFFUSE,
    MAT_GLASS, MAT_MIRROR, NONE, Params, ShadingBlock, kind_number,
};

fn v4(v: Vec3, w: f32) -> [f32; 4] {
    [v.x, v.y, v.z, w]
}

/// The GPU record of a primitive; the kinds of [`geo`] append their data to `geo`.
///
/// # Errors
/// When the kind has no WGSL port or its data does not fit ([`geo::supports`]).
pub(crate) fn prim(shape: &Shape, id: u32, geo: &mut Geo) -> Result<GpuPrim, String> {
    let mut p = match shape {
        Shape::Triangle(t) => GpuPrim {
            a: v4(t.v[0], 0.0),
            b: v4(t.v[1], 0.0),
            c: v4(t.v[2], 0.0),
        },
        Shape::Sphere(s) => GpuPrim {
            a: v4(s.center, 0.0),
            b: v4(Vec3::ZERO, 0.0),
            c: [s.radius, 0.0, 0.0, 0.0],
        },
        Shape::Plane(p) => GpuPrim {
            a: v4(p.point, 0.0),
            b: v4(Vec3::ZERO, 0.0),
            c: v4(p.normal, 0.0),
        },
        Shape::HeightField(_) | Shape::Csg(_) | Shape::Bezier(_) | Shape::Sdf(_) => {
            geo::encode(shape, geo)?.unwrap_or_default()
        }
    };
    p.a[3] = f32::from_bits(kind_number(shape.kind()));
    p.b[3] = f32::from_bits(id);
    Ok(p)
}

/// Why the shaders cannot render `scene`, if they cannot: every primitive kind must have a
/// WGSL port whose data fits ([`geo::supports`]). (Environment maps, every bounded emitter
/// kind as a light of `path`, textures and shading normals are ported: [`crate::shading`].)
///
/// # Errors
/// The first primitive the kernels cannot intersect.
pub fn check_kinds(scene: &Scene) -> Result<(), String> {
    scene.geometry.shapes().iter().try_for_each(geo::supports)
}

/// The scene flattened for the GPU.
pub struct SceneData {
    /// BVH2 nodes, depth first (none for the CWBVH kernels).
    pub nodes: Vec<GpuNode>,
    /// CWBVH nodes (none for the BVH2 kernels).
    pub wide: Vec<WideNode>,
    /// Bounded primitives in leaf order, then the unbounded ones, then the emitter list.
    pub prims: Vec<GpuPrim>,
    /// Per primitive id: material index, with [`EMITTER_BIT`] for sampled emitters.
    pub prim_info: Vec<u32>,
    /// Materials (five vectors each), then lights (two vectors each).
    pub shading: Vec<[f32; 4]>,
    /// The primitives' own data beyond their records ([`geo`]).
    pub geo: Vec<[f32; 4]>,
    /// Where the unbounded primitives start in `prims`, and how many.
    pub unbounded: (u32, u32),
    /// Where the emitter list starts in `prims`, and how many.
    pub emitters: (u32, u32),
    /// Where the lights start in `shading`, and how many.
    pub lights: (u32, u32),
    /// Nodes of the flat part's tree (the mesh trees and the top level follow them).
    pub flat_nodes: u32,
    /// Where the instances live ([`crate::instances`]).
    pub instancing: Instancing,
    /// Where the shading data is in `geo` ([`crate::shading`]).
    pub block: ShadingBlock,
    /// Where the volume table starts in `geo` and how many volumes, or why the volume
    /// modes cannot run ([`crate::volume`]).
    pub volumes: crate::volume::GpuVolumes,
}

/// The 32-byte nodes of `bvh`, depth first as it stores them.
#[must_use]
pub fn bvh2_nodes(bvh: &Bvh) -> Vec<GpuNode> {
    bvh.nodes()
        .iter()
        .map(|n| GpuNode {
            min: n.min.into(),
            first_or_right: n.first_or_right,
            max: n.max.into(),
            count: n.count,
        })
        .collect()
}

impl SceneData {
    /// Flattens `scene` with the nodes of its tree: BVH2 `nodes` or CWBVH `wide` nodes (the
    /// other list empty), whose leaves index the primitives `leaf_order` lists.
    ///
    /// # Errors
    /// When the scene holds a primitive kind without a WGSL port ([`check_kinds`]).
    pub fn new(
        scene: &Scene,
        nodes: Vec<GpuNode>,
        wide: Vec<WideNode>,
        leaf_order: &[u32],
    ) -> Result<Self, String> {
        check_kinds(scene)?;
        let g = &scene.geometry;
        let mut geo = Geo::new();
        // Leaves index the primitive buffer directly: primitives are stored in leaf order.
        let mut prims = Vec::with_capacity(leaf_order.len() + g.unbounded().len());
        for &id in leaf_order.iter().chain(g.unbounded()) {
            prims.push(prim(g.shape(id), id, &mut geo)?);
        }
        let unbounded = (leaf_order.len() as u32, g.unbounded().len() as u32);
        // The emitter list repeats its primitives' records (data shared with the originals
        // where the kind keeps any in `geo`: the record is copied, not re-encoded); what
        // light sampling needs beyond them is in the emitter table ([`crate::shading`]).
        let mut slot_of = vec![u32::MAX; g.len()];
        for (k, &id) in leaf_order.iter().chain(g.unbounded()).enumerate() {
            slot_of[id as usize] = k as u32;
        }
        let emitter_first = prims.len() as u32;
        for &id in &scene.emitters.ids {
            prims.push(prims[slot_of[id as usize] as usize]);
        }
        let emitters = (emitter_first, scene.emitters.ids.len() as u32);
        let flat_nodes = (nodes.len() + wide.len()) as u32;

        let mut prim_info = scene.prim_material.clone();
        for &id in &scene.emitters.ids {
            prim_info[id as usize] |= EMITTER_BIT;
        }
        let block = crate::shading::encode(scene, &mut geo)?;
        let mut shading = Vec::with_capacity(scene.materials.len() * 5 + scene.lights.len() * 2);
        for m in &scene.materials {
            let kind = match m.kind {
                MaterialKind::Diffuse => MAT_DIFFUSE,
                MaterialKind::Mirror => MAT_MIRROR,
                MaterialKind::Glass => MAT_GLASS,
            };
            let (checker, size) = m.checker.map_or((Vec3::ZERO, 0.0), |c| (c.color, c.size));
            shading.push(v4(m.base_color, f32::from_bits(kind)));
            shading.push(v4(m.specular, m.shininess));
            shading.push(v4(m.emission, m.ior));
            shading.push(v4(checker, size));
            let texture = |t: Option<u32>| f32::from_bits(t.unwrap_or(NONE));
            shading.push([
                texture(m.base_color_texture),
                texture(m.emission_texture),
                0.0,
                0.0,
            ]);
        }
        let lights = (shading.len() as u32, scene.lights.len() as u32);
        for l in &scene.lights {
            let (a, kind, b) = match *l {
                Light::Point {
                    position,
                    intensity,
                } => (position, LIGHT_POINT, intensity),
                Light::Directional {
                    direction,
                    radiance,
                } => (direction, LIGHT_DIRECTIONAL, radiance),
            };
            shading.push(v4(a, f32::from_bits(kind)));
            shading.push(v4(b, 0.0));
        }
        // The volumes last, so that they can be dropped again ([`Self::drop_volumes`]).
        let volumes = crate::volume::append(scene, &mut geo);
        Ok(Self {
            nodes,
            wide,
            prims,
            prim_info,
            shading,
            geo,
            unbounded,
            emitters,
            lights,
            flat_nodes,
            instancing: Instancing::default(),
            block,
            volumes,
        })
    }

    /// Takes the volumes out of `geo` (they are last in it), the volume modes refused
    /// with `reason`.
    pub fn drop_volumes(&mut self, reason: String) {
        if let Ok((first, _)) = self.volumes {
            self.geo.truncate(first as usize);
        }
        self.volumes = Err(reason);
    }

    /// Bytes of the scene buffers.
    #[must_use]
    pub fn bytes(&self) -> u64 {
        (self.nodes.len() * 32
            + self.wide.len() * 80
            + self.prims.len() * 48
            + self.prim_info.len() * 4) as u64
            + (self.shading.len() + self.geo.len()) as u64 * 16
    }

    /// The parameters every dispatch of a frame shares; the caller fills in the band,
    /// region and sample range.
    ///
    /// # Errors
    /// When `settings` names a camera the scene does not have ([`Scene::view`]).
    pub fn params(&self, scene: &Scene, settings: &RenderSettings) -> Result<Params, RenderError> {
        let camera: CameraRays = scene.view(settings)?.rays(settings.width, settings.height);
        Ok(Params {
            origin: camera.origin.into(),
            inv_width: camera.inv_width,
            forward: camera.forward.into(),
            inv_height: camera.inv_height,
            right: camera.right.into(),
            seed: settings.seed,
            up: camera.up.into(),
            spp: settings.spp,
            background: scene.background.into(),
            max_depth: settings.max_depth,
            cast_light: raybench_core::integrator::cast_light(scene).into(),
            inf: f32::INFINITY,
            width: settings.width,
            height: settings.height,
            node_count: self.flat_nodes,
            unbounded_first: self.unbounded.0,
            unbounded_count: self.unbounded.1,
            emitter_first: self.emitters.0,
            emitter_count: self.emitters.1,
            light_first: self.lights.0,
            light_count: self.lights.1,
            emitter_weight: scene.emitters.total_weight(),
            mis: u32::from(
                settings.light_sampling == LightSampling::Mis && !scene.emitters.is_empty(),
            ),
            shading: self.block,
            far_scale: FAR_SCALE,
            cull_slack: CULL_SLACK,
            instance_count: self.instancing.count,
            top_root: self.instancing.top_root,
            instance_records: self.instancing.records,
            instance_order: self.instancing.order,
            flat_count: self.instancing.flat_count,
            volume_first: self.volumes.as_ref().map_or(0, |v| v.0),
            volume_count: self.volumes.as_ref().map_or(0, |v| v.1),
            ..Params::default()
        })
    }
}

/// The kernel (entry point) of explicit any-hit rays.
pub const OCCLUDE_ENTRY: &str = "occlude_kernel";

/// The kernel (entry point) of a mode (`None`: explicit rays), or why there is none.
///
/// # Errors
/// None today: every mode has a kernel (the volume modes' `mip_kernel` and
/// `composite_kernel` are in `kernels/volume.wgsl`; a scene whose volumes do not fit the
/// device is refused by the renderer, [`SceneData::volumes`]).
pub fn entry_point(mode: Option<Mode>) -> Result<&'static str, String> {
    match mode {
        Some(Mode::Cast) => Ok("cast_kernel"),
        Some(Mode::Whitted) => Ok("whitted_kernel"),
        Some(Mode::Path) => Ok("path_kernel"),
        Some(Mode::Mip) => Ok("mip_kernel"),
        Some(Mode::Composite) => Ok("composite_kernel"),
        None => Ok("trace_kernel"),
    }
}
