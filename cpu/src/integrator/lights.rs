//! Light samples of the CPU path tracer: shadow rays to delta suns, point and spot lights, and
//! next-event estimation of emissive triangles, sun discs and the environment map, with the MIS
//! weights of both strategies
//! ([`furnace_render::LightSampling`], [`furnace_render::EnvSampling`]).

use super::accel::{Trace, Tracer};
use furnace_brdf::{Frame, HitBsdf};
use furnace_render::LightSampling;
use furnace_render::layout::{
    self, LIGHT_EMITTER_BIN, LIGHT_EMITTER_POINT, LIGHT_ENVIRONMENT, LIGHT_SUN_DISC,
};
use furnace_sampling::warp::{
    in_cone, square_to_spherical_triangle, square_to_uniform_cone, square_to_uniform_triangle,
    uniform_cone_pdf,
};
use furnace_sampling::{Sampler, to_unit_f32};
use furnace_scene::{Environment, Sun, SurfacePoint, geometric_normal, triangle_area};
use glam::{Vec2, Vec3};

/// A sun disc, with what its sampling needs formed once.
#[derive(Debug, Clone, Copy)]
pub(super) struct SunDisc {
    /// Unit direction towards the sun (the cone's axis).
    pub axis: Vec3,
    /// `1 − cos θ` of the disc's half-angle ([`Sun::one_minus_cos`]).
    pub one_minus_cos: f32,
    /// Solid-angle pdf of a direction sampled in the cone.
    pub pdf: f32,
    /// Radiance seen inside the cone.
    pub radiance: Vec3,
    /// `f · cos · L / pdf` per unit `f · cos` ([`Sun::cone_estimate`]).
    pub estimate: Vec3,
}

impl SunDisc {
    pub fn new(sun: &Sun) -> Self {
        let one_minus_cos = sun.one_minus_cos();
        Self {
            axis: -sun.direction,
            one_minus_cos,
            pdf: uniform_cone_pdf(one_minus_cos),
            radiance: sun.radiance(),
            estimate: sun.cone_estimate(),
        }
    }
}

/// What a light sample needs of the scattering event it is taken at.
pub(super) struct Vertex<'a> {
    pub throughput: Vec3,
    pub bsdf: &'a HitBsdf,
    pub wo: Vec3,
    pub frame: Frame,
    pub surface: &'a SurfacePoint,
    /// The offset origin of rays leaving the surface on the side it was reached from (the
    /// side of `surface.geometric`); light samples are taken from this point.
    pub leave: Vec3,
    /// The offset origin on the other side, for a BSDF that transmits light from there (a rough
    /// dielectric); `None` for a one-sided reflection.
    pub leave_behind: Option<Vec3>,
    /// The absorption coefficient of the volume the vertex is in (0 in air).
    pub medium: Vec3,
}

impl Vertex<'_> {
    /// The origin of a shadow ray along `wi`: `leave` above the surface, `leave_behind` below
    /// it where the BSDF transmits; `None` where it does neither.
    #[inline]
    pub fn origin_towards(&self, wi: Vec3) -> Option<Vec3> {
        let side = wi.dot(self.surface.geometric);
        if side > 0.0 {
            Some(self.leave)
        } else if side < 0.0 {
            self.leave_behind
        } else {
            None
        }
    }

    /// The receiving side for the light BVH's importance: the geometric normal, or none
    /// (zero) for a vertex lit from both sides.
    #[inline]
    pub fn receiver_normal(&self) -> Vec3 {
        if self.leave_behind.is_some() { Vec3::ZERO } else { self.surface.geometric }
    }
}

