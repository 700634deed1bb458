//! Two-level acceleration: one BVH per mesh (a BLAS, in the mesh's object space), a binary BVH
//! over the instances' world-space boxes (the TLAS), and rays carried into each instance they
//! may hit by its inverse transform.
//!
//! A ray `o + t·d` transformed by an affine map keeps its parameter: `A⁻¹(o + t·d) =
//! A⁻¹o + t·(A⁻¹d)` with the direction left unnormalised, so a hit's `t` in an instance is its
//! world `t`, and the closest hit so far bounds the next instance's query directly.
//!
//! Self-intersection across the transform: the integrators offset a ray's origin in world space
//! (`offset_ray_origin_scaled`: 256 ULPs of the world coordinate, or a fixed step scaled to the
//! scene), and the offset origin is then carried into the object by `A⁻¹`. Rounding in that
//! product moves it by a few ULPs of the world coordinate, magnified by at most the transform's
//! condition number (the ratio of its largest to smallest scale), so the offset's 256 ULPs stay
//! ahead of it for transforms whose scales differ by less than ~50×
//! (`tests/instances.rs` measures it, in `docs/stability.md`).

use glam::{Affine3A, Vec2, Vec3, Vec3A};
use obvhs::{aabb::Aabb, ploc::PlocBuilder};
use rayon::prelude::*;
use std::ops::Range;

use crate::bvh::safe_recip3;
use crate::{BuildOptions, Bvh, Hit};

/// A node of the TLAS, 32 bytes: its box, and either its two children (`count` 0, the first at
/// `first`, the second after it) or one instance (`count` 1, `first` the instance's index).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct TlasNode {
    /// Box minimum.
    pub min: [f32; 3],
    /// 0 for an inner node, 1 for a leaf.
    pub count: u32,
    /// Box maximum.
    pub max: [f32; 3],
    /// First child, or the leaf's instance.
    pub first: u32,
}

const _: () = assert!(size_of::<TlasNode>() == 32);

/// A closest hit of a [`TwoLevel`] query: the triangle (its id in the caller's numbering), and
/// the instance that placed it (`None` for a world-space triangle).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InstanceHit {
    /// The triangle, distance and barycentrics (as the mesh's own [`Bvh`] reports them).
    pub hit: Hit,
    /// The instance, an index into the instances given to [`TwoLevel::build`].
    pub instance: Option<u32>,
}

/// One placement: the mesh and the transform a ray is carried into it by.
#[derive(Clone, Copy, Debug)]
struct Placement {
    mesh: u32,
    object_from_world: Affine3A,
}

/// World-space triangles in one BVH, and meshes placed by instances under a TLAS.
///
/// Triangle ids are the caller's: the world triangles' ids are the indices given to
/// [`TwoLevel::build`] (`world` range), a mesh's are its range's.
pub struct TwoLevel {
    world: Option<Bvh>,
    /// One BVH per mesh, with the id of its first triangle.
    meshes: Vec<(Bvh, u32)>,
    placements: Vec<Placement>,
    nodes: Vec<TlasNode>,
}

/// A scene's acceleration structure: one [`Bvh`] over world-space triangles when no mesh is
/// placed by an instance, else a [`TwoLevel`]. Built once, it can serve several users of the
/// same scene (a probe before rendering, then the renderer).
pub enum SceneAccel {
    /// One BVH over every triangle.
    Flat(Bvh),
    /// World triangles and instanced meshes.
    TwoLevel(TwoLevel),
}

/// What a [`SceneAccel`] takes, in bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AccelBytes {
    /// The BVHs on the host ([`Bvh::bytes`]).
    pub bvh: usize,
    /// The instances' placements (transforms) and the TLAS nodes on the host.
    pub instances: usize,
    /// The BVHs as a GPU uploads them ([`Bvh::gpu_bytes`]).
    pub gpu_bvh: usize,
    /// The TLAS nodes as a GPU uploads them (its instance records are the GPU integrator's).
    pub gpu_tlas: usize,
}

impl SceneAccel {
    /// [`TwoLevel::build`] when `instances` is not empty; otherwise one BVH over all of
    /// `triangles` (`world` and `meshes` are then ignored) with the default options.
    ///
    /// # Panics
    /// As [`TwoLevel::build`].
    pub fn build(
        positions: &[Vec3],
        triangles: &[[u32; 3]],
        world: Range<u32>,
        meshes: &[Range<u32>],
        instances: &[(u32, Affine3A)],
    ) -> Self {
        if instances.is_empty() {
            Self::Flat(Bvh::from_indexed(positions, triangles, BuildOptions::default()))
        } else {
            Self::TwoLevel(TwoLevel::build(positions, triangles, world, meshes, instances))
        }
    }

