//! The scene's acceleration structure: one BVH over world-space triangles, or, for a scene
//! with shared meshes, furnace-accel's two-level structure (a BVH per mesh under a TLAS of
//! instances). A scene without instances keeps the one BVH: it pays nothing for instancing.
//!
//! The path loop is generic over [`Trace`] and compiled once per structure ([`Tracer`]): the
//! loop a scene without instances runs holds no two-level code, whose calls (even out of line)
//! cost a one-level scene several percent in register pressure and code layout.

use super::CpuRenderer;
use furnace_accel::{Bvh, Hit, SceneAccel, TwoLevel};
use furnace_scene::{Instance, Scene};
use glam::{Vec2, Vec3};

/// The instance argument of a mask for a world-space triangle.
pub(super) const WORLD: u32 = u32::MAX;

/// The structure for `scene`'s triangles and instances: one BVH without instances, else the
/// world triangles' BVH and one per shared mesh under a TLAS.
pub(super) fn scene_accel(scene: &Scene) -> SceneAccel {
    let g = &scene.geometry;
    let inst = &scene.instancing;
    let placements: Vec<_> = inst.instances.iter().map(|i| (i.mesh, i.world_from_object)).collect();
    SceneAccel::build(&g.positions, &g.triangles, 0..inst.world_triangles, &inst.meshes, &placements)
}

/// The ray queries of the path loop. Hits come with their instance ([`WORLD`] for a
/// world-space triangle: a plain index, not an `Option`, so that the hit stays as small as the
/// one-level query's); masks are called with `(instance, triangle, barycentrics)`.
pub(super) trait Trace: Sync {
    /// Whether hits may lie in instances (otherwise every hit's instance is [`WORLD`]).
    const INSTANCED: bool;

    /// The closest hit `mask` accepts.
    fn closest_hit_masked(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_max: f32,
        mask: impl FnMut(u32, u32, Vec2) -> bool,
    ) -> Option<(Hit, u32)>;

    /// The closest hit.
    fn closest_hit(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<(Hit, u32)>;

    /// Whether a triangle `mask` accepts lies along the ray before `t_max`.
    fn occluded_masked(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_max: f32,
        mask: impl FnMut(u32, u32, Vec2) -> bool,
    ) -> bool;

    /// Whether any triangle lies along the ray before `t_max`.
    fn occluded(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool;
}

impl Trace for Bvh {
    const INSTANCED: bool = false;

    #[inline]
    fn closest_hit_masked(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_max: f32,
        mut mask: impl FnMut(u32, u32, Vec2) -> bool,
    ) -> Option<(Hit, u32)> {
        Bvh::closest_hit_masked(self, origin, dir, t_max, |t, uv| mask(WORLD, t, uv)).map(|h| (h, WORLD))
    }

    #[inline]
    fn closest_hit(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<(Hit, u32)> {
        Bvh::closest_hit(self, origin, dir, t_max).map(|h| (h, WORLD))
    }

    #[inline]
    fn occluded_masked(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_max: f32,
        mut mask: impl FnMut(u32, u32, Vec2) -> bool,
    ) -> bool {
        Bvh::occluded_masked(self, origin, dir, t_max, |t, uv| mask(WORLD, t, uv))
    }

    #[inline]
    fn occluded(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
        Bvh::occluded(self, origin, dir, t_max)
    }
}

impl Trace for TwoLevel {
    const INSTANCED: bool = true;

    #[inline]
    fn closest_hit_masked(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_max: f32,
        mask: impl FnMut(u32, u32, Vec2) -> bool,
    ) -> Option<(Hit, u32)> {
        TwoLevel::closest_hit_masked(self, origin, dir, t_max, mask)
            .map(|h| (h.hit, h.instance.unwrap_or(WORLD)))
    }

    #[inline]
    fn closest_hit(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<(Hit, u32)> {
        Trace::closest_hit_masked(self, origin, dir, t_max, |_, _, _| true)
    }

    #[inline]
    fn occluded_masked(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_max: f32,
        mask: impl FnMut(u32, u32, Vec2) -> bool,
    ) -> bool {
        TwoLevel::occluded_masked(self, origin, dir, t_max, mask)
    }

    #[inline]
    fn occluded(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
        TwoLevel::occluded_masked(self, origin, dir, t_max, |_, _, _| true)
    }
}

/// The renderer with the structure its rays are traced against: the path loop's `self`
/// (everything else of the renderer through `Deref`).
pub(super) struct Tracer<'a, A> {
    pub renderer: &'a CpuRenderer,
    pub accel: &'a A,
}

impl<A> std::ops::Deref for Tracer<'_, A> {
    type Target = CpuRenderer;

    #[inline]
    fn deref(&self) -> &CpuRenderer {
        self.renderer
    }
}

impl<A: Trace> Tracer<'_, A> {
    /// Instance `instance` of the scene (`None` for [`WORLD`], and always for a structure
    /// without instances).
    #[inline]
    pub(super) fn instance(&self, instance: u32) -> Option<&Instance> {
        if A::INSTANCED { self.renderer.instance(instance) } else { None }
    }
}
