//! The environment options (`--env`, `--env-intensity`, `--env-rotation`, `--env-visible`) and
//! the default light ([`crate::default_light`]): how `furnace render`, `view`, `bench` and
//! `chart` set up a scene's environment map, and the check of `--env-sampling` against
//! `--light-sampling`.

use crate::args::{EnvArg, EnvArgs, Switch};
use crate::default_light::Decision;
use furnace_accel::SceneAccel;
use furnace_render::{EnvSampling, LightSampling};
use furnace_scene::{Environment, EnvironmentMap, Scene};
use std::sync::Arc;

/// What [`apply`] did to the scene's environment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Applied {
    /// The scene's own environment, adjusted by the options given.
    Own,
    /// The map of `--env FILE` or `--env studio`.
    Given,
    /// Neither `--env` nor an environment of the scene's own: the default light's rule decided
    /// (the built-in studio, or nothing).
    Rule(Decision),
    /// No environment: `--env none`.
    None,
}

/// [`apply_resumed`] for a new render: the default light's rule measures the scene.
///
/// # Errors
/// As [`apply_resumed`].
pub fn apply(scene: &mut Scene, e: &EnvArgs, accel: &mut Option<SceneAccel>) -> Result<Applied, String> {
    apply_resumed(scene, e, None, accel)
}

/// Sets the scene's environment from `e` (the scene's own when `--env` is not given; else the
/// default light's decision, [`crate::default_light::decide_with`]), scaled, turned and shown as `e`
/// says. `resumed` is, for a render being continued, its file's record of the decision
/// (`Some(None)`: a file written before the rule), which is followed instead of measuring
/// again. The rule's probe traces rays through `accel`, building the scene's structure there
/// when it holds none (for the renderer to take: [`furnace_cli::backend::open`]). Prints to stderr one `note:` line when the rule adds the studio to a new render (why,
/// and `--env none`) and a `warning:` line for a map's warning or options that have no environment to act
/// on (also with `--quiet`: they say what the image shows).
///
/// # Errors
/// The map's one-line error (`EnvironmentError`: the file, and the texel for a non-finite one);
/// a resumed record that is neither `studio` nor `none`.
pub fn apply_resumed(
    scene: &mut Scene,
    e: &EnvArgs,
    resumed: Option<Option<&str>>,
    accel: &mut Option<SceneAccel>,
) -> Result<Applied, String> {
    let mut ruled = None;
    let map = match &e.env {
        Some(EnvArg::File(path)) => {
            let (map, warning) = EnvironmentMap::load(path).map_err(|err| err.to_string())?;
            if let Some(w) = warning {
                eprintln!("warning: {w}");
            }
            Some((Arc::new(map), Applied::Given))
        }
        Some(EnvArg::Studio) => Some((Arc::new(EnvironmentMap::studio()), Applied::Given)),
        Some(EnvArg::None) => {
            scene.set_environment(None);
            None
        }
        None if scene.environment().is_some() => None,
        None => {
            let decision = match resumed {
                Some(record) => Decision::resumed(scene, record).map_err(|v| {
                    format!(
                        "attribute '{}' = {} is not studio or none",
                        crate::resume::DEFAULT_LIGHT,
                        furnace_post::printable_excerpt(&v)
                    )
                })?,
                None => crate::default_light::decide_with(scene, accel),
            };
            ruled = Some(decision);
            decision.studio.then(|| {
                // A resumed render says nothing: the file decided, and another --env would
                // not continue it.
                if resumed.is_none() {
                    eprintln!(
                        "note: {}: lit by the built-in studio environment: {} (--env none for {}, --env FILE \
                     for another map)",
                        scene_file_name(scene),
                        decision.reason(),
                        if scene.has_own_light() { "its own lights alone" } else { "none" }
                    );
                }
                (Arc::new(EnvironmentMap::studio()), Applied::Rule(decision))
            })
        }
    };
    let applied = match map {
        Some((map, how)) => {
            scene.set_environment(Some(Environment::new(map)));
            how
        }
        None if scene.environment().is_some() => Applied::Own,
        None => ruled.map_or(Applied::None, Applied::Rule),
    };
    let Some(mut env) = scene.environment().cloned() else {
        if e.adjusts() {
            let why = if e.env == Some(EnvArg::None) { "--env none" } else { "the scene has none" };
            eprintln!(
                "warning: {}: {} ignored: no environment map ({why})",
                scene_file_name(scene),
                adjusting_options(e)
            );
        }
        return Ok(applied);
    };
    if let Some(x) = e.env_intensity {
        env.intensity = x;
    }
    if let Some(deg) = e.env_rotation {
        env.rotation = f64::from(deg).to_radians() as f32;
    }
    if let Some(v) = e.env_visible {
        env.visible = v == Switch::On;
    }
    scene.set_environment(Some(env));
    Ok(applied)
}

