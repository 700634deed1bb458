//! What an integrator needs at a ray hit: the surface point with its geometric and shading
//! normals ([`Scene::surface_point`], [`geometric_normal`]), the alpha test
//! ([`Scene::alpha_passes`]) and the coverage of blended surfaces ([`Scene::coverage`],
//! [`blend_keeps`]). The CPU integrator calls these; `furnace-gpu`'s `scene.wgsl` is
//! their twin.

use crate::{AlphaMode, Instance, Material, Scene, VertexAttributes};
use furnace_sampling::hash::{hash2, hash3};
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
    /// The clear coat's normal (KHR_materials_clearcoat): the interpolated normal with the
    /// coat's own normal map, not the base's; the shading normal for a material without a coat.
    pub coat: Vec3,
    /// The ray hit the back of a double-sided surface (both normals were flipped to face it).
    /// Emission is one-sided: the back of an emitter does not emit.
    pub back_face: bool,
    /// KHR_materials_anisotropy's direction: a unit vector orthogonal to `shading`, the x axis
    /// of the BSDF frame; `None` without anisotropy (or without tangents to place it by).
    pub anisotropy: Option<Vec3>,
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

/// The shading normal `n` bent towards the geometric normal `ng` just enough that the mirror
/// reflection of the view direction `wo` about it leaves the surface at least
/// `min(0.9·(wo·ng), 0.01)` above it; `n` itself where it already does (Cycles'
/// `ensure_valid_specular_reflection`; Schüssler et al., "Microfacet-based Normal Mapping for
/// Robust Monte Carlo Path Tracing", 2017, on why). A normal map can tilt the shading normal
/// until the viewer is below it, where a BSDF reflects nothing: black patches on a bumpy cloth
/// seen at a grazing angle. The bent normal lies in the plane of `n` and `ng`, its height `z`
/// above the surface the root of `4a·z⁴ − 2b·z² + c = 0` that puts the reflection at the
/// threshold (with `wo = (ix, ·, iz)` in the frame (x, ·, ng), x the direction of `n` across
/// `ng`: `a = ix² + iz²`, `b = 2(a + iz·t)`, `c = (t + iz)²`). All three unit, `ng` facing
/// `wo`.
pub fn valid_reflection_normal(ng: Vec3, wo: Vec3, n: Vec3) -> Vec3 {
    let iz = wo.dot(ng);
    let t = (0.9 * iz).min(0.01);
    let r = 2.0 * n.dot(wo) * n - wo;
    if !(iz > 0.0) || r.dot(ng) >= t {
        return n;
    }
    let x = (n - ng * n.dot(ng)).normalize_or_zero();
    if x == Vec3::ZERO {
        return ng;
    }
    let ix = wo.dot(x);
    let a = ix * ix + iz * iz;
    let b = 2.0 * (a + iz * t);
    let c = (t + iz) * (t + iz);
    let root = (b * b - 4.0 * a * c).max(0.0).sqrt();
    // The larger root z² where wo leans away from x (the reflection must tilt back over ng),
    // else the smaller; z² and 1 − z² each from a form without cancellation (a grazing view
    // needs a normal within 10⁻⁵ of ng, whose 1 − z² is below f32's resolution of z² near 1).
    let (z2, x2) = if ix < 0.0 {
        (0.25 * (b + root) / a, (iz - t) * (iz - t) / (2.0 * (a - iz * t) + root))
    } else {
        (c / (b + root), 0.25 * (2.0 * (a - iz * t) + root) / a)
    };
    (x * x2.clamp(0.0, 1.0).sqrt() + ng * z2.clamp(0.0, 1.0).sqrt()).normalize_or(ng)
}