    /// Whether this structure was built for a store of `triangles` triangles placed by
    /// `instances` instances (a cheap check that it belongs to a scene, not a proof).
    pub fn fits(&self, triangles: usize, instances: usize) -> bool {
        match self {
            Self::Flat(b) => instances == 0 && b.input_count() == triangles,
            Self::TwoLevel(t) => {
                let stored = t.world.as_ref().map_or(0, Bvh::input_count)
                    + t.meshes.iter().map(|(b, _)| b.input_count()).sum::<usize>();
                instances > 0 && t.placements.len() == instances && stored <= triangles
            }
        }
    }

    /// The bytes the structure holds on the host and those a GPU uploads of it.
    pub fn bytes(&self) -> AccelBytes {
        let bvhs: Vec<&Bvh> = match self {
            Self::Flat(b) => vec![b],
            Self::TwoLevel(t) => t.world.iter().chain(t.meshes.iter().map(|(b, _)| b)).collect(),
        };
        let (placements, tlas) = match self {
            Self::Flat(_) => (0, 0),
            Self::TwoLevel(t) => {
                (t.placements.len() * size_of::<Placement>(), t.nodes.len() * size_of::<TlasNode>())
            }
        };
        AccelBytes {
            bvh: bvhs.iter().map(|b| b.bytes()).sum(),
            instances: placements + tlas,
            gpu_bvh: bvhs.iter().map(|b| b.gpu_bytes()).sum(),
            gpu_tlas: tlas,
        }
    }

    /// The closest hit of `origin + t·dir`, `0 < t < t_max`, with its instance.
    pub fn closest_hit(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<InstanceHit> {
        match self {
            Self::Flat(b) => b.closest_hit(origin, dir, t_max).map(|hit| InstanceHit { hit, instance: None }),
            Self::TwoLevel(t) => t.closest_hit(origin, dir, t_max),
        }
    }

    /// Whether any triangle lies along `origin + t·dir`, `0 < t < t_max`.
    pub fn occluded(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
        match self {
            Self::Flat(b) => b.occluded(origin, dir, t_max),
            Self::TwoLevel(t) => t.occluded(origin, dir, t_max),
        }
    }
}

/// The box padding: a fraction of the box's extent plus of its largest coordinate, so that the
/// transformed corners' rounding (a few ULPs) cannot cut a triangle off.
const PAD: f32 = 1e-5;

impl TwoLevel {
    /// Builds the world BVH over `triangles[world]` and one BVH per `meshes` range (all in
    /// parallel, each with the preset its size picks), then the TLAS over `instances`
    /// (`(mesh, world_from_object)`). `positions` and `triangles` are one indexed store; an
    /// instance's mesh index must be in range.
    ///
    /// # Panics
    /// If an instance names a mesh out of range.
    pub fn build(
        positions: &[Vec3],
        triangles: &[[u32; 3]],
        world: Range<u32>,
        meshes: &[Range<u32>],
        instances: &[(u32, Affine3A)],
    ) -> Self {
        let build = |r: &Range<u32>| {
            Bvh::from_indexed(
                positions,
                &triangles[r.start as usize..r.end as usize],
                BuildOptions::default(),
            )
        };
        let (world_bvh, blas) = rayon::join(
            || (!world.is_empty()).then(|| build(&world)),
            || meshes.par_iter().map(|r| (build(r), r.start)).collect::<Vec<_>>(),
        );
        let bounds: Vec<Option<(Vec3, Vec3)>> = blas.iter().map(|(b, _)| b.bounds()).collect();
        let mut aabbs = Vec::with_capacity(instances.len());
        let mut kept = Vec::with_capacity(instances.len());
        let mut placements = Vec::with_capacity(instances.len());
        for (index, &(mesh, world_from_object)) in instances.iter().enumerate() {
            assert!((mesh as usize) < meshes.len(), "instance {index}: mesh {mesh} of {}", meshes.len());
            placements.push(Placement { mesh, object_from_world: world_from_object.inverse() });
            let Some((lo, hi)) = bounds[mesh as usize] else { continue };
            let (mut wlo, mut whi) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
            for k in 0..8 {
                let corner = Vec3::new(
                    if k & 1 == 0 { lo.x } else { hi.x },
                    if k & 2 == 0 { lo.y } else { hi.y },
                    if k & 4 == 0 { lo.z } else { hi.z },
                );
                let p = Vec3A::from(world_from_object.transform_point3(corner));
                wlo = wlo.min(p);
                whi = whi.max(p);
            }
            if !(wlo.is_finite() && whi.is_finite()) {
                continue;
            }
            let pad = (whi - wlo) * PAD + Vec3A::splat(wlo.abs().max(whi.abs()).max_element() * PAD);
            aabbs.push(Aabb { min: wlo - pad, max: whi + pad });
            kept.push(index as u32);
        }
        let nodes = tlas(&aabbs, &kept);
        Self { world: world_bvh, meshes: blas, placements, nodes }
    }