/// The adjusting options given, for messages: `--env-intensity 2 and --env-rotation 30 are`.
fn adjusting_options(e: &EnvArgs) -> String {
    let mut given = Vec::new();
    if let Some(x) = e.env_intensity {
        given.push(format!("--env-intensity {x}"));
    }
    if let Some(d) = e.env_rotation {
        given.push(format!("--env-rotation {d}"));
    }
    if let Some(v) = e.env_visible {
        given.push(format!("--env-visible {}", crate::resume::cli_name(&v)));
    }
    let verb = if given.len() == 1 { "is" } else { "are" };
    format!("{} {verb}", given.join(" and "))
}

/// The scene's file name (its name is the path it was loaded from).
fn scene_file_name(scene: &Scene) -> String {
    std::path::Path::new(&scene.name)
        .file_name()
        .map_or_else(|| scene.name.clone(), |n| n.to_string_lossy().into_owned())
}

/// `Err` for `--env-sampling compensated` with `--light-sampling nee`: MIS compensation leaves
/// the environment's dim part to BSDF rays, which NEE alone does not count.
pub fn check_sampling(env: EnvSampling, light: LightSampling) -> Result<(), String> {
    if env == EnvSampling::Compensated && light == LightSampling::Nee {
        return Err("--env-sampling compensated needs --light-sampling mis: compensation leaves the \
                    environment's dim part to BSDF rays, which --light-sampling nee does not count (use \
                    --env-sampling importance with nee)"
            .into());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use furnace_scene::builtin;

    fn args(env: Option<EnvArg>) -> EnvArgs {
        EnvArgs { env, ..EnvArgs::default() }
    }

    #[test]
    fn the_cornell_box_keeps_its_sun_and_sky() {
        let mut scene = builtin::cornell_box().unwrap();
        let hash = scene.content_hash();
        let sky = Decision { studio: false, why: crate::default_light::Why::Sky };
        assert_eq!(apply(&mut scene, &args(None), &mut None).unwrap(), Applied::Rule(sky));
        assert!(scene.environment().is_none());
        assert_eq!(scene.content_hash(), hash);
    }

    #[test]
    fn a_scene_without_light_gets_the_studio_unless_none() {
        let mut scene = builtin::cornell_box().unwrap();
        scene.lights.clear();
        for m in &mut scene.materials {
            m.emissive = glam::Vec3::ZERO;
        }
        assert!(!scene.has_own_light());
        let mut dark = scene.clone();
        let e = EnvArgs { env_rotation: Some(90.0), env_visible: Some(Switch::Off), ..args(None) };
        let studio = Decision { studio: true, why: crate::default_light::Why::NoLight };
        assert_eq!(apply(&mut scene, &e, &mut None).unwrap(), Applied::Rule(studio));
        let env = scene.environment().unwrap();
        assert_eq!((env.intensity, env.visible), (1.0, false));
        assert!((env.rotation - std::f32::consts::FRAC_PI_2).abs() < 1e-7);
        assert_eq!(apply(&mut dark, &args(Some(EnvArg::None)), &mut None).unwrap(), Applied::None);
        assert!(dark.environment().is_none());
    }

    #[test]
    fn options_scale_the_given_map_and_a_missing_file_is_named() {
        let mut scene = builtin::cornell_box().unwrap();
        let e = EnvArgs { env_intensity: Some(0.5), ..args(Some(EnvArg::Studio)) };
        assert_eq!(apply(&mut scene, &e, &mut None).unwrap(), Applied::Given);
        assert_eq!(scene.environment().unwrap().intensity, 0.5);
        assert!(scene.sun().is_some(), "the scene's sun stays");
        let e = args(Some(EnvArg::File("no/such.hdr".into())));
        let err = apply(&mut scene, &e, &mut None).unwrap_err();
        assert!(err.starts_with("no/such.hdr: "), "{err}");
    }

    #[test]
    fn compensation_needs_mis() {
        assert!(check_sampling(EnvSampling::Compensated, LightSampling::Nee).is_err());
        assert!(check_sampling(EnvSampling::Compensated, LightSampling::Mis).is_ok());
        assert!(check_sampling(EnvSampling::Compensated, LightSampling::Bsdf).is_ok());
        assert!(check_sampling(EnvSampling::Importance, LightSampling::Nee).is_ok());
    }
}
