//! The scene's acceleration structure: one BVH over world-space triangles, or, for a scene
//! with shared meshes, furnace-accel's two-level structure (a BVH per mesh under a TLAS of
//! instances). A scene without instances keeps the one BVH: it pays nothing for instancing.

use furnace_accel::{BuildOptions, Bvh, InstanceHit, TwoLevel};
use furnace_scene::Scene;
use glam::{Vec2, Vec3};

/// What the integrator traces rays against.
pub(super) enum Accel {
    Flat(Bvh),
    TwoLevel(TwoLevel),
}

/// The instance argument of a mask for a world-space triangle.
pub(super) const WORLD: u32 = u32::MAX;

impl Accel {
    /// The structure for `scene`'s triangles and instances.
    pub(super) fn new(scene: &Scene) -> Self {
        let g = &scene.geometry;
        let inst = &scene.instancing;
        if inst.is_empty() {
            return Accel::Flat(Bvh::from_indexed(&g.positions, &g.triangles, BuildOptions::default()));
        }
        let placements: Vec<_> = inst.instances.iter().map(|i| (i.mesh, i.world_from_object)).collect();
        Accel::TwoLevel(TwoLevel::build(
            &g.positions,
            &g.triangles,
            0..inst.world_triangles,
            &inst.meshes,
            &placements,
        ))
    }

    /// The closest hit `mask(instance, triangle, barycentrics)` accepts (`instance` is
    /// [`WORLD`] for a world-space triangle).
    #[inline]
    pub(super) fn closest_hit_masked(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_max: f32,
        mut mask: impl FnMut(u32, u32, Vec2) -> bool,
    ) -> Option<InstanceHit> {
        match self {
            Accel::Flat(b) => b
                .closest_hit_masked(origin, dir, t_max, |t, uv| mask(WORLD, t, uv))
                .map(|hit| InstanceHit { hit, instance: None }),
            Accel::TwoLevel(b) => b.closest_hit_masked(origin, dir, t_max, mask),
        }
    }

    /// The closest hit.
    #[inline]
    pub(super) fn closest_hit(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<InstanceHit> {
        match self {
            Accel::Flat(b) => {
                b.closest_hit(origin, dir, t_max).map(|hit| InstanceHit { hit, instance: None })
            }
            Accel::TwoLevel(b) => b.closest_hit(origin, dir, t_max),
        }
    }

    /// Whether a triangle `mask` accepts lies along the ray before `t_max`.
    #[inline]
    pub(super) fn occluded_masked(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_max: f32,
        mut mask: impl FnMut(u32, u32, Vec2) -> bool,
    ) -> bool {
        match self {
            Accel::Flat(b) => b.occluded_masked(origin, dir, t_max, |t, uv| mask(WORLD, t, uv)),
            Accel::TwoLevel(b) => b.occluded_masked(origin, dir, t_max, mask),
        }
    }

    /// Whether any triangle lies along the ray before `t_max`.
    #[inline]
    pub(super) fn occluded(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
        match self {
            Accel::Flat(b) => b.occluded(origin, dir, t_max),
            Accel::TwoLevel(b) => b.occluded(origin, dir, t_max),
        }
    }

    /// Bytes the structure holds.
    pub(super) fn bytes(&self) -> usize {
        match self {
            Accel::Flat(b) => b.bytes(),
            Accel::TwoLevel(b) => b.bytes(),
        }
    }
}
