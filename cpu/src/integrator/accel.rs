//! The scene's acceleration structure: one BVH over world-space triangles, or, for a scene
//! with shared meshes, furnace-accel's two-level structure (a BVH per mesh under a TLAS of
//! instances). A scene without instances keeps the one BVH: it pays nothing for instancing.

use furnace_accel::{BuildOptions, Bvh, Hit, TwoLevel};
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

    /// The closest hit `mask(instance, triangle, barycentrics)` accepts, with its instance
    /// ([`WORLD`] for a world-space triangle: a plain index, not an `Option`, so that the hit
    /// stays as small as the one-level query's).
    #[inline]
    pub(super) fn closest_hit_masked(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_max: f32,
        mut mask: impl FnMut(u32, u32, Vec2) -> bool,
    ) -> Option<(Hit, u32)> {
        match self {
            Accel::Flat(b) => {
                b.closest_hit_masked(origin, dir, t_max, |t, uv| mask(WORLD, t, uv)).map(|h| (h, WORLD))
            }
            Accel::TwoLevel(b) => two_level_closest(b, origin, dir, t_max, mask),
        }
    }

    /// The closest hit.
    #[inline]
    pub(super) fn closest_hit(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<(Hit, u32)> {
        match self {
            Accel::Flat(b) => b.closest_hit(origin, dir, t_max).map(|h| (h, WORLD)),
            Accel::TwoLevel(b) => two_level_closest(b, origin, dir, t_max, |_, _, _| true),
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
            Accel::TwoLevel(b) => two_level_occluded(b, origin, dir, t_max, mask),
        }
    }

    /// Whether any triangle lies along the ray before `t_max`.
    #[inline]
    pub(super) fn occluded(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
        match self {
            Accel::Flat(b) => b.occluded(origin, dir, t_max),
            Accel::TwoLevel(b) => two_level_occluded(b, origin, dir, t_max, |_, _, _| true),
        }
    }
}

// The two-level queries out of line: inlined, their TLAS loop made the integrator's loop larger
// for every scene, with or without instances (measured: the Cornell box 6 % slower).
#[inline(never)]
fn two_level_closest(
    b: &TwoLevel,
    origin: Vec3,
    dir: Vec3,
    t_max: f32,
    mask: impl FnMut(u32, u32, Vec2) -> bool,
) -> Option<(Hit, u32)> {
    b.closest_hit_masked(origin, dir, t_max, mask).map(|h| (h.hit, h.instance.unwrap_or(WORLD)))
}

#[inline(never)]
fn two_level_occluded(
    b: &TwoLevel,
    origin: Vec3,
    dir: Vec3,
    t_max: f32,
    mask: impl FnMut(u32, u32, Vec2) -> bool,
) -> bool {
    b.occluded_masked(origin, dir, t_max, mask)
}
