//! The scene's lights: one list ([`Scene::lights`]) of [`Light`]s.
//!
//! Every light type is a variant of [`Light`]; the loader adds them, the content hash covers
//! them, and each integrator gathers the kinds it knows (see ARCHITECTURE.md, "Adding a light
//! type").

use crate::Scene;
use glam::{Mat4, Vec3};

/// A directional light ("sun"): light of constant irradiance from a direction, either exactly
/// parallel (a delta light, `angular_radius` 0) or from a disc of uniform radiance that
/// subtends `angular_radius` (soft shadows).
#[derive(Clone, Copy, PartialEq)]
pub struct Sun {
    /// Unit direction the light **travels** (the light node's −Z in world space). The
    /// direction towards the sun is `-direction`.
    pub direction: Vec3,
    /// Irradiance on a surface facing the sun, W/m² per channel (`color × intensity`, no
    /// photometric conversion), the disc's included.
    pub irradiance: Vec3,
    /// Half the disc's angular diameter θ in radians, in `[0, π/2]`: 0 is the delta sun; a disc
    /// has uniform radiance [`Sun::radiance`] `= E / (π sin²θ)` over the cone of half-angle θ
    /// (the references' convention).
    pub angular_radius: f32,
}

impl std::fmt::Debug for Sun {
    /// As `#[derive(Debug)]` would print it, without `angular_radius` when it is 0: the content
    /// hash reads this, and delta suns keep the hash they had before discs existed.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut d = f.debug_struct("Sun");
        d.field("direction", &self.direction).field("irradiance", &self.irradiance);
        if self.angular_radius != 0.0 {
            d.field("angular_radius", &self.angular_radius);
        }
        d.finish()
    }
}

impl Sun {
    /// A delta sun (no disc).
    pub fn delta(direction: Vec3, irradiance: Vec3) -> Self {
        Self { direction, irradiance, angular_radius: 0.0 }
    }

    /// Whether the sun is a disc (sampled over its cone, seen by rays) rather than a delta light.
    pub fn is_disc(&self) -> bool {
        self.angular_radius > 0.0
    }

    /// `1 − cos θ` of the disc's half-angle θ, formed as `2 sin²(θ/2)` in `f64`: exact to
    /// `f32` rounding however small the disc (a 0.001° disc has 3.8·10⁻¹¹, where `cos θ`
    /// rounds to 1). 0 for a delta sun.
    pub fn one_minus_cos(&self) -> f32 {
        let h = f64::from(self.angular_radius) / 2.0;
        (2.0 * h.sin() * h.sin()) as f32
    }

    /// The disc's radiance `E / (π sin²θ)` (`sin²θ = t(2 − t)`, `t = 1 − cos θ`); zero for a
    /// delta sun.
    pub fn radiance(&self) -> Vec3 {
        self.irradiance * self.radiance_scale()
    }

    /// The disc's radiance per unit irradiance, `1 / (π sin²θ)`, formed in `f64` (0 for a delta
    /// sun): [`Sun::radiance`] is `irradiance ×` this.
    pub fn radiance_scale(&self) -> f32 {
        if !self.is_disc() {
            return 0.0;
        }
        let t = f64::from(self.one_minus_cos());
        (1.0 / (std::f64::consts::PI * t * (2.0 - t))) as f32
    }

    /// The cone sampling estimate's factor: a disc sampled uniformly over its cone, one
    /// direction, contributes `f · cos · L / pdf = f · cos · E · 2 / (2 − t)`; this is
    /// `E · 2 / (2 − t)` (E for a delta sun), formed without the huge `L` and `1/pdf` of a tiny
    /// disc.
    pub fn cone_estimate(&self) -> Vec3 {
        let t = self.one_minus_cos();
        self.irradiance * (2.0 / (2.0 - t))
    }
}

/// Constant radiance arriving from every direction in which a ray leaves the scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sky {
    /// Radiance, linear RGB.
    pub radiance: Vec3,
}

/// A point light (`KHR_lights_punctual` `point`), or a spot light (`spot`: a point light whose
/// intensity is shaped by a cone). A delta light: reached only by shadow rays, never seen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointLight {
    /// World-space position (the light node's origin).
    pub position: Vec3,
    /// Radiant intensity `color × intensity` in W/sr per channel (no photometric conversion,
    /// as the references' README rules); inside the inner cone for a spot light.
    pub intensity: Vec3,
    /// `range` of the file: beyond it the light contributes nothing; `None` = pure inverse
    /// square.
    pub range: Option<f32>,
    /// The cone of a spot light.
    pub spot: Option<SpotCone>,
}

