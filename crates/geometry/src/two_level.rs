//! The two-level form of any structure: one structure per distinct mesh (built once, shared
//! by all its instances), one over the flat primitives, and a small tree over the
//! instances' world boxes, walked nearest-first with rule 3's early exit.
//!
//! Every backend shares this top level (it is not the backend's own); only the structures
//! below it are the backend's. A candidate from an instance is the bottom structure's
//! closest hit on the instance-space ray clipped at the best `t` so far (the range is
//! inclusive, so a hit at exactly that `t` comes back), offered to the best hit under its
//! global id through [`keep_closer`]; so ties across instances and with flat primitives go
//! to the smaller global id, and every exact backend stays bit-identical with the naive
//! loop. Batches go ray by ray through the top level in this first version (the default
//! [`Accel::intersect_batch`]), so packet kernels do not apply to instanced scenes.

use crate::aabb::{Aabb, SlabRay};
use crate::accel::{Accel, AccelStats};
use crate::counters::Counters;
use crate::geometry::Geometry;
use crate::hit::{Hit, PrimHit, keep_closer};
use crate::ray::Ray;
use crate::stack::{NodeStack, cull_bound};
use glam::Vec3A;
use std::sync::Arc;

/// Most instances in one leaf of the top-level tree.
const LEAF_INSTANCES: usize = 2;

/// Depth bound of the top-level walk's stack: median splits of at most
/// [`crate::limits::MAX_INSTANCES`] (`2^20`) instances are at most 20 levels deep.
const STACK_DEPTH: usize = 64;

/// One node of the top-level tree: a box and either two children or a run of instances.
#[derive(Clone, Debug)]
pub struct TopNode {
    /// Box minimum.
    pub min: Vec3A,
    /// Box maximum.
    pub max: Vec3A,
    /// Inner node: index of the first child (the second follows it); leaf: first index
    /// into [`TopLevel::order`].
    pub first: u32,
    /// 0 for an inner node, else the number of instances in the leaf.
    pub count: u32,
}

/// The tree over the instances' world boxes (the GPU backend uploads the same tree).
#[derive(Clone, Debug, Default)]
pub struct TopLevel {
    nodes: Vec<TopNode>,
    order: Vec<u32>,
}

impl TopLevel {
    /// The nodes, root first (none without boxes).
    #[must_use]
    pub fn nodes(&self) -> &[TopNode] {
        &self.nodes
    }

    /// Box indices in leaf order: leaf `n` holds `order[n.first .. n.first + n.count]`.
    #[must_use]
    pub fn order(&self) -> &[u32] {
        &self.order
    }

    /// Median splits along the widest axis of the boxes' centres: the same tree on any
    /// machine and thread count.
    #[must_use]
    pub fn build(boxes: &[Aabb]) -> Self {
        let mut top = Self {
            nodes: Vec::new(),
            order: (0..boxes.len() as u32).collect(),
        };
        if !boxes.is_empty() {
            top.nodes.push(TopNode {
                min: Vec3A::ZERO,
                max: Vec3A::ZERO,
                first: 0,
                count: 0,
            });
            top.split(boxes, 0, 0, boxes.len());
        }
        top
    }

    fn split(&mut self, boxes: &[Aabb], node: usize, start: usize, end: usize) {
        let items = &mut self.order[start..end];
        let bounds = items
            .iter()
            .fold(Aabb::EMPTY, |b, &i| b.union(boxes[i as usize]));
        self.nodes[node].min = bounds.min.into();
        self.nodes[node].max = bounds.max.into();
        if items.len() <= LEAF_INSTANCES {
            self.nodes[node].first = start as u32;
            self.nodes[node].count = items.len() as u32;
            return;
        }
        let centres = Aabb::from_points(items.iter().map(|&i| boxes[i as usize].center()));
        let e = centres.extent();
        let axis = if e.x >= e.y && e.x >= e.z {
            0
        } else if e.y >= e.z {
            1
        } else {
            2
        };
        let mid = items.len() / 2;
        items.select_nth_unstable_by(mid, |&a, &b| {
            let (ca, cb) = (
                boxes[a as usize].center()[axis],
                boxes[b as usize].center()[axis],
            );
            ca.total_cmp(&cb).then(a.cmp(&b))
        });
        let first = self.nodes.len();
        self.nodes[node].first = first as u32;
        for _ in 0..2 {
            self.nodes.push(TopNode {
                min: Vec3A::ZERO,
                max: Vec3A::ZERO,
                first: 0,
                count: 0,
            });
        }
        self.split(boxes, first, start, start + mid);
        self.split(boxes, first + 1, start + mid, end);
    }