impl Scene {
    /// The surface at a hit of triangle `t` at barycentrics `(b1, b2)` by a ray travelling along
    /// `direction`: the position, the geometric normal, and the shading normal — `interpolated`
    /// (the vertex normals' interpolation, [`crate::Geometry::shading_normal`]; the geometric
    /// normal where it is `None` or zero) with `material`'s glTF normal map applied at `at`
    /// through the vertex tangents — both turned towards the incoming ray for a double-sided
    /// material. `None` on the back of a single-sided material (black, like a one-sided BSDF)
    /// or for a triangle out of range. A triangle of a shared mesh is placed by its `instance`
    /// (`interpolated` is then already in world space); `None` for a world-space one.
    #[allow(clippy::too_many_arguments)]
    pub fn surface_point(
        &self,
        instance: Option<&Instance>,
        t: usize,
        (b1, b2): (f32, f32),
        material: &Material,
        at: &VertexAttributes,
        direction: Vec3,
        interpolated: Option<Vec3>,
    ) -> Option<SurfacePoint> {
        let g = &self.geometry;
        let mut vertices = g.triangle(t)?;
        if let Some(i) = instance {
            vertices = vertices.map(|v| i.point(v));
        }
        let [v0, v1, v2] = vertices;
        let position = (1.0 - b1 - b2) * v0 + b1 * v1 + b2 * v2;
        // A mirroring instance turns the winding: its front stays the mesh's front.
        let mut geometric = geometric_normal(v0, v1, v2);
        if instance.is_some_and(Instance::mirrors) {
            geometric = -geometric;
        }
        let base = interpolated.filter(|n| *n != Vec3::ZERO).unwrap_or(geometric);
        let mut shading = self.normal_mapped(
            instance,
            t,
            (b1, b2),
            base,
            material.normal_texture.as_ref(),
            material.normal_scale,
            at,
        );
        let mut coat = match &material.layers.clearcoat {
            Some(c) => {
                self.normal_mapped(instance, t, (b1, b2), base, c.normal_texture.as_ref(), c.normal_scale, at)
            }
            None => shading,
        };
        // Before the flip: the back of a double-sided surface has the front's direction (the
        // same line on the surface; the lobe is symmetric about it).
        let anisotropy = material
            .anisotropy
            .as_ref()
            .and_then(|a| self.anisotropy_direction(instance, t, (b1, b2), shading, a, at));
        let mapped = shading != base;
        let back_face = geometric.dot(direction) > 0.0;
        if back_face {
            if !material.double_sided {
                return None;
            }
            geometric = -geometric;
            shading = -shading;
            coat = -coat;
        }
        if mapped {
            shading = valid_reflection_normal(geometric, -direction, shading);
        }
        Some(SurfacePoint { position, geometric, shading, coat, back_face, anisotropy })
    }

    /// KHR_materials_anisotropy's direction at a hit: `(cos r, sin r)` — or, with the texture,
    /// `2·rg − 1` rotated by r — in the tangent frame (T, B = w·N×T), made orthogonal to the
    /// shading `normal` and unit. `None` without tangents or where the direction vanishes.
    fn anisotropy_direction(
        &self,
        instance: Option<&Instance>,
        t: usize,
        (b1, b2): (f32, f32),
        normal: Vec3,
        anisotropy: &crate::Anisotropy,
        at: &VertexAttributes,
    ) -> Option<Vec3> {
        let tangent = self.world_tangent(instance, t, (b1, b2))?;
        let d = match &anisotropy.texture {
            Some(map) => {
                let rg = map.sample(at, &self.textures, &self.images);
                glam::Vec2::new(2.0 * rg.x - 1.0, 2.0 * rg.y - 1.0)
            }
            None => glam::Vec2::X,
        };
        let (s, c) = anisotropy.rotation.sin_cos();
        let d = glam::Vec2::new(c * d.x - s * d.y, s * d.x + c * d.y);
        let tn = tangent.truncate();
        let bn = tangent.w * normal.cross(tn);
        let dir = d.x * tn + d.y * bn;
        let dir = dir - normal * normal.dot(dir);
        let dir = dir.normalize_or_zero();
        (dir != Vec3::ZERO).then_some(dir)
    }

    /// `normal` with a glTF normal map applied at `at` through the vertex tangents: the
    /// tangent-space normal (2·rgb − 1)·(scale, scale, 1) in the frame (T, B = w·N×T, N), with T
    /// made orthogonal to N. `normal` itself without a map or tangents.
    #[allow(clippy::too_many_arguments)]
    fn normal_mapped(
        &self,
        instance: Option<&Instance>,
        t: usize,
        (b1, b2): (f32, f32),
        normal: Vec3,
        map: Option<&crate::texture::TextureRef>,
        scale: f32,
        at: &VertexAttributes,
    ) -> Vec3 {
        let (Some(map), Some(tangent)) = (map, self.world_tangent(instance, t, (b1, b2))) else {
            return normal;
        };
        let m = map.sample(at, &self.textures, &self.images).truncate();
        let m = (2.0 * m - Vec3::ONE) * Vec3::new(scale, scale, 1.0);
        let tn = (tangent.truncate() - normal * normal.dot(tangent.truncate())).normalize_or_zero();
        if tn == Vec3::ZERO {
            return normal;
        }
        let bn = tangent.w * normal.cross(tn);
        (m.x * tn + m.y * bn + m.z * normal).normalize_or(normal)
    }

