//! The path tracing loop of the CPU path tracer, in stages: the ray that escapes, the surface it
//! hits (AOVs, absorption, emission), the BSDF there and its light samples
//! ([`super::lights`]), and the scattered ray that continues the path.

use super::accel::{Trace, Tracer};
use super::lights::Vertex;
use super::{Shading, absorption, bsdf};
use furnace_accel::offset_ray_origin_scaled;
use furnace_brdf::spectrum::{dispersed_ior, sample_wavelength};
use furnace_brdf::{Frame, HitBsdf};
use furnace_render::AovSample;
use furnace_render::layout::{self, BOUNCE_BSDF_DIRECTION, BOUNCE_BSDF_LOBE, BOUNCE_RUSSIAN_ROULETTE};
use furnace_sampling::Sampler;
use furnace_scene::{Material, SurfacePoint, VertexAttributes};
use glam::{Vec2, Vec3};

/// What a path carries from one ray to the next.
struct Path {
    /// Where the current ray starts.
    origin: Vec3,
    /// Where the current ray goes (unit length).
    direction: Vec3,
    /// The radiance gathered so far.
    radiance: Vec3,
    /// The product of the sample weights so far.
    throughput: Vec3,
    /// The scattering events so far; the loop body handles one ray.
    event: u32,
    /// The solid-angle pdf of the BSDF sample that made the ray (`None`: the camera's, or a
    /// delta event's), for the MIS weights of the lights it reaches.
    bsdf_pdf: Option<f32>,
    /// The receiving side (geometric normal) of the vertex the ray left, for the light BVH's
    /// probabilities in those weights (zero: both sides).
    normal: Vec3,
    /// Where that vertex took its light samples from (`origin` unless the ray crossed a
    /// surface since), for the same weights.
    mis_origin: Option<Vec3>,
    /// The absorption coefficient of the volume the ray travels in (0: air).
    medium: Vec3,
    /// The surface point the ray left (its offset origin would shorten the path by the offset).
    left_from: Vec3,
    /// Passes straight through thin-walled sheets since the last event (not events
    /// themselves).
    passes: u32,
    /// The lobe number those passes left unused for the next choice.
    carried_uc: Option<f32>,
    /// The wavelength (nm) the path is traced at since its first dispersive solid; `None`:
    /// RGB.
    wavelength: Option<f32>,
}