    /// Walks the tree nearest-first, calling `visit` with each instance whose box the ray
    /// enters within `limit()` (re-read after every visit: rule 3's strict early exit), and
    /// counting node visits. `visit` returns true to stop the walk.
    #[inline]
    fn walk<C: Counters>(
        &self,
        ray: &Ray,
        counters: &mut C,
        mut limit: impl FnMut() -> f32,
        mut visit: impl FnMut(u32, &mut C) -> bool,
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let slab = SlabRay::new(ray);
        let mut storage = [(0u32, 0.0f32); STACK_DEPTH];
        let mut stack = NodeStack::new(&mut storage);
        let root = &self.nodes[0];
        let Some(entry) = slab.entry(root.min, root.max, limit()) else {
            return;
        };
        stack.push(0, entry);
        while let Some((n, _)) = stack.pop_within(limit()) {
            counters.add_visits(1);
            let node = &self.nodes[n as usize];
            if node.count > 0 {
                let run = node.first as usize..(node.first + node.count) as usize;
                for &i in &self.order[run] {
                    if visit(i, counters) {
                        return;
                    }
                }
                continue;
            }
            let bound = limit();
            let children = [node.first, node.first + 1].map(|c| {
                let child = &self.nodes[c as usize];
                (c, slab.entry(child.min, child.max, bound))
            });
            // The farther child first, so the nearer is popped first.
            let [(a, ta), (b, tb)] = children;
            let ordered = match (ta, tb) {
                (Some(x), Some(y)) if y > x => [(b, tb), (a, ta)],
                _ => [(a, ta), (b, tb)],
            };
            for (c, t) in ordered {
                if let Some(t) = t {
                    stack.push(c, t);
                }
            }
        }
    }
}

/// The two-level form of the structure `A` for a geometry with instances (see the module
/// documentation); an [`Accel`] itself, whose queries cover the flattened scene.
#[derive(Debug)]
pub struct TwoLevel<A: Accel> {
    geometry: Arc<Geometry>,
    flat: A,
    meshes: Vec<A>,
    top: TopLevel,
}

impl<A: Accel> TwoLevel<A> {
    /// Builds `A` with `build` over the flat primitives (a structure built over the whole
    /// geometry organises those only) and over each distinct mesh once, and the top-level
    /// tree over the instances' world boxes.
    pub fn build_with(geometry: Arc<Geometry>, build: impl Fn(Arc<Geometry>) -> A) -> Self {
        let meshes = geometry
            .meshes()
            .iter()
            .map(|m| build(Arc::clone(m)).for_instances())
            .collect();
        let boxes: Vec<Aabb> = geometry.instances().iter().map(|i| i.bounds()).collect();
        Self {
            flat: build(Arc::clone(&geometry)),
            geometry,
            meshes,
            top: TopLevel::build(&boxes),
        }
    }

    /// The structure over the flat primitives.
    #[must_use]
    pub fn flat(&self) -> &A {
        &self.flat
    }

    /// The structures over the distinct meshes, in [`Geometry::meshes`] order.
    #[must_use]
    pub fn meshes(&self) -> &[A] {
        &self.meshes
    }

