//! Instances on the GPU (`closest_instances` and `occluded_instances` in
//! `kernels/main.wgsl`, ports of [`raybench_core::TwoLevel`]'s `intersect` and `occluded`).
//!
//! - Each distinct mesh ([`raybench_core::Geometry::meshes`]) gets its own tree of the
//!   renderer's layout (BVH2, or the CWBVH collapsed from it), appended after the flat
//!   part's nodes; its primitives follow the flat part's records (and the emitter list)
//!   with their ids in the mesh, so a hit's id is the instance's base plus that id.
//! - The top level is the CPU's own tree ([`TopLevel::build`] over the instances' world
//!   boxes), appended to the BVH2 node buffer (in both layouts), its leaves indexing the
//!   instance order list in `geo`.
//! - One record of [`crate::records::RECORD`] entries per instance in `geo`, in id order: the
//!   inverse transform's columns and translation, the normal matrix (inverse transpose), the world
//!   box, and in the `w` lanes the mesh's root node, the base id, the instance's material (or
//!   `NO_HIT` for the mesh's own), where the mesh's materials start in `prim_info`, the primitive
//!   count, and the float index of the mesh's shading attribute table
//!   ([`crate::shading::mesh_attribute_tables`]; `NONE` for a mesh without attributes).

use crate::cwbvh::{self, Cwbvh};
use crate::data::{SceneData, bvh2_nodes};
use crate::records::{GpuNode, Instancing, Layout, STACK_SIZE, next_index};
use raybench_bvh::Bvh;
use raybench_core::{Accel, NO_HIT, Scene, TopLevel, Vec3};
use std::sync::Arc;

fn bits(x: u32) -> f32 {
    f32::from_bits(x)
}

fn v4(v: Vec3, w: f32) -> [f32; 4] {
    [v.x, v.y, v.z, w]
}

/// Appends the meshes' trees and primitives, the top level and the instance records of
/// `scene` to `data` (nothing for a scene without instances).
///
/// # Errors
/// When a mesh's tree is deeper than the kernels' stack, a primitive has no port, or an
/// index overflows.
pub(crate) fn append(scene: &Scene, layout: Layout, data: &mut SceneData) -> Result<(), String> {
    let g = &scene.geometry;
    if !g.has_instances() {
        return Ok(());
    }
    let depth_limit = STACK_SIZE as usize;
    // Per mesh: its root node index and where its materials start in `prim_info`.
    let mut roots = Vec::with_capacity(g.meshes().len());
    let mut materials = Vec::with_capacity(g.meshes().len());
    for (m, mesh) in g.meshes().iter().enumerate() {
        let bvh = match layout {
            Layout::Bvh2 => Bvh::build(Arc::clone(mesh)),
            Layout::Cwbvh => Bvh::build_with(Arc::clone(mesh), cwbvh::bvh2_params()),
        };
        if bvh.depth() + 1 > depth_limit {
            return Err(format!(
                "instanced mesh {m}'s BVH depth {} exceeds the GPU traversal stack",
                bvh.depth()
            ));
        }
        let prim_base = u32::try_from(data.prims.len()).map_err(|_| "too many primitives")?;
        let (root, order) = match layout {
            Layout::Bvh2 => {
                let base = data.nodes.len() as u32;
                data.nodes.extend(bvh2_nodes(&bvh).into_iter().map(|mut n| {
                    n.first_or_right += if n.count > 0 { prim_base } else { base };
                    n
                }));
                (base, bvh.prim_ids().to_vec())
            }
            Layout::Cwbvh => {
                let wide = Cwbvh::collapse(&bvh)?;
                let base = data.wide.len() as u32;
                data.wide.extend(wide.nodes.into_iter().map(|mut n| {
                    n.words[4] += base;
                    n.words[5] += prim_base;
                    n
                }));
                (base, wide.prim_ids)
            }
        };
        for id in order {
            let p = crate::data::prim(mesh.shape(id), id, &mut data.geo)?;
            data.prims.push(p);
        }
        roots.push(root);
        materials.push(data.prim_info.len() as u32);
        data.prim_info.extend_from_slice(&scene.mesh_materials[m]);
    }

    let attribute_tables = crate::shading::mesh_attribute_tables(scene, &mut data.geo)?;

    let instances = g.instances();
    let boxes: Vec<_> = instances.iter().map(|i| i.bounds()).collect();
    let top = TopLevel::build(&boxes);
    let top_root = data.nodes.len() as u32;
    data.nodes.extend(top.nodes().iter().map(|n| GpuNode {
        min: n.min.into(),
        first_or_right: n.first + if n.count > 0 { 0 } else { top_root },
        max: n.max.into(),
        count: n.count,
    }));
    let order = next_index(&data.geo)?;
    data.geo.extend(top.order().chunks(4).map(|c| {
        let mut e = [bits(NO_HIT); 4];
        for (slot, &k) in e.iter_mut().zip(c) {
            *slot = bits(k);
        }
        e
    }));
    let records = next_index(&data.geo)?;
    for (k, inst) in instances.iter().enumerate() {
        let (to_local, normal) = (inst.to_local(), inst.normal_matrix());
        let mesh = inst.mesh() as usize;
        let material = scene.instance_materials[k].unwrap_or(NO_HIT);
        let b = inst.bounds();
        data.geo.extend([
            v4(to_local.matrix3.x_axis.into(), bits(roots[mesh])),
            v4(to_local.matrix3.y_axis.into(), bits(inst.base())),
            v4(to_local.matrix3.z_axis.into(), bits(material)),
            v4(to_local.translation.into(), bits(materials[mesh])),
            v4(normal.x_axis.into(), bits(inst.count())),
            v4(normal.y_axis.into(), bits(attribute_tables[mesh])),
            v4(normal.z_axis.into(), 0.0),
            v4(b.min, 0.0),
            v4(b.max, 0.0),
        ]);
    }
    next_index(&data.geo)?;
    data.instancing = Instancing {
        top_root,
        records,
        count: instances.len() as u32,
        order,
        flat_count: g.len() as u32,
    };
    Ok(())
}
