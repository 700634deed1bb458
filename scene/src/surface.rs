//! What an integrator needs at a ray hit: the surface point with its geometric and shading
//! normals ([`Scene::surface_point`], [`geometric_normal`]) and the alpha test
//! ([`Scene::alpha_passes`]). The CPU integrator calls these; `furnace-gpu`'s `scene.wgsl` is
//! their twin.

use crate::{AlphaMode, Material, Scene, VertexAttributes};
use glam::Vec3;

/// Where a ray hit a surface, in world space, with normals oriented towards the incoming ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// The hit position, from the barycentrics.
    pub position: Vec3,
    /// Geometric normal (for ray offsets and the geometric side test).
    pub geometric: Vec3,
    /// Shading normal (interpolated, normal-mapped): the z axis of the BSDF frame.
    pub shading: Vec3,
    /// The ray hit the back of a double-sided surface (both normals were flipped to face it).
    /// Emission is one-sided: the back of an emitter does not emit.
    pub back_face: bool,
}

/// The unit normal `(v1 − v0) × (v2 − v0)` of a triangle, or zero if it has none.
///
/// `normalize_or_zero` squares the cross product's length, which overflows `f32` once the
/// edges pass ~4e9 (|cross|² > 3.4e38) and underflows below ~1e-10 (|cross|² < 1e-45), giving a
/// zero normal that would end every path at such a triangle. Then the cross product is first
/// divided by its largest component, which is exact enough for a direction; elsewhere the
/// result is bit-identical to `normalize_or_zero` (the GPU twin's).
#[inline]
pub fn geometric_normal(v0: Vec3, v1: Vec3, v2: Vec3) -> Vec3 {
    let c = (v1 - v0).cross(v2 - v0);
    let n = c.normalize_or_zero();
    if n != Vec3::ZERO || !c.is_finite() {
        return n;
    }
    let m = c.abs().max_element();
    if m > 0.0 { (c / m).normalize_or_zero() } else { Vec3::ZERO }
}

impl Scene {
    /// The surface at a hit of triangle `t` at barycentrics `(b1, b2)` by a ray travelling along
    /// `direction`: the position, the geometric normal, and the shading normal — `interpolated`
    /// (the vertex normals' interpolation, [`crate::Geometry::shading_normal`]; the geometric
    /// normal where it is `None` or zero) with `material`'s glTF normal map applied at `at`
    /// through the vertex tangents — both turned towards the incoming ray for a double-sided
    /// material. `None` on the back of a single-sided material (black, like a one-sided BSDF)
    /// or for a triangle out of range.
    pub fn surface_point(
        &self,
        t: usize,
        (b1, b2): (f32, f32),
        material: &Material,
        at: &VertexAttributes,
        direction: Vec3,
        interpolated: Option<Vec3>,
    ) -> Option<SurfacePoint> {
        let g = &self.geometry;
        let [v0, v1, v2] = g.triangle(t)?;
        let position = (1.0 - b1 - b2) * v0 + b1 * v1 + b2 * v2;
        let mut geometric = geometric_normal(v0, v1, v2);
        let mut shading = interpolated.filter(|n| *n != Vec3::ZERO).unwrap_or(geometric);
        if let Some(normal_map) = &material.normal_texture
            && let Some(tangent) = g.tangent(t, b1, b2)
        {
            // glTF normal map: tangent-space normal (2·rgb − 1)·(scale, scale, 1) in the frame
            // (T, B = w·N×T, N), with T made orthogonal to the shading normal N.
            let m = normal_map.sample(at, &self.textures, &self.images).truncate();
            let m = (2.0 * m - Vec3::ONE) * Vec3::new(material.normal_scale, material.normal_scale, 1.0);
            let tn = (tangent.truncate() - shading * shading.dot(tangent.truncate())).normalize_or_zero();
            if tn != Vec3::ZERO {
                let bn = tangent.w * shading.cross(tn);
                shading = (m.x * tn + m.y * bn + m.z * shading).normalize_or(shading);
            }
        }
        let back_face = geometric.dot(direction) > 0.0;
        if back_face {
            if !material.double_sided {
                return None;
            }
            geometric = -geometric;
            shading = -shading;
        }
        Some(SurfacePoint { position, geometric, shading, back_face })
    }

    /// The alpha test of a hit of triangle `t` (of `material`) at barycentrics `(b1, b2)`: true
    /// unless the material is alpha-masked and `baseColorFactor.a × base colour texture alpha ×
    /// vertex alpha` there is below its cutoff.
    pub fn alpha_passes(&self, t: usize, (b1, b2): (f32, f32), material: &Material) -> bool {
        if !matches!(material.alpha_mode, AlphaMode::Mask { .. }) {
            return true;
        }
        let at = self.geometry.attributes(t, b1, b2);
        let texture = material.base_color_texture.as_ref();
        let alpha = material.base_color_factor.w
            * texture.map_or(1.0, |t| t.sample(&at, &self.textures, &self.images).w)
            * at.color.w;
        material.alpha_test(alpha)
    }
}