/// A spot light's cone: full intensity inside the inner angle, none outside the outer one, and
/// between them the smooth falloff the `KHR_lights_punctual` specification recommends.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpotCone {
    /// Unit direction the spot points (the light node's −Z in world space).
    pub direction: Vec3,
    /// `cos(innerConeAngle)`.
    pub cos_inner: f32,
    /// `cos(outerConeAngle)`, below `cos_inner`.
    pub cos_outer: f32,
}

impl PointLight {
    /// The radiant intensity (W/sr) the light sends along unit direction `direction` (from the
    /// light) to a point at distance `distance`: [`intensity`](Self::intensity) × the spot
    /// cone's attenuation × the range window. Divide by `distance²` for the irradiance at
    /// normal incidence.
    ///
    /// Both factors are the specification's recommended ones: the cone's
    /// `t = clamp((cos − cos_outer) / (cos_inner − cos_outer), 0, 1)`, squared; the window
    /// `clamp(1 − (distance / range)⁴, 0, 1)`.
    pub fn intensity_towards(&self, direction: Vec3, distance: f32) -> Vec3 {
        let mut k = 1.0;
        if let Some(cone) = &self.spot {
            let cos = direction.dot(cone.direction);
            let t = ((cos - cone.cos_outer) / (cone.cos_inner - cone.cos_outer)).clamp(0.0, 1.0);
            k = t * t;
        }
        if let Some(range) = self.range {
            let r = distance / range;
            k *= (1.0 - (r * r) * (r * r)).clamp(0.0, 1.0);
        }
        self.intensity * k
    }

    /// The light's power as luminance: the Rec. 709 luminance of its intensity integrated over
    /// the directions it lights, `4π·Y` for a point light and, for a spot light,
    /// `2π·Y·((1 − cos_inner) + (cos_inner − cos_outer)/3)` (the cone's squared linear falloff
    /// integrates to a third of its band). The range window is left out: an upper bound, as
    /// pbrt-v4's `Phi` leaves it. [`PointLightDistribution`] chooses lights by it.
    pub fn power(&self) -> f32 {
        let y = crate::luminance(self.intensity);
        let solid_angle = match &self.spot {
            None => 4.0 * std::f32::consts::PI,
            Some(c) => 2.0 * std::f32::consts::PI * ((1.0 - c.cos_inner) + (c.cos_inner - c.cos_outer) / 3.0),
        };
        y * solid_angle
    }
}

/// One point or spot light chosen in proportion to its [`PointLight::power`]: the light sample
/// of `--point-lights one`, which traces one shadow ray per scattering event where gathering
/// every light traces one per light.
///
/// A cumulative table searched by bisection: `O(log n)` per choice, and the same comparisons
/// in the WGSL twin (furnace-gpu's `choose_point_light`), so the CPU and GPU choose the same
/// light for the same sample. Lights of zero power are never chosen (their slot of the table
/// has zero width).
#[derive(Debug, Clone, PartialEq)]
pub struct PointLightDistribution {
    /// `cdf[i]`: the probability of choosing a light `≤ i`, the last exactly 1.
    cdf: Vec<f32>,
    /// `pmf[i]`: the probability of choosing light `i`.
    pmf: Vec<f32>,
}

impl PointLightDistribution {
    /// The distribution over `lights` in their order; `None` when their total power is zero or
    /// not finite (no light to choose: nothing is gathered).
    pub fn new(lights: &[PointLight]) -> Option<Self> {
        // Sums in f64, so that the table of many lights of very different power keeps each
        // light's share.
        let powers: Vec<f64> = lights.iter().map(|l| f64::from(l.power()).max(0.0)).collect();
        let total: f64 = powers.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let mut running = 0.0;
        let mut cdf: Vec<f32> = powers
            .iter()
            .map(|p| {
                running += p;
                (running / total) as f32
            })
            .collect();
        // The last light that can be chosen closes the table at exactly 1, so every u < 1
        // finds a light (rounding may leave the sum at 1 − ε).
        if let Some(last) = powers.iter().rposition(|&p| p > 0.0) {
            for c in &mut cdf[last..] {
                *c = 1.0;
            }
        }
        let pmf = powers.iter().map(|p| (p / total) as f32).collect();
        Some(Self { cdf, pmf })
    }