    /// The TLAS nodes, root first (none without instances).
    pub fn tlas_nodes(&self) -> &[TlasNode] {
        &self.nodes
    }

    /// Each instance's mesh and world-to-object transform, in the order given to
    /// [`TwoLevel::build`].
    pub fn placements(&self) -> impl ExactSizeIterator<Item = (u32, Affine3A)> + '_ {
        self.placements.iter().map(|p| (p.mesh, p.object_from_world))
    }

    /// The world-space triangles' BVH, if there are any.
    pub fn world(&self) -> Option<&Bvh> {
        self.world.as_ref()
    }

    /// Each mesh's BVH with the id of its first triangle.
    pub fn meshes(&self) -> &[(Bvh, u32)] {
        &self.meshes
    }

    /// The closest hit of `origin + t·dir`, `0 < t < t_max`, over the world triangles and every
    /// instance; `mask(instance, triangle, barycentrics)` filters candidates as
    /// [`Bvh::closest_hit_masked`]'s mask does (`instance` is `u32::MAX` for a world triangle).
    pub fn closest_hit_masked(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_max: f32,
        mut mask: impl FnMut(u32, u32, Vec2) -> bool,
    ) -> Option<InstanceHit> {
        let mut best = self
            .world
            .as_ref()
            .and_then(|w| w.closest_hit_masked(origin, dir, t_max, |t, b| mask(u32::MAX, t, b)))
            .map(|hit| InstanceHit { hit, instance: None });
        let current = std::cell::Cell::new(best.map_or(t_max, |b| b.hit.t));
        self.instances_along(
            origin,
            dir,
            || current.get(),
            |instance, o, d| {
                let (bvh, first) = &self.meshes[self.placements[instance as usize].mesh as usize];
                let hit = bvh.closest_hit_masked(o, d, current.get(), |t, b| mask(instance, t + first, b));
                if let Some(mut hit) = hit {
                    hit.triangle += first;
                    current.set(hit.t);
                    best = Some(InstanceHit { hit, instance: Some(instance) });
                }
                false
            },
        );
        best
    }