    /// Refits the bottom level to `geometry`, another frame of the same scene
    /// ([`crate::same_topology`]): the flat part's structure, and each distinct mesh's
    /// whose geometry changed (a mesh shared with the previous frame, the same `Arc`, is
    /// left alone). The top level is *not* updated: call [`TwoLevel::rebuild_top`] next
    /// (they are separate so that each can be timed). Returns false, and changes nothing,
    /// when `A` cannot refit or the topology differs.
    pub fn refit_bottom(&mut self, geometry: Arc<Geometry>) -> bool {
        if !A::REFITS || !crate::same_topology(&self.geometry, &geometry) {
            return false;
        }
        for (k, m) in geometry.meshes().iter().enumerate() {
            if !Arc::ptr_eq(m, &self.geometry.meshes()[k]) && !self.meshes[k].refit(Arc::clone(m)) {
                // An `A` that says it refits refuses only another topology, checked above.
                self.meshes[k] = A::build(Arc::clone(m)).for_instances();
            }
        }
        if !self.flat.refit(Arc::clone(&geometry)) {
            self.flat = A::build(Arc::clone(&geometry));
        }
        self.geometry = geometry;
        true
    }

    /// Rebuilds the bottom level for `geometry`, another frame of the same scene, with
    /// `build`: the flat part's structure, and each distinct mesh's whose geometry changed
    /// (a shared `Arc` is kept). The top level is not updated: call
    /// [`TwoLevel::rebuild_top`] next. Returns false, and changes nothing, when the
    /// topology differs (build the two-level form anew).
    pub fn rebuild_bottom(
        &mut self,
        geometry: Arc<Geometry>,
        build: impl Fn(Arc<Geometry>) -> A,
    ) -> bool {
        if !crate::same_topology(&self.geometry, &geometry) {
            return false;
        }
        for (k, m) in geometry.meshes().iter().enumerate() {
            if !Arc::ptr_eq(m, &self.geometry.meshes()[k]) {
                self.meshes[k] = build(Arc::clone(m)).for_instances();
            }
        }
        self.flat = build(Arc::clone(&geometry));
        self.geometry = geometry;
        true
    }

    /// Rebuilds the top level over the instances' current world boxes: a median-split tree
    /// over the instances, cheap next to the bottom level, so moving scenes rebuild it every
    /// frame rather than refit it.
    pub fn rebuild_top(&mut self) {
        let boxes: Vec<Aabb> = self
            .geometry
            .instances()
            .iter()
            .map(|i| i.bounds())
            .collect();
        self.top = TopLevel::build(&boxes);
    }

    /// Checks that every top-level node's box holds its children's boxes and its
    /// instances' world boxes, and that every instance is in one leaf (the top level of a
    /// valid, conservative two-level structure).
    ///
    /// # Errors
    /// A description of the first violation.
    pub fn validate_top(&self) -> Result<(), String> {
        let instances = self.geometry.instances();
        let mut seen = vec![0u32; instances.len()];
        let holds = |n: &TopNode, b: Aabb| Aabb::new(n.min.into(), n.max.into()).contains(&b);
        for (i, n) in self.top.nodes.iter().enumerate() {
            if n.count > 0 {
                let run = n.first as usize..(n.first + n.count) as usize;
                for &k in self.top.order.get(run).ok_or("leaf out of range")? {
                    if !holds(n, instances[k as usize].bounds()) {
                        return Err(format!("top node {i} does not hold instance {k}"));
                    }
                    seen[k as usize] += 1;
                }
            } else {
                for c in [n.first, n.first + 1] {
                    let child = self.top.nodes.get(c as usize).ok_or("child out of range")?;
                    if !holds(n, Aabb::new(child.min.into(), child.max.into())) {
                        return Err(format!("top node {c} sticks out of node {i}"));
                    }
                }
            }
        }
        match seen.iter().position(|&s| s != 1) {
            Some(k) => Err(format!("instance {k} is in {} top leaves", seen[k])),
            None => Ok(()),
        }
    }
}