    /// The light chosen by `u ∈ [0, 1)` — the first `i` with `u < cdf[i]` — and the
    /// probability of choosing it.
    #[inline]
    pub fn sample(&self, u: f32) -> (usize, f32) {
        let (mut lo, mut hi) = (0usize, self.cdf.len() - 1);
        while lo < hi {
            let mid = (lo + hi) / 2;
            if u < self.cdf[mid] {
                hi = mid;
            } else {
                lo = mid + 1;
            }
        }
        (lo, self.pmf[lo])
    }

    /// The cumulative table, one entry per light.
    pub fn cdf(&self) -> &[f32] {
        &self.cdf
    }

    /// The probability of choosing each light.
    pub fn pmf(&self) -> &[f32] {
        &self.pmf
    }
}

/// A light of a scene.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Light {
    /// A directional light, gathered by shadow rays.
    Sun(Sun),
    /// Constant radiance at infinity, gathered by rays that escape.
    Sky(Sky),
    /// A point or spot light, gathered by shadow rays.
    Point(PointLight),
    /// Radiance at infinity from an HDR image, gathered by rays that escape and by light
    /// samples of its importance distribution.
    Environment(crate::Environment),
}

impl std::fmt::Display for Light {
    /// One line for `furnace info`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let v = |v: Vec3| format!("({:.4}, {:.4}, {:.4})", v.x, v.y, v.z);
        match self {
            Light::Sun(s) => {
                write!(f, "sun travelling {}, irradiance {} W/m²", v(s.direction), v(s.irradiance))?;
                if s.is_disc() {
                    write!(f, ", a disc of {:.4}°", 2.0 * s.angular_radius.to_degrees())?;
                }
                Ok(())
            }
            Light::Sky(s) => write!(f, "sky of radiance {}", v(s.radiance)),
            Light::Environment(e) => {
                write!(
                    f,
                    "environment map {} ({} × {} texels), intensity {}, rotated {:.1}° about +Y",
                    e.map.source(),
                    e.map.width(),
                    e.map.height(),
                    e.intensity,
                    e.rotation.to_degrees()
                )?;
                if !e.visible {
                    write!(f, ", not seen by the camera")?;
                }
                Ok(())
            }
            Light::Point(p) => {
                write!(
                    f,
                    "{} light at {}, intensity {} W/sr",
                    if p.spot.is_some() { "spot" } else { "point" },
                    v(p.position),
                    v(p.intensity)
                )?;
                if let Some(cone) = &p.spot {
                    let deg = |c: f32| c.clamp(-1.0, 1.0).acos().to_degrees();
                    write!(
                        f,
                        ", pointing {}, cone {:.1}°–{:.1}°",
                        v(cone.direction),
                        deg(cone.cos_inner),
                        deg(cone.cos_outer)
                    )?;
                }
                if let Some(r) = p.range {
                    write!(f, ", range {r} m")?;
                }
                Ok(())
            }
        }
    }
}

/// The light of a `KHR_lights_punctual` node whose world transform is `world`, or where and why
/// it is ignored (an empty place: the light itself).
pub(crate) fn punctual(
    light: &gltf::khr_lights_punctual::Light<'_>,
    world: Mat4,
) -> Result<Light, (&'static str, &'static str)> {
    use gltf::khr_lights_punctual::Kind;
    let power = Vec3::from(light.color()) * light.intensity();
    if !power.is_finite() || power.min_element() < 0.0 {
        return Err(("", "negative or non-finite colour × intensity: light ignored"));
    }
    let direction = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    match light.kind() {
        Kind::Directional => {
            if direction == Vec3::ZERO {
                return Err(("", "degenerate directional light: ignored"));
            }
            Ok(Light::Sun(Sun::delta(direction, power)))
        }
        kind => {
            let position = world.transform_point3(Vec3::ZERO);
            if !position.is_finite() {
                return Err(("", "light at a non-finite position: ignored"));
            }
            let range = match light.range() {
                None => None,
                Some(r) if r > 0.0 && r.is_finite() => Some(r),
                Some(_) => return Err(("", "range must be a positive number: light ignored")),
            };
            let spot = match kind {
                Kind::Spot { inner_cone_angle, outer_cone_angle } => {
                    if direction == Vec3::ZERO {
                        return Err(("", "degenerate spot light direction: ignored"));
                    }
                    // The specification: 0 ≤ inner < outer ≤ π/2.
                    let ok = 0.0 <= inner_cone_angle
                        && inner_cone_angle < outer_cone_angle
                        && outer_cone_angle <= std::f32::consts::FRAC_PI_2;
                    if !ok {
                        return Err((
                            "",
                            "spot cone angles must satisfy 0 ≤ inner < outer ≤ π/2: light ignored",
                        ));
                    }
                    Some(SpotCone {
                        direction,
                        cos_inner: inner_cone_angle.cos(),
                        cos_outer: outer_cone_angle.cos(),
                    })
                }
                _ => None,
            };
            Ok(Light::Point(PointLight { position, intensity: power, range, spot }))
        }
    }
}