    /// [`closest_hit_masked`](Self::closest_hit_masked) with every candidate accepted.
    pub fn closest_hit(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<InstanceHit> {
        self.closest_hit_masked(origin, dir, t_max, |_, _, _| true)
    }

    /// Whether any triangle `mask` accepts lies along `origin + t·dir`, `0 < t < t_max`.
    pub fn occluded_masked(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_max: f32,
        mut mask: impl FnMut(u32, u32, Vec2) -> bool,
    ) -> bool {
        if let Some(w) = &self.world
            && w.occluded_masked(origin, dir, t_max, |t, b| mask(u32::MAX, t, b))
        {
            return true;
        }
        self.instances_along(
            origin,
            dir,
            || t_max,
            |instance, o, d| {
                let (bvh, first) = &self.meshes[self.placements[instance as usize].mesh as usize];
                bvh.occluded_masked(o, d, t_max, |t, b| mask(instance, t + first, b))
            },
        )
    }

    /// [`occluded_masked`](Self::occluded_masked) with every candidate accepted.
    pub fn occluded(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
        self.occluded_masked(origin, dir, t_max, |_, _, _| true)
    }

    /// Visits the instances whose boxes the ray enters before `t_max()`, nearer boxes first,
    /// calling `visit(instance, origin, direction)` with the ray in the instance's object
    /// space; stops when `visit` returns true, and then returns true.
    #[inline]
    fn instances_along(
        &self,
        origin: Vec3,
        dir: Vec3,
        mut t_max: impl FnMut() -> f32,
        mut visit: impl FnMut(u32, Vec3, Vec3) -> bool,
    ) -> bool {
        if self.nodes.is_empty() || !(origin.is_finite() && dir.is_finite()) || dir == Vec3::ZERO {
            return false;
        }
        let inv = Vec3::from(safe_recip3(dir.into()));
        let mut stack = [0u32; 64];
        let mut top = 0usize;
        let mut node = 0u32;
        loop {
            let n = &self.nodes[node as usize];
            if n.count > 0 {
                let a = &self.placements[n.first as usize].object_from_world;
                if visit(n.first, a.transform_point3(origin), a.transform_vector3(dir)) {
                    return true;
                }
            } else {
                let limit = t_max();
                let (a, b) = (n.first, n.first + 1);
                let ta = enter(&self.nodes[a as usize], origin, inv, limit);
                let tb = enter(&self.nodes[b as usize], origin, inv, limit);
                match (ta, tb) {
                    (Some(ta), Some(tb)) => {
                        let (near, far) = if ta <= tb { (a, b) } else { (b, a) };
                        if top < stack.len() {
                            stack[top] = far;
                            top += 1;
                            node = near;
                            continue;
                        }
                        // A TLAS deeper than the stack (never built: PLOC's trees over 2²⁴
                        // instances stay far shallower) visits the far child's subtree later
                        // by recursion instead of losing it.
                        if self.subtree(far, origin, dir, inv, &mut t_max, &mut visit) {
                            return true;
                        }
                        node = near;
                        continue;
                    }
                    (Some(_), None) => {
                        node = a;
                        continue;
                    }
                    (None, Some(_)) => {
                        node = b;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // Pop the next subtree still entered before the closest hit.
            loop {
                if top == 0 {
                    return false;
                }
                top -= 1;
                node = stack[top];
                if enter(&self.nodes[node as usize], origin, inv, t_max()).is_some() {
                    break;
                }
            }
        }
    }

    /// The subtree under `node`, recursively (the deep-tree fallback of `instances_along`).
    fn subtree(
        &self,
        node: u32,
        origin: Vec3,
        dir: Vec3,
        inv: Vec3,
        t_max: &mut impl FnMut() -> f32,
        visit: &mut impl FnMut(u32, Vec3, Vec3) -> bool,
    ) -> bool {
        let n = &self.nodes[node as usize];
        if enter(n, origin, inv, t_max()).is_none() {
            return false;
        }
        if n.count > 0 {
            let a = &self.placements[n.first as usize].object_from_world;
            return visit(n.first, a.transform_point3(origin), a.transform_vector3(dir));
        }
        self.subtree(n.first, origin, dir, inv, t_max, visit)
            || self.subtree(n.first + 1, origin, dir, inv, t_max, visit)
    }
}

/// The ray's entry distance into `node`'s box if it enters before `t_max` (slab test; the
/// exit distance widened by 2γ₃ as Ize's robust traversal does, so that rounding cannot turn a
/// grazing hit into a miss).
#[inline(always)]
fn enter(node: &TlasNode, origin: Vec3, inv: Vec3, t_max: f32) -> Option<f32> {
    let t0 = (Vec3::from(node.min) - origin) * inv;
    let t1 = (Vec3::from(node.max) - origin) * inv;
    let near = t0.min(t1).max_element().max(0.0);
    let far = t0.max(t1).min_element() * (1.0 + 2.0 * GAMMA3);
    (near <= far && near < t_max).then_some(near)
}

/// γ₃ = 3ε/(1 − 3ε), ε = 2⁻²⁴ (pbrt's `gamma(3)`).
const GAMMA3: f32 = 3.0 * 5.960_464_5e-8 / (1.0 - 3.0 * 5.960_464_5e-8);

/// The TLAS over `aabbs` (the boxes of instances `ids`): obvhs's PLOC builder, as 32-byte
/// nodes whose leaves name their instance.
fn tlas(aabbs: &[Aabb], ids: &[u32]) -> Vec<TlasNode> {
    if aabbs.is_empty() {
        return Vec::new();
    }
    let params = obvhs::BvhBuildParams::medium_build();
    let bvh2 = PlocBuilder::with_capacity(aabbs.len()).build(
        params.ploc_search_distance,
        aabbs,
        (0..aabbs.len() as u32).collect(),
        params.sort_precision,
        params.search_depth_threshold,
    );
    // PLOC makes one leaf per box and no leaf of several (no collapsing pass runs here).
    bvh2.nodes
        .iter()
        .map(|n| {
            assert!(n.prim_count <= 1, "a TLAS leaf of {} instances", n.prim_count);
            let first = match n.prim_count {
                0 => n.first_index,
                _ => ids[bvh2.primitive_indices[n.first_index as usize] as usize],
            };
            TlasNode { min: n.aabb.min.to_array(), count: n.prim_count, max: n.aabb.max.to_array(), first }
        })
        .collect()
}
