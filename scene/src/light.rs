//! The scene's lights: one list ([`Scene::lights`]) of [`Light`]s.
//!
//! Every light type is a variant of [`Light`]; the loader adds them, the content hash covers
//! them, and each integrator gathers the kinds it knows (see ARCHITECTURE.md, "Adding a light
//! type").

use crate::Scene;
use glam::{Mat4, Vec3};

/// A directional light ("sun"): parallel light of constant irradiance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sun {
    /// Unit direction the light **travels** (the light node's −Z in world space). The
    /// direction towards the sun is `-direction`.
    pub direction: Vec3,
    /// Irradiance on a surface facing the sun, W/m² per channel (`color × intensity`, no
    /// photometric conversion).
    pub irradiance: Vec3,
}

/// Constant radiance arriving from every direction in which a ray leaves the scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sky {
    /// Radiance, linear RGB.
    pub radiance: Vec3,
}

/// A light of a scene.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Light {
    /// A directional light, gathered by shadow rays.
    Sun(Sun),
    /// Constant radiance at infinity, gathered by rays that escape.
    Sky(Sky),
}

impl std::fmt::Display for Light {
    /// One line for `furnace info`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let v = |v: Vec3| format!("({:.4}, {:.4}, {:.4})", v.x, v.y, v.z);
        match self {
            Light::Sun(s) => {
                write!(f, "sun travelling {}, irradiance {} W/m²", v(s.direction), v(s.irradiance))
            }
            Light::Sky(s) => write!(f, "sky of radiance {}", v(s.radiance)),
        }
    }
}

/// The light of a `KHR_lights_punctual` node whose world transform is `world`, or where and why
/// it is ignored (an empty place: the light itself).
pub(crate) fn punctual(
    light: &gltf::khr_lights_punctual::Light<'_>,
    world: Mat4,
) -> Result<Light, (&'static str, &'static str)> {
    match light.kind() {
        gltf::khr_lights_punctual::Kind::Directional => {
            let direction = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
            let irradiance = Vec3::from(light.color()) * light.intensity();
            if direction == Vec3::ZERO || !irradiance.is_finite() {
                return Err(("", "degenerate directional light: ignored"));
            }
            Ok(Light::Sun(Sun { direction, irradiance }))
        }
        _ => Err(("KHR_lights_punctual", "point and spot lights are not supported: ignored")),
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

    #[test]
    fn sun_and_sky_setters_replace() {
        let mut scene = builtin::furnace_sphere(builtin::lambert(Vec3::ONE), 4);
        assert_eq!(scene.sky(), Vec3::ONE);
        assert!(scene.sun().is_none());
        let sun = Sun { direction: -Vec3::Y, irradiance: Vec3::splat(2.0) };
        scene.set_sun(Some(sun));
        scene.set_sky(Vec3::splat(0.5));
        assert_eq!(scene.lights, [Light::Sun(sun), Light::Sky(Sky { radiance: Vec3::splat(0.5) })]);
        scene.set_sky(Vec3::ZERO);
        scene.set_sun(None);
        assert!(scene.lights.is_empty());
        assert_eq!(scene.sky(), Vec3::ZERO);
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