impl<A: Trace> Tracer<'_, A> {
    /// The path tracing loop: radiance arriving at `origin` from direction `-direction`. With
    /// `aov`, what the first ray hits is written there (it is left as it is for a miss).
    pub(super) fn trace(
        &self,
        pixel: u32,
        index: u32,
        origin: Vec3,
        direction: Vec3,
        mut aov: Option<&mut AovSample>,
    ) -> Vec3 {
        let scene = &self.scene;
        let mut path = Path {
            origin,
            direction,
            radiance: Vec3::ZERO,
            throughput: Vec3::ONE,
            event: 0,
            bsdf_pdf: None,
            normal: Vec3::ZERO,
            mis_origin: None,
            medium: Vec3::ZERO,
            left_from: origin,
            passes: 0,
            carried_uc: None,
            wavelength: None,
        };
        loop {
            let Some(hit) = self.closest_hit(path.origin, path.direction) else {
                self.escape(&mut path);
                break;
            };
            let (hit, hit_instance) = hit;
            let instance = self.instance(hit_instance);
            let material_index = self.triangle_materials[hit.triangle as usize] as usize;
            let material = &scene.materials[material_index];
            // Materials with textures or vertex colours are evaluated at the hit's attributes;
            // the others were built once.
            let t = hit.triangle as usize;
            let (b1, b2) = (hit.barycentrics.x, hit.barycentrics.y);
            let (at, shading) = match &self.constant_materials[material_index] {
                Some(c) => (VertexAttributes::default(), Shading::Constant(c)),
                None => {
                    let at = scene.geometry.attributes(t, b1, b2);
                    (at, Shading::Evaluated(material.evaluate(&at, &scene.textures, &scene.images)))
                }
            };
            let interpolated = self.shading_normal(hit_instance, t, b1, b2);
            let surface =
                scene.surface_point(instance, t, (b1, b2), material, &at, path.direction, interpolated);
            if let Some(aov) = aov.take() {
                *aov = first_hit_aov(&shading, surface.as_ref(), hit.t);
            }
            // Borrowed, not moved out of the `Option`: the move copied it through memory in
            // pieces that did not match the stores that wrote it (a store-forwarding stall).
            let Some(surface) = &surface else {
                // The back of a single-sided surface: black, like a one-sided BSDF.
                break;
            };
            if path.medium != Vec3::ZERO {
                // Beer–Lambert over the segment inside the volume, surface to surface.
                path.throughput *= absorption(path.medium, (surface.position - path.left_from).length());
            }
            if material.unlit {
                // KHR_materials_unlit: the colour as is, from either side; nothing reflected.
                path.radiance += path.throughput * shading.params().base_color;
                break;
            }
            self.add_emission(&mut path, &shading, surface, material_index, t, hit.t);
            // A dispersive solid has its index at the path's wavelength, drawn here if this is the
            // first (the throughput takes the wavelength's RGB weight).
            let dispersed = (material.dispersion > 0.0).then(|| {
                let lambda = self.wavelength(pixel, index, &mut path);
                dispersed_ior(material.ior, material.dispersion, lambda)
            });
            let evaluated;
            let bsdf = match (&shading, dispersed) {
                (Shading::Constant(c), None) => &c.bsdf,
                (shading, ior) => {
                    let ior = ior.unwrap_or(material.ior);
                    let b = bsdf(shading.params(), material, ior, self.settings.specular, Vec3::Z);
                    evaluated = match coat_normal(material, &b, surface) {
                        Some(n) => b.with_clearcoat_normal(n),
                        None => b,
                    };
                    &evaluated
                }
            };
            // A sheet (or an η = 1 interface) can still be passed after the last event (the
            // pass is none).
            let last = path.event == self.settings.bounces;
            if last && !bsdf.is_straight() {
                break;
            }
            let vertex = self.vertex(&path, bsdf, surface);
            if !last && !bsdf.is_delta() {
                self.light_samples(pixel, index, path.event, &vertex, &mut path.radiance);
            }
            if !self.scatter(pixel, index, &mut path, &vertex, material, last) {
                break;
            }
        }
        path.radiance
    }

    /// The path's wavelength, drawn from the layout's wavelength dimension the first time (its
    /// RGB weight multiplied into the throughput).
    #[inline]
    fn wavelength(&self, pixel: u32, index: u32, path: &mut Path) -> f32 {
        if let Some(lambda) = path.wavelength {
            return lambda;
        }
        let u = self.sampler.value(pixel, index, layout::wavelength(self.settings.bounces));
        let s = sample_wavelength(u);
        path.throughput *= s.weight;
        path.wavelength = Some(s.lambda);
        s.lambda
    }

    /// The ray leaves the scene: the absorption of the volume it is in, then the sky, the
    /// environment and the sun discs it sees.
    #[inline]
    fn escape(&self, path: &mut Path) {
        if path.medium != Vec3::ZERO {
            path.throughput *= absorption(path.medium, f32::INFINITY);
        }
        path.radiance += path.throughput * self.sky;
        if let Some(env) = &self.environment {
            path.radiance +=
                path.throughput * self.environment_seen(env, path.direction, path.bsdf_pdf, path.event == 0);
        }
        if !self.sun_discs.is_empty() {
            path.radiance += path.throughput * self.sun_discs_seen(path.direction, path.bsdf_pdf);
        }
    }

    /// The emission the ray sees at the hit (`distance` along it). Emission is one-sided: the
    /// back of a double-sided emitter does not emit. Reached by a BSDF sample, it is weighted
    /// against the light sample that could have found it.
    #[inline]
    fn add_emission(
        &self,
        path: &mut Path,
        shading: &Shading<'_>,
        surface: &SurfacePoint,
        material_index: usize,
        t: usize,
        distance: f32,
    ) {
        let emission = shading.params().emission;
        if !surface.back_face {
            if self.emitters.is_some() && emission != Vec3::ZERO {
                let cos_light = -surface.geometric.dot(path.direction);
                // The distance from where the light samples were taken (the ray's own
                // length unless it crossed a surface on the way).
                let (from, distance) = match path.mis_origin {
                    Some(o) => (o, (surface.position - o).length()),
                    None => (path.origin, distance),
                };
                let w = self.emission_weight(
                    path.bsdf_pdf,
                    from,
                    path.normal,
                    material_index,
                    t,
                    distance,
                    cos_light,
                );
                path.radiance += path.throughput * emission * w;
            } else {
                path.radiance += path.throughput * emission;
            }
        }
    }

    /// The scattering event at `surface`: its shading frame and the offset origins that rays
    /// leave it from.
    #[inline]
    fn vertex<'a>(&self, path: &Path, bsdf: &'a HitBsdf, surface: &'a SurfacePoint) -> Vertex<'a> {
        // A solid's interface is shaded in its outward frame (the side of index 1), where
        // `wo` may be inside; every other surface in the frame facing the ray.
        let outward = if bsdf.is_volume() && surface.back_face { -surface.shading } else { surface.shading };
        let frame = shading_frame(outward, surface);
        let wo = frame.to_local(-path.direction);
        let leave = offset_ray_origin_scaled(surface.position, surface.geometric, self.offset_scale);
        Vertex {
            throughput: path.throughput,
            bsdf,
            wo,
            frame,
            surface,
            leave,
            leave_behind: bsdf.transmits_light_samples().then(|| self.behind(surface)),
            medium: path.medium,
        }
    }

    /// The offset origin of rays leaving `surface` on the side opposite its geometric normal.
    #[inline]
    fn behind(&self, surface: &SurfacePoint) -> Vec3 {
        offset_ray_origin_scaled(surface.position, -surface.geometric, self.offset_scale)
    }

    /// Continues the path by sampling the BSDF at `v`: the next ray, or `false` where the path
    /// ends (no sample, a direction the surface does not allow, the last event, Russian
    /// roulette).
    #[inline]
    fn scatter(
        &self,
        pixel: u32,
        index: u32,
        path: &mut Path,
        v: &Vertex<'_>,
        material: &Material,
        last: bool,
    ) -> bool {
        let (bsdf, surface) = (v.bsdf, v.surface);
        let dim = layout::bounce(path.event);
        let [u1, u2] = self.sampler.value_2d(pixel, index, dim + BOUNCE_BSDF_DIRECTION);
        // The lobe choice `uc` is drawn only where the material has two lobes (or left over
        // by a pass through a sheet at this event).
        let carried_uc = path.carried_uc;
        let uc = || carried_uc.unwrap_or_else(|| self.sampler.value(pixel, index, dim + BOUNCE_BSDF_LOBE));
        let Some(s) = bsdf.sample(v.wo, Vec2::new(u1, u2), uc) else { return false };
        let wi = v.frame.to_world(s.wi);
        // Reflections leave on the side the ray came from, transmissions on the other; a
        // direction the shading normal allows but the surface does not ends the path —
        // except at a solid's interface, where the ray goes on to whichever side it points
        // (as Mitsuba's, which switches media by that side too).
        let side = wi.dot(surface.geometric);
        let crosses = if bsdf.is_volume() { side < 0.0 } else { s.transmitted };
        if !(if crosses { side < 0.0 } else { side > 0.0 }) {
            return false;
        }
        if s.delta && s.transmitted && bsdf.is_straight() {
            // Straight through a sheet or an invisible interface: no event, the MIS state of
            // the last one kept (a solid's medium changes).
            if bsdf.is_volume() {
                path.medium = if surface.back_face { Vec3::ZERO } else { material.absorption };
            }
            path.passes += 1;
            if path.passes > furnace_render::MAX_SHEET_PASSES {
                return false;
            }
            path.throughput *= s.weight;
            path.carried_uc = Some(s.rest);
            path.mis_origin.get_or_insert(path.origin);
            path.origin = self.behind(surface);
            path.left_from = surface.position;
            return true;
        }
        if last {
            return false;
        }
        path.throughput *= s.weight;
        path.bsdf_pdf = (!s.delta).then_some(s.pdf);
        path.event += 1;
        path.passes = 0;
        path.carried_uc = None;
        if crosses && bsdf.bounds_medium() {
            // Into the solid from outside, or out of it (refracted or diffusely transmitted).
            path.medium = if surface.back_face { Vec3::ZERO } else { material.absorption };
        }
        if self.settings.russian_roulette && path.event >= 3 {
            let survive = furnace_render::russian_roulette_survival(path.throughput);
            if !(self.sampler.value(pixel, index, dim + BOUNCE_RUSSIAN_ROULETTE) < survive) {
                return false;
            }
            path.throughput /= survive;
        }
        path.normal = v.receiver_normal();
        path.left_from = surface.position;
        if crosses {
            path.origin = self.behind(surface);
            path.mis_origin = Some(v.leave);
        } else {
            path.origin = v.leave;
            path.mis_origin = None;
        }
        path.direction = wi;
        true
    }
}