impl<A: Accel> Accel for TwoLevel<A> {
    const TESTS_INSTANCES: bool = true;

    fn build(geometry: Arc<Geometry>) -> Self {
        Self::build_with(geometry, A::build)
    }

    const REFITS: bool = A::REFITS;

    /// [`TwoLevel::refit_bottom`], then [`TwoLevel::rebuild_top`].
    fn refit(&mut self, geometry: Arc<Geometry>) -> bool {
        let refitted = self.refit_bottom(geometry);
        if refitted {
            self.rebuild_top();
        }
        refitted
    }

    fn geometry(&self) -> &Geometry {
        &self.geometry
    }

    fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        let flat = self.flat.intersect(ray, counters);
        let as_prim = |h: &Hit| PrimHit {
            t: h.t,
            sub: h.sub,
            u: h.u,
            v: h.v,
        };
        let best: Option<(u32, PrimHit)> = flat.as_ref().map(|h| (h.prim, as_prim(h)));
        let best_t = |best: &Option<(u32, PrimHit)>| best.map_or(ray.t_max, |(_, h)| h.t);
        let cell = std::cell::Cell::new(best);
        self.top.walk(
            ray,
            counters,
            || cull_bound(best_t(&cell.get())),
            |k, counters| {
                let instance = &self.geometry.instances()[k as usize];
                let mut b = cell.get();
                let t = best_t(&b);
                if instance.bounds().intersect(ray, cull_bound(t)).is_some() {
                    let local = instance.local_ray(&ray.clipped(t));
                    let mesh = &self.meshes[instance.mesh() as usize];
                    if let Some(h) = mesh.intersect(&local, counters) {
                        keep_closer(&mut b, instance.base() + h.prim, as_prim(&h));
                        cell.set(b);
                    }
                }
                false
            },
        );
        match cell.get() {
            Some((id, _)) if (id as usize) < self.geometry.len() => flat,
            winner => self.geometry.complete_global(ray, winner),
        }
    }

    fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        if self.flat.occluded(ray, counters) {
            return true;
        }
        let mut hit = false;
        self.top.walk(
            ray,
            counters,
            || ray.t_max,
            |k, counters| {
                let instance = &self.geometry.instances()[k as usize];
                hit = instance.bounds().intersect(ray, ray.t_max).is_some()
                    && self.meshes[instance.mesh() as usize]
                        .occluded(&instance.local_ray(ray), counters);
                hit
            },
        );
        hit
    }

    /// Memory: the flat structure's, each distinct mesh's structure once, and the top
    /// level's. Counts: the flat structure's own (its names may be maxima or ratios, which
    /// do not add across structures), then the top level's nodes, the instances and the
    /// distinct meshes.
    fn stats(&self) -> AccelStats {
        let mut stats = self.flat.stats();
        stats.memory_bytes += self
            .meshes
            .iter()
            .map(|m| m.stats().memory_bytes)
            .sum::<usize>()
            + self.top.nodes.len() * std::mem::size_of::<TopNode>()
            + self.top.order.len() * 4
            + self.meshes.len() * std::mem::size_of::<A>();
        stats.counts.extend([
            ("top nodes", self.top.nodes.len() as u64),
            ("instances", self.geometry.instances().len() as u64),
            ("meshes", self.meshes.len() as u64),
        ]);
        stats
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Instance, RayCounters, Shape, Sphere, Triangle, random_rays};
    use glam::{Affine3A, Quat, Vec3};

    /// The brute force over the flat part only: the simplest `A`, so that these tests check
    /// the top level and the combination, not a structure.
    struct Flat(Arc<Geometry>);

    impl Accel for Flat {
        fn build(geometry: Arc<Geometry>) -> Self {
            Self(geometry)
        }
        fn geometry(&self) -> &Geometry {
            &self.0
        }
        fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
            self.0.closest_brute_force(ray, counters)
        }
        fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
            self.0.occluded_brute_force(ray, counters)
        }
        fn stats(&self) -> AccelStats {
            AccelStats::default()
        }
    }

    /// A mesh of two triangles and a sphere, instanced 40 times with rotations, mirrors,
    /// non-uniform scales and coincident copies, beside flat spheres.
    fn scene() -> Arc<Geometry> {
        let mesh = Arc::new(Geometry::new(vec![
            Shape::Triangle(Triangle::new(
                Vec3::new(-1.0, -1.0, 0.0),
                Vec3::new(1.0, -1.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
            )),
            Shape::Triangle(Triangle::new(
                Vec3::new(-1.0, -1.0, 0.3),
                Vec3::new(1.0, -1.0, 0.3),
                Vec3::new(0.0, 1.0, -0.3),
            )),
            Shape::Sphere(Sphere::new(Vec3::new(0.0, 0.0, 0.5), 0.4)),
        ]));
        // Every fourth instance repeats the previous one's place: coincident.
        let instances = (0..40)
            .map(|k| {
                Instance::new(0, &mesh, placement(if k % 4 == 3 { k - 1 } else { k })).unwrap()
            })
            .collect();
        Arc::new(Geometry::with_instances(
            vec![
                Shape::Sphere(Sphere::new(Vec3::new(0.0, 0.0, -1.0), 0.7)),
                Shape::Plane(crate::Plane::new(Vec3::new(0.0, 0.0, -4.0), Vec3::Z)),
            ],
            vec![mesh],
            instances,
        ))
    }

    /// The placement of instance `k`: on a 7-wide grid, rotated, non-uniformly scaled,
    /// every third mirrored.
    fn placement(k: usize) -> Affine3A {
        let x = (k % 7) as f32 - 3.0;
        let y = (k / 7) as f32 - 3.0;
        let mirror = if k.is_multiple_of(3) { -1.0 } else { 1.0 };
        Affine3A::from_scale_rotation_translation(
            Vec3::new(mirror * 0.6, 0.4 + 0.05 * (k % 5) as f32, 0.5),
            Quat::from_euler(glam::EulerRot::ZYX, 0.3 * k as f32, 0.2, 0.1),
            Vec3::new(x, y, 0.0),
        )
    }

    /// The two-level form returns the naive loop's ids, `t` and normals bit for bit, and
    /// the same any-hit answers; coincident instances go to the smaller id.
    #[test]
    fn equals_the_naive_loop() {
        let g = scene();
        assert_eq!(g.total_len(), 2 + 40 * 3);
        let two = TwoLevel::<Flat>::build(Arc::clone(&g));
        let mut rays = random_rays::incoherent(g.world_bounds(), 4000, 7);
        // Straight down onto the instances' grid: many coincident hits.
        rays.extend((0..400).map(|i| {
            let (x, y) = ((i % 20) as f32 * 0.35 - 3.5, (i / 20) as f32 * 0.35 - 3.5);
            Ray::new(Vec3::new(x, y, 5.0), Vec3::NEG_Z)
        }));
        let (mut hits, mut odd) = (0, 0);
        for ray in &rays {
            let mut c = RayCounters::default();
            let naive = g.closest_every(ray, &mut c);
            assert_eq!(c.prim_tests, g.total_len() as u64);
            let fast = two.intersect(ray, &mut RayCounters::default());
            assert_eq!(naive, fast, "{ray:?}");
            assert_eq!(
                g.occluded_every(ray, &mut RayCounters::default()),
                two.occluded(ray, &mut RayCounters::default())
            );
            if let Some(h) = naive {
                hits += 1;
                if let Some((k, _)) = g.locate(h.prim)
                    && k % 4 == 3
                {
                    odd += 1;
                }
            }
        }
        assert!(hits > 1000, "{hits}");
        // The coincident copies (instances 3, 7, ...) lose every tie to their twins.
        assert_eq!(odd, 0);
        let stats = two.stats();
        assert!(stats.counts.contains(&("instances", 40)));
        assert!(stats.counts.contains(&("meshes", 1)));
    }
}