    /// [`crate::Geometry::tangent`] in world space: carried by `instance` for a shared mesh's
    /// triangle.
    fn world_tangent(
        &self,
        instance: Option<&Instance>,
        t: usize,
        (b1, b2): (f32, f32),
    ) -> Option<glam::Vec4> {
        let tangent = self.geometry.tangent(t, b1, b2)?;
        Some(instance.map_or(tangent, |i| i.tangent(tangent)))
    }

    /// The alpha test of a hit of triangle `t` (of `material`) at barycentrics `(b1, b2)`: true
    /// unless the material is alpha-masked and `baseColorFactor.a × base colour texture alpha ×
    /// vertex alpha` there is below its cutoff.
    pub fn alpha_passes(&self, t: usize, (b1, b2): (f32, f32), material: &Material) -> bool {
        if !matches!(material.alpha_mode, AlphaMode::Mask { .. }) {
            return true;
        }
        material.alpha_test(self.alpha_at(t, (b1, b2), material))
    }

    /// The coverage of a hit of triangle `t` (of `material`) at barycentrics `(b1, b2)`: the
    /// fraction of light the surface stops there. 1 for an opaque material, 0 or 1 for a masked
    /// one ([`Scene::alpha_passes`]), and for a blended one its alpha clamped to [0, 1] (0 for
    /// a NaN alpha: a surface of undefined alpha is left out rather than drawn opaque).
    pub fn coverage(&self, t: usize, (b1, b2): (f32, f32), material: &Material) -> f32 {
        match material.alpha_mode {
            AlphaMode::Opaque => 1.0,
            AlphaMode::Mask { .. } => f32::from(u8::from(self.alpha_passes(t, (b1, b2), material))),
            AlphaMode::Blend => {
                let a = self.alpha_at(t, (b1, b2), material);
                if a > 0.0 { a.min(1.0) } else { 0.0 }
            }
        }
    }

    /// `baseColorFactor.a × base colour texture alpha × vertex alpha` at a hit.
    fn alpha_at(&self, t: usize, (b1, b2): (f32, f32), material: &Material) -> f32 {
        let at = self.geometry.attributes(t, b1, b2);
        let texture = material.base_color_texture.as_ref();
        material.base_color_factor.w
            * texture.map_or(1.0, |t| t.sample(&at, &self.textures, &self.images).w)
            * at.color.w
    }
}

/// The seed of a ray's stochastic transparency: a hash of its origin's and direction's bits.
/// Every blended triangle the ray meets draws its own number from it ([`blend_keeps`]), so the
/// decision for one triangle is the same however often traversal visits it, and the rays of
/// different samples decide independently. The GPU's `blend_seed_of` (the integrator's shadow.wgsl) is the twin.
#[inline]
pub fn blend_seed(origin: Vec3, direction: Vec3) -> u32 {
    let b = |v: Vec3| hash3(v.x.to_bits(), v.y.to_bits(), v.z.to_bits());
    hash2(b(origin), b(direction))
}