/// The AOVs of the first hit: the albedo (1 on the front of an emitter: its colour is its
/// light, like the sky's), the shading normal (none on the back of a single-sided surface,
/// which is black) and the depth.
#[inline]
fn first_hit_aov(shading: &Shading<'_>, surface: Option<&SurfacePoint>, depth: f32) -> AovSample {
    let (base_color, emission) = (shading.params().base_color, shading.params().emission);
    let emits = emission != Vec3::ZERO && surface.is_some_and(|s| !s.back_face);
    AovSample {
        albedo: if emits { Vec3::ONE } else { base_color },
        normal: surface.map_or(Vec3::ZERO, |s| s.shading),
        depth: Some(depth),
    }
}

/// The clear coat's normal in the frame `bsdf` is shaded in (`vertex`'s: outward for a solid's
/// interface), or `None` where it is the shading normal (no coat, or neither normal map).
#[inline]
fn coat_normal(material: &Material, bsdf: &HitBsdf, surface: &SurfacePoint) -> Option<Vec3> {
    if material.layers.clearcoat.is_none() || surface.coat == surface.shading {
        return None;
    }
    let sign = if bsdf.is_volume() && surface.back_face { -1.0 } else { 1.0 };
    Some(shading_frame(sign * surface.shading, surface).to_local(sign * surface.coat))
}

/// The BSDF's frame around `normal` (the shading normal, or its opposite for a solid seen from
/// inside): x along the anisotropy direction where the material has one.
#[inline]
fn shading_frame(normal: Vec3, surface: &SurfacePoint) -> Frame {
    match surface.anisotropy {
        Some(t) => Frame::with_tangent(normal, t),
        None => Frame::new(normal),
    }
}