impl<A: Trace> Tracer<'_, A> {
    /// The lights gathered at a non-delta scattering event (throughput included): a shadow ray
    /// to each delta sun, point and spot light, and one light sample each of the emitters, sun
    /// discs and environment (next-event estimation).
    pub(super) fn light_samples(
        &self,
        pixel: u32,
        index: u32,
        event: u32,
        v: &Vertex<'_>,
        radiance: &mut Vec3,
    ) {
        // Delta suns: gathered by a shadow ray only.
        for sun in &self.suns {
            let to_sun = -sun.direction;
            if let Some(origin) = v.origin_towards(to_sun) {
                let f = v.bsdf.eval(v.wo, v.frame.to_local(to_sun));
                if f != Vec3::ZERO {
                    let contribution = v.throughput * f * sun.irradiance;
                    *radiance += contribution * self.transmittance(origin, to_sun, f32::INFINITY, v.medium);
                }
            }
        }

        // Point and spot lights, delta lights too: a shadow ray to each, or to one chosen by
        // power (`--point-lights one`; none to choose when no light has power).
        if !self.point_lights.is_empty() {
            *radiance += if self.one_point_light {
                self.sample_point_light(pixel, index, event, v)
            } else {
                self.gather_point_lights(v)
            };
        }

        // Emitters, sun discs and the environment: one light sample each.
        if self.settings.light_sampling != LightSampling::Bsdf
            && (self.emitters.is_some() || !self.sun_discs.is_empty() || self.env_sampler.is_some())
        {
            if self.emitters.is_some() {
                *radiance += self.sample_emitter(pixel, index, event, v);
            }
            if !self.sun_discs.is_empty() {
                *radiance += self.sample_sun_discs(pixel, index, event, v);
            }
            if self.env_sampler.is_some() {
                *radiance += self.sample_environment(pixel, index, event, v);
            }
        }
    }

    /// What the point and spot lights add at a scattering event (throughput included): a
    /// shadow ray to each, stopping `SHADOW_EPSILON·d` short of it; a contribution that is not
    /// finite (a light on the surface, d → 0) adds nothing. Summed over the lights first (the
    /// WGSL twin does so for many lights; for a few it adds each light's share after its queued
    /// shadow ray: the same to float rounding).
    fn gather_point_lights(&self, v: &Vertex<'_>) -> Vec3 {
        let mut sum = Vec3::ZERO;
        for light in &self.point_lights {
            sum += self.point_light(light, v);
        }
        sum
    }

    /// What one point or spot light, chosen by power with the sampler's dimension
    /// [`layout::point_light`] of event `event`, adds at a scattering event: its share divided
    /// by the probability of the choice (`--point-lights one`; the WGSL twin chooses with the
    /// same table and comparisons).
    fn sample_point_light(&self, pixel: u32, index: u32, event: u32, v: &Vertex<'_>) -> Vec3 {
        let Some(choice) = &self.point_choice else {
            return Vec3::ZERO;
        };
        let u = self.sampler.value(pixel, index, layout::point_light(self.settings.bounces, event));
        let (k, pmf) = choice.sample(u);
        self.point_light(&self.point_lights[k], v) / pmf
    }

    /// What `light` adds at a scattering event (throughput included): its shadow ray stops
    /// `SHADOW_EPSILON·d` short of it; a contribution that is not finite (a light on the
    /// surface, d → 0) adds nothing.
    #[inline]
    fn point_light(&self, light: &furnace_scene::PointLight, v: &Vertex<'_>) -> Vec3 {
        let to_light = light.position - v.surface.position;
        let d2 = to_light.length_squared();
        if !(d2 > 0.0) {
            return Vec3::ZERO;
        }
        let d = d2.sqrt();
        let wi = to_light / d;
        if let Some(origin) = v.origin_towards(wi) {
            let li = light.intensity_towards(-wi, d);
            if li != Vec3::ZERO {
                let f = v.bsdf.eval(v.wo, v.frame.to_local(wi));
                let contribution = v.throughput * f * li / d2;
                if f != Vec3::ZERO && contribution.is_finite() {
                    let t_max = d * (1.0 - furnace_render::SHADOW_EPSILON);
                    return contribution * self.transmittance(origin, wi, t_max, v.medium);
                }
            }
        }
        Vec3::ZERO
    }

    /// One light sample of an emissive triangle at scattering event `event` (throughput
    /// included): the triangle chosen by the light BVH or by power
    /// ([`furnace_render::LightSelection`]), a point on it uniform in solid angle or in area
    /// ([`furnace_render::TriangleSampling`]), a shadow ray stopping `SHADOW_EPSILON·d` short of
    /// it; weighted against BSDF sampling.
    pub(super) fn sample_emitter(&self, pixel: u32, index: u32, event: u32, v: &Vertex<'_>) -> Vec3 {
        let Some(emitters) = &self.emitters else { return Vec3::ZERO };
        let dim = layout::light(self.settings.bounces, event);
        // The bin's bits and the coin are a pair (`LIGHT_EMITTER_COIN = LIGHT_EMITTER_BIN + 1`):
        // one 2-D draw, the same bits as two 1-D ones, cheaper for the pattern samplers. The
        // light BVH descends by the bits alone.
        let [bits, coin] = self.sampler.bits_2d(pixel, index, dim + LIGHT_EMITTER_BIN);
        // The triangle and, for the BVH, its probability (the alias table's follows from the
        // material and the area below).
        let (t, bvh_pmf) = match &self.light_bvh {
            Some(bvh) => match bvh.sample(v.leave, v.receiver_normal(), to_unit_f32(bits)) {
                Some((item, pmf)) => (emitters.triangles()[item] as usize, Some(pmf)),
                None => return Vec3::ZERO, // no emitter can light this point
            },
            None => (emitters.select(bits, to_unit_f32(coin)) as usize, None),
        };
        let Some([v0, v1, v2]) = self.scene.geometry.triangle(t) else { return Vec3::ZERO };
        // Everything is seen from the offset origin the shadow ray starts at (as the BSDF ray's
        // distance to a hit is measured): a point of the emitter's own plane is then strictly
        // behind or in front of it, never lit by it at a rounding-error cosine.
        let (a, b, c) = (v0 - v.leave, v1 - v.leave, v2 - v.leave);
        // One-sided: only the front (the side the winding's normal points to) emits, and a
        // point behind the emitter's plane sees none of it.
        if !(a.dot((v1 - v0).cross(v2 - v0)) < 0.0) {
            return Vec3::ZERO;
        }
        let u = Vec2::from(self.sampler.value_2d(pixel, index, dim + LIGHT_EMITTER_POINT));
        let omega = self.settings.triangle_sampling.solid_angle(a, b, c);
        let bary = match omega {
            Some(omega) => match square_to_spherical_triangle(u, a, b, c, omega) {
                Some((_, bary)) => bary,
                None => return Vec3::ZERO,
            },
            None => square_to_uniform_triangle(u),
        };
        let y = (1.0 - bary.x - bary.y) * v0 + bary.x * v1 + bary.y * v2;
        let to_light = y - v.leave;
        let d2 = to_light.length_squared();
        if !(d2 > 0.0) {
            return Vec3::ZERO;
        }
        let d = d2.sqrt();
        let wi = to_light / d;
        let cos_light = -geometric_normal(v0, v1, v2).dot(wi);
        let Some(origin) = v.origin_towards(wi).filter(|_| cos_light > 0.0) else { return Vec3::ZERO };
        // A cut-out of an alpha-masked emitter emits nothing; a blended one emits in proportion
        // to its coverage (a path ray sees it with that probability).
        let coverage = self.coverage(t as u32, bary);
        if coverage == 0.0 {
            return Vec3::ZERO;
        }
        let material = self.triangle_materials[t] as usize;
        let emission = self.emission_at(material, t, bary);
        let emission = if coverage < 1.0 { emission * coverage } else { emission };
        let wi_local = v.frame.to_local(wi);
        let f = v.bsdf.eval(v.wo, wi_local);
        if emission == Vec3::ZERO || f == Vec3::ZERO {
            return Vec3::ZERO;
        }
        let area = triangle_area(v0, v1, v2);
        let selection = bvh_pmf.unwrap_or_else(|| emitters.selection_pdf(material, area));
        let pdf = match omega {
            Some(omega) => selection / omega,
            None => selection * d2 / (area * cos_light),
        };
        let w = self.settings.light_sampling.light_weight(pdf, v.bsdf.pdf(v.wo, wi_local));
        let contribution = v.throughput * f * emission * (w / pdf);
        // A light sample that is not finite (an emitter touching the surface) adds nothing.
        if !(contribution.is_finite() && contribution != Vec3::ZERO) {
            return Vec3::ZERO;
        }
        contribution * self.transmittance(origin, wi, d * (1.0 - furnace_render::SHADOW_EPSILON), v.medium)
    }

    /// One light sample of each sun disc at scattering event `event` (throughput included): a
    /// direction uniform in its cone and a shadow ray to infinity, weighted against BSDF sampling.
    pub(super) fn sample_sun_discs(&self, pixel: u32, index: u32, event: u32, v: &Vertex<'_>) -> Vec3 {
        let mut sum = Vec3::ZERO;
        let dim = layout::light(self.settings.bounces, event) + LIGHT_SUN_DISC;
        for disc in &self.sun_discs {
            let [u1, u2] = self.sampler.value_2d(pixel, index, dim);
            let wi =
                Frame::new(disc.axis).to_world(square_to_uniform_cone(Vec2::new(u1, u2), disc.one_minus_cos));
            let Some(origin) = v.origin_towards(wi) else { continue };
            let wi_local = v.frame.to_local(wi);
            let f = v.bsdf.eval(v.wo, wi_local);
            if f == Vec3::ZERO {
                continue;
            }
            let w = self.settings.light_sampling.light_weight(disc.pdf, v.bsdf.pdf(v.wo, wi_local));
            let contribution = v.throughput * f * disc.estimate * w;
            if contribution != Vec3::ZERO {
                sum += contribution * self.transmittance(origin, wi, f32::INFINITY, v.medium);
            }
        }
        sum
    }

    /// One light sample of the environment map at scattering event `event` (throughput
    /// included): a direction from its importance distribution, a shadow ray to infinity,
    /// weighted against BSDF sampling.
    pub(super) fn sample_environment(&self, pixel: u32, index: u32, event: u32, v: &Vertex<'_>) -> Vec3 {
        let (Some(env), Some(sampler)) = (&self.environment, &self.env_sampler) else { return Vec3::ZERO };
        let dim = layout::light(self.settings.bounces, event) + LIGHT_ENVIRONMENT;
        let u = Vec2::from(self.sampler.value_2d(pixel, index, dim));
        let Some(s) = sampler.sample(env, u) else { return Vec3::ZERO };
        let Some(origin) = v.origin_towards(s.direction) else { return Vec3::ZERO };
        if s.radiance == Vec3::ZERO {
            return Vec3::ZERO;
        }
        let wi_local = v.frame.to_local(s.direction);
        let f = v.bsdf.eval(v.wo, wi_local);
        if f == Vec3::ZERO {
            return Vec3::ZERO;
        }
        let w = self.env_weights.light_weight(s.pdf, v.bsdf.pdf(v.wo, wi_local));
        let contribution = v.throughput * f * s.radiance * (w / s.pdf);
        if !(contribution.is_finite() && contribution != Vec3::ZERO) {
            return Vec3::ZERO;
        }
        contribution * self.transmittance(origin, s.direction, f32::INFINITY, v.medium)
    }

    /// The environment's radiance along an escaping ray (`direction`), weighted against its
    /// light samples at the previous vertex (`bsdf_pdf`; `None` for a camera ray or a delta
    /// event: weight 1). A `camera` ray (no scattering event yet) sees nothing where the camera
    /// does not see the environment.
    pub(super) fn environment_seen(
        &self,
        env: &Environment,
        direction: Vec3,
        bsdf_pdf: Option<f32>,
        camera: bool,
    ) -> Vec3 {
        if camera && !env.visible {
            return Vec3::ZERO;
        }
        let w = match (bsdf_pdf, &self.env_sampler) {
            (Some(p), Some(sampler)) => self.env_weights.bsdf_weight(p, sampler.pdf(direction)),
            _ => 1.0,
        };
        if w == 0.0 {
            return Vec3::ZERO;
        }
        env.radiance_with(self.env_rotation, direction) * w
    }

    /// The sun discs' radiance along an escaping ray (`direction`), each weighted against its
    /// cone sampling at the previous vertex (`bsdf_pdf`; `None` for a camera ray, weight 1).
    pub(super) fn sun_discs_seen(&self, direction: Vec3, bsdf_pdf: Option<f32>) -> Vec3 {
        let mut sum = Vec3::ZERO;
        for disc in &self.sun_discs {
            if in_cone(direction, disc.axis, disc.one_minus_cos) {
                let w = bsdf_pdf.map_or(1.0, |p| self.settings.light_sampling.bsdf_weight(p, disc.pdf));
                sum += disc.radiance * w;
            }
        }
        sum
    }

    /// The MIS weight of emission reached by a BSDF-sampled ray of pdf `bsdf_pdf` (`None`: a
    /// camera ray) from `origin` (the previous vertex's offset origin, whose receiving side was
    /// `normal`), at distance `t` on the front of triangle `triangle` of `material`: against the
    /// light sample that could have chosen the same point from there.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn emission_weight(
        &self,
        bsdf_pdf: Option<f32>,
        origin: Vec3,
        normal: Vec3,
        material: usize,
        triangle: usize,
        t: f32,
        cos_light: f32,
    ) -> f32 {
        let (Some(p), Some(emitters)) = (bsdf_pdf, &self.emitters) else { return 1.0 };
        let Some([v0, v1, v2]) = self.scene.geometry.triangle(triangle) else { return 1.0 };
        let area = triangle_area(v0, v1, v2);
        let selection = match &self.light_bvh {
            Some(bvh) => emitters.index_of(triangle as u32).map_or(0.0, |i| bvh.pmf(origin, normal, i)),
            None => emitters.selection_pdf(material, area),
        };
        if !(selection > 0.0) {
            return 1.0; // never chosen by the light sampler: BSDF sampling is its only strategy
        }
        // The light sample's pdf of this direction, decided as `sample_emitter` decides it.
        let light = match self.settings.triangle_sampling.solid_angle(v0 - origin, v1 - origin, v2 - origin) {
            Some(omega) => selection / omega,
            None => selection * (t * t) / (area * cos_light),
        };
        self.settings.light_sampling.bsdf_weight(p, light)
    }

    /// The emitted radiance of `material` on triangle `t` at barycentrics `b`.
    fn emission_at(&self, material: usize, t: usize, b: Vec2) -> Vec3 {
        match &self.constant_materials[material] {
            Some(c) => c.params.emission,
            None => {
                let at = self.scene.geometry.attributes(t, b.x, b.y);
                self.scene.materials[material]
                    .evaluate(&at, &self.scene.textures, &self.scene.images)
                    .emission
            }
        }
    }
}