impl Scene {
    /// The directional lights, in list order.
    pub fn suns(&self) -> impl Iterator<Item = &Sun> {
        self.lights.iter().filter_map(|l| match l {
            Light::Sun(s) => Some(s),
            _ => None,
        })
    }

    /// The point and spot lights, in list order.
    pub fn point_lights(&self) -> impl Iterator<Item = &PointLight> {
        self.lights.iter().filter_map(|l| match l {
            Light::Point(p) => Some(p),
            _ => None,
        })
    }

    /// The first directional light, if any.
    pub fn sun(&self) -> Option<&Sun> {
        self.suns().next()
    }

    /// The radiance of a ray that leaves the scene: the sum of the [`Light::Sky`] lights, black
    /// without one.
    pub fn sky(&self) -> Vec3 {
        self.lights
            .iter()
            .filter_map(|l| match l {
                Light::Sky(s) => Some(s.radiance),
                _ => None,
            })
            .fold(Vec3::ZERO, |a, b| a + b)
    }

    /// Replaces the scene's directional lights by `sun` (none for `None`), first in the list.
    pub fn set_sun(&mut self, sun: Option<Sun>) {
        self.lights.retain(|l| !matches!(l, Light::Sun(_)));
        if let Some(s) = sun {
            self.lights.insert(0, Light::Sun(s));
        }
    }

    /// Gives every directional light a disc of angular diameter `degrees` (0: delta suns);
    /// returns how many there are.
    pub fn set_sun_angular_diameter(&mut self, degrees: f32) -> usize {
        let radius = (f64::from(degrees).to_radians() / 2.0) as f32;
        let mut n = 0;
        for l in &mut self.lights {
            if let Light::Sun(s) = l {
                s.angular_radius = radius;
                n += 1;
            }
        }
        n
    }

    /// Whether a path samples a light here beyond the delta lights: the scene has emissive
    /// triangles ([`crate::Emitters`]) or a sun disc. Such scenes read the sampler's light
    /// dimensions (`furnace_render::layout`).
    pub fn samples_lights(&self) -> bool {
        self.suns().any(Sun::is_disc) || self.environment().is_some() || crate::Emitters::new(self).is_some()
    }

    /// Whether a material disperses (KHR_materials_dispersion): paths that meet it read the
    /// sampler's wavelength dimension (`furnace_render::layout::wavelength`).
    pub fn disperses(&self) -> bool {
        self.materials.iter().any(|m| m.dispersion > 0.0)
    }

    /// The environment map light, if any (the first: a scene has at most one).
    pub fn environment(&self) -> Option<&crate::Environment> {
        self.lights.iter().find_map(|l| match l {
            Light::Environment(e) => Some(e),
            _ => None,
        })
    }

    /// Replaces the scene's environment map by `env` (none for `None`).
    pub fn set_environment(&mut self, env: Option<crate::Environment>) {
        self.lights.retain(|l| !matches!(l, Light::Environment(_)));
        if let Some(e) = env {
            self.lights.push(Light::Environment(e));
        }
    }

    /// Whether the scene brings a light of its own: a sun, a sky, a point or spot light, an
    /// environment map, or an emissive material without an emissive texture. Emissive
    /// **textures** alone do not count: in glTF assets they are glow details (decals, screens,
    /// indicator lamps) drawn for a viewer that lights the model with an environment, and such
    /// assets (DamagedHelmet) would render black but for them. A scene without a light of its
    /// own is lit by the built-in studio environment in `furnace render`. Only materials some
    /// triangle uses count: an emissive material no mesh uses lights nothing.
    pub fn has_own_light(&self) -> bool {
        let mut used = vec![false; self.materials.len()];
        for t in 0..self.geometry.triangle_count() {
            if let Some(u) = used.get_mut(self.triangle_material(t)) {
                *u = true;
            }
        }
        let lamp = self
            .materials
            .iter()
            .zip(&used)
            .any(|(m, &u)| u && m.emissive != Vec3::ZERO && m.emissive_texture.is_none());
        lamp || self.lights.iter().any(|l| match l {
            Light::Sky(s) => s.radiance != Vec3::ZERO,
            _ => true,
        })
    }