/// Stochastic transparency: whether a ray of `seed` ([`blend_seed`]) stops at triangle `t` of
/// `coverage` ([`Scene::coverage`]), with probability `coverage`; else it passes straight on,
/// so a surface of alpha α is seen in a fraction α of the paths. The number drawn is the top 24
/// bits of a hash, exact in `f32`: `u < 1` always stops at a coverage of 1 and never at 0.
#[inline]
pub fn blend_keeps(seed: u32, t: u32, coverage: f32) -> bool {
    let u = (hash2(seed, t) >> 8) as f32 * (1.0 / 16_777_216.0);
    u < coverage
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Coverage 1 always stops a ray and 0 never does (whatever the hash), NaN never; in
    /// between, the fraction kept over 10⁵ seeds is the coverage within 5 standard errors
    /// (σ = √(c(1 − c)/10⁵) ≤ 1.6e-3), and two triangles decide independently (the joint
    /// fraction is the product).
    #[test]
    fn blend_keeps_a_ray_with_probability_coverage() {
        let n = 100_000u32;
        let seeds = (0..n).map(|i| blend_seed(Vec3::new(i as f32, 0.5, -2.0), Vec3::new(0.0, 0.6, 0.8)));
        let (mut always, mut never, mut nan) = (true, false, false);
        let (mut a, mut b, mut both) = (0u32, 0u32, 0u32);
        for seed in seeds {
            always &= blend_keeps(seed, 7, 1.0);
            never |= blend_keeps(seed, 7, 0.0);
            nan |= blend_keeps(seed, 7, f32::NAN);
            let (ka, kb) = (blend_keeps(seed, 7, 0.3), blend_keeps(seed, 8, 0.6));
            a += u32::from(ka);
            b += u32::from(kb);
            both += u32::from(ka && kb);
        }
        assert!(always && !never && !nan);
        let f = |k: u32| f64::from(k) / f64::from(n);
        let close = |got: f64, p: f64| (got - p).abs() < 5.0 * (p * (1.0 - p) / f64::from(n)).sqrt();
        assert!(close(f(a), 0.3) && close(f(b), 0.6), "{} {}", f(a), f(b));
        assert!(close(f(both), 0.18), "joint {}", f(both));
    }

    /// `valid_reflection_normal` on 2·10⁵ random configurations (ng fixed, wo and n uniform over
    /// the upper hemisphere, half of wo within 2° of grazing, n also tilted up to 89.9°):
    /// a normal whose reflection is valid comes back unchanged (bit for bit); a bent one is
    /// unit, in the plane of n and ng, on ng's side, and puts the reflection at least at the
    /// threshold `t = min(0.9·iz, 0.01)` and at most as high as ng itself would (`iz`: the bend
    /// stops at ng). Tolerances: 1e-5 for unit length, the plane and the upper bound (f32
    /// rounding of a normalised vector); 10⁻⁶·(1 + 1/√disc) below the threshold, the rounding
    /// of the quadratic's root, which grows as its discriminant (relative to b²) vanishes: five
    /// times the worst measured, 2.1·10⁻⁷/√disc.
    #[test]
    fn bent_normals_reflect_the_view_just_above_the_surface() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut u = move || {
            state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            ((state >> 40) as f32) / (1u64 << 24) as f32
        };
        let ng = Vec3::Z;
        let (mut bent, mut at_threshold, mut worst) = (0, 0, 0.0f32);
        for k in 0..200_000 {
            let phi = std::f32::consts::TAU * u();
            let iz = if k % 2 == 0 { u() } else { (2f32.to_radians() * u()).sin() }.max(1e-7);
            let wo = Vec3::new((1.0 - iz * iz).sqrt() * phi.cos(), (1.0 - iz * iz).sqrt() * phi.sin(), iz);
            let (theta, psi) = (89.9f32.to_radians() * u().sqrt(), std::f32::consts::TAU * u());
            let n = Vec3::new(theta.sin() * psi.cos(), theta.sin() * psi.sin(), theta.cos());
            let b = valid_reflection_normal(ng, wo, n);
            let t = (0.9 * iz).min(0.01);
            let height = |m: Vec3| (2.0 * m.dot(wo) * m - wo).dot(ng);
            if height(n) >= t {
                assert_eq!(b.to_array().map(f32::to_bits), n.to_array().map(f32::to_bits), "wo {wo} n {n}");
                continue;
            }
            bent += 1;
            assert!(b.is_finite() && (b.length() - 1.0).abs() < 1e-5, "wo {wo} n {n}: {b}");
            assert!(b.dot(ng.cross(n).normalize_or_zero()).abs() < 1e-5 && b.z > 0.0, "wo {wo} n {n}: {b}");
            // The discriminant of the quadratic in z², from the same quantities.
            let x = (n - ng * n.dot(ng)).normalize();
            let (ix, a) = (wo.dot(x), wo.dot(x).powi(2) + iz * iz);
            let (bq, c) = (2.0 * (a + iz * t), (t + iz) * (t + iz));
            let disc = (bq * bq - 4.0 * a * c).max(1e-12) / (bq * bq);
            let h = height(b);
            let below = (t - h).max(0.0);
            worst = worst.max(below * disc.sqrt());
            at_threshold += usize::from((h - t).abs() < 1e-4);
            assert!(below < 1e-6 * (1.0 + 1.0 / disc.sqrt()), "wo {wo} n {n} (ix {ix}): height {h} for {t}");
            assert!(h <= iz + 1e-5, "wo {wo} n {n} (ix {ix}): height {h} above ng's {iz}");
        }
        println!(
            "{bent} of 200000 normals bent, {at_threshold} to within 1e-4 of the threshold; \
             worst shortfall × √disc {worst:e}"
        );
        assert!(bent > 10_000, "the configurations must exercise the bend");
    }
}