    /// Replaces the scene's skies by one of `radiance` (none for black).
    pub fn set_sky(&mut self, radiance: Vec3) {
        self.lights.retain(|l| !matches!(l, Light::Sky(_)));
        if radiance != Vec3::ZERO {
            self.lights.push(Light::Sky(Sky { radiance }));
        }
    }

    /// The lights as the content hash reads them: the first sun and the sky radiance — all an
    /// image depends on when the lights are at most one sun and skies, hashed as scenes were
    /// before the light list so that saved renders keep their hash — then the whole list when
    /// there is anything more (a second sun, any other kind of light).
    pub(crate) fn lights_debug(&self) -> String {
        let mut s = format!("{:?}|{:?}", self.sun(), self.sky());
        let more = self.suns().count() > 1
            || self.lights.iter().any(|l| !matches!(l, Light::Sun(_) | Light::Sky(_)));
        if more {
            s.push_str(&format!("|{:?}", self.lights));
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builtin;

    fn light(intensity: f32, spot: Option<(f32, f32)>) -> PointLight {
        PointLight {
            position: Vec3::ZERO,
            intensity: Vec3::splat(intensity),
            range: None,
            spot: spot.map(|(inner, outer): (f32, f32)| SpotCone {
                direction: Vec3::NEG_Z,
                cos_inner: inner.cos(),
                cos_outer: outer.cos(),
            }),
        }
    }

    /// `power` is the intensity integrated over the sphere: a midpoint rule over cos θ (the
    /// cone depends on θ alone) with 200 000 bands agrees to 1e-5 relative, far below the
    /// ~1e-2 a wrong falloff integral (a half instead of a third of the band) would miss by.
    #[test]
    fn power_is_the_intensity_integrated_over_the_sphere() {
        for spot in [None, Some((0.3, 0.6)), Some((0.0, 1.2)), Some((1.0, 1.0001))] {
            let l = light(2.0, spot);
            let bands = 200_000;
            let mut sum = 0.0f64;
            for i in 0..bands {
                let cos = -1.0 + (i as f64 + 0.5) * 2.0 / bands as f64;
                let dir = Vec3::new((1.0 - cos * cos).sqrt() as f32, 0.0, -(cos as f32));
                sum += f64::from(l.intensity_towards(dir, 1.0).y) * 2.0 * std::f64::consts::PI * 2.0
                    / bands as f64;
            }
            let p = f64::from(l.power());
            assert!((p - sum).abs() <= 1e-5 * sum.max(1e-3), "{spot:?}: power {p}, integral {sum}");
        }
    }

    /// Every `u` on a grid of 2^20 points in [0, 1) chooses a light; the share of the grid each
    /// light gets is its pmf to within the grid's spacing (2^-20, plus f32 rounding of the
    /// table, < 1e-6), and a light of zero power is never chosen.
    #[test]
    fn point_lights_are_chosen_in_proportion_to_power() {
        let lights = [
            light(2.0, None),
            light(0.0, None),
            light(1.0, None),
            light(5.0, Some((0.3, 0.6))),
            light(0.0, None),
        ];
        let d = PointLightDistribution::new(&lights).unwrap();
        let total: f32 = lights.iter().map(PointLight::power).sum();
        let n = 1u32 << 20;
        let mut counts = [0u32; 5];
        for i in 0..n {
            let (k, pmf) = d.sample(i as f32 / n as f32);
            assert_eq!(pmf, d.pmf()[k]);
            counts[k] += 1;
        }
        for (k, l) in lights.iter().enumerate() {
            let share = counts[k] as f32 / n as f32;
            assert!(
                (share - l.power() / total).abs() < 2e-6,
                "light {k}: {share} of the grid, power share {}",
                l.power() / total
            );
            assert!((d.pmf()[k] - l.power() / total).abs() < 1e-6);
        }
        assert_eq!(counts[1] + counts[4], 0);
        assert_eq!(*d.cdf().last().unwrap(), 1.0);
        // The largest u below 1 still finds a light of nonzero power.
        assert_eq!(d.sample(1.0 - f32::EPSILON / 2.0).0, 3);
        assert!(PointLightDistribution::new(&[light(0.0, None)]).is_none());
        assert!(PointLightDistribution::new(&[]).is_none());
    }

    #[test]
    fn sun_and_sky_setters_replace() {
        let mut scene = builtin::furnace_sphere(builtin::lambert(Vec3::ONE), 4);
        assert_eq!(scene.sky(), Vec3::ONE);
        assert!(scene.sun().is_none());
        let sun = Sun::delta(-Vec3::Y, Vec3::splat(2.0));
        scene.set_sun(Some(sun));
        scene.set_sky(Vec3::splat(0.5));
        assert_eq!(scene.lights, [Light::Sun(sun), Light::Sky(Sky { radiance: Vec3::splat(0.5) })]);
        scene.set_sky(Vec3::ZERO);
        scene.set_sun(None);
        assert!(scene.lights.is_empty());
        assert_eq!(scene.sky(), Vec3::ZERO);
    }

    #[test]
    fn point_and_spot_lights_are_read_as_the_specification_says() {
        let json = br#"{"asset":{"version":"2.0"},"extensionsUsed":["KHR_lights_punctual"],
            "extensions":{"KHR_lights_punctual":{"lights":[
                {"type":"point","color":[1,0.5,0.25],"intensity":2},
                {"type":"spot","intensity":3,"range":4,"spot":{"innerConeAngle":0.2,"outerConeAngle":0.5}},
                {"type":"spot","spot":{"innerConeAngle":0.6,"outerConeAngle":0.5}},
                {"type":"point","intensity":-1},
                {"type":"point","range":0}]}}}"#;
        let doc = gltf::Gltf::from_slice(json).expect("valid JSON");
        let lights: Vec<_> = doc.lights().expect("lights").collect();
        let world = Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0));
        let Ok(Light::Point(p)) = punctual(&lights[0], world) else { panic!("a point light") };
        assert_eq!(
            (p.position, p.intensity, p.range, p.spot),
            (Vec3::new(1.0, 2.0, 3.0), Vec3::new(2.0, 1.0, 0.5), None, None)
        );
        let Ok(Light::Point(s)) = punctual(&lights[1], world) else { panic!("a spot light") };
        let cone = s.spot.expect("a cone");
        assert_eq!((s.intensity, s.range, cone.direction), (Vec3::splat(3.0), Some(4.0), Vec3::NEG_Z));
        assert_eq!((cone.cos_inner, cone.cos_outer), (0.2f32.cos(), 0.5f32.cos()));
        // Full intensity inside the inner cone (and at d = 0 of the range), none outside the
        // outer one or beyond the range, t² between; the window (1 − (d/r)⁴).
        assert_eq!(s.intensity_towards(Vec3::NEG_Z, 0.0), Vec3::splat(3.0));
        let at = |angle: f32| Vec3::new(angle.sin(), 0.0, -angle.cos());
        assert_eq!(s.intensity_towards(at(0.51), 1.0), Vec3::ZERO);
        assert_eq!(s.intensity_towards(Vec3::NEG_Z, 4.0), Vec3::ZERO);
        let t = (0.35f32.cos() - 0.5f32.cos()) / (0.2f32.cos() - 0.5f32.cos());
        let k = s.intensity_towards(at(0.35), 2.0).x / 3.0;
        // At d = 2 of range 4 the window is 1 − 0.5⁴ = 0.9375. Tolerance: f32 rounding of the
        // cosines.
        assert!((k - t * t * 0.9375).abs() < 1e-5, "{k} vs {}", t * t * 0.9375);
        // Invalid lights are refused with the reason.
        assert!(matches!(punctual(&lights[2], world), Err((_, why)) if why.contains("inner < outer")));
        assert!(matches!(punctual(&lights[3], world), Err((_, why)) if why.contains("negative")));
        assert!(matches!(punctual(&lights[4], world), Err((_, why)) if why.contains("range")));
    }

    #[test]
    fn a_second_sun_changes_the_hash() {
        let mut scene = builtin::cornell_box().unwrap();
        let h = scene.content_hash();
        let sun = *scene.sun().unwrap();
        scene.lights.push(Light::Sun(sun));
        assert_ne!(scene.content_hash(), h);
    }
}
