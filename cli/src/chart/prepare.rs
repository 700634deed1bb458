//! Resolving a study from the arguments and the references: the scene, the checks of what a
//! furnace reference records, the model and bounces, the configurations, and warnings about
//! biased or correlated comparisons.

use super::axes::configurations;
use super::reference::Reference;
use super::study::{Study, checkpoints, dedup};
use crate::args::{ChartArgs, SceneArg, Switch};
use crate::resume;
use furnace_brdf::Masking;
use furnace_render::RenderSettings;
use furnace_render::{Choice, EnvSampling, LightSampling};
use furnace_scene::{Scene, builtin};

fn load_scene(scene: &SceneArg) -> Result<(Scene, String), String> {
    Ok(match scene {
        SceneArg::Cbox => (builtin::cornell_box().map_err(|e| e.to_string())?, "cbox".to_string()),
        SceneArg::Interior(n) => (builtin::sunlit_interior(*n), format!("interior:{n}")),
        SceneArg::Forest(n, seed) => (builtin::forest(*n, *seed), format!("forest:{n}:{seed}")),
        SceneArg::File(p) => (Scene::load(p).map_err(|e| e.to_string())?, p.display().to_string()),
    })
}

/// Resolves the study from the arguments and the references, checking what a furnace reference
/// records; prints warnings about biased or correlated comparisons.
pub(super) fn prepare(a: &ChartArgs) -> Result<Study, String> {
    let (mut scene, scene_name) = load_scene(&a.scene)?;
    for w in &scene.warnings {
        eprintln!("warning: {}: {w}", scene.name);
    }
    crate::env::apply(&mut scene, &a.environment, &mut None)?;
    let (reference, compensated) = load_references(a)?;
    let recorded_bounces = check_recorded(a, &reference, compensated.as_ref(), &scene, &scene_name)?;
    let masking = study_masking(a, &reference, compensated.as_ref());
    if !reference.furnace && a.bounces.is_none() {
        eprintln!(
            "note: {} records no bounces: using 4 (give --bounces to change)",
            reference.path.display()
        );
    }
    let bounces = a.bounces.or(recorded_bounces).unwrap_or(4);
    let mut settings = RenderSettings {
        width: reference.width,
        height: reference.height,
        bounces,
        seed: a.seed,
        russian_roulette: false,
        ..RenderSettings::default()
    };
    settings.specular.masking = masking;
    let mut study = Study {
        args: a.clone(),
        scene: std::sync::Arc::new(scene),
        scene_name,
        settings,
        checkpoints: checkpoints(a.spp),
        configs: Vec::new(),
        reference,
        compensated,
    };
    let importance_listed = a.env_sampling.contains(&EnvSampling::Importance);
    study.configs = configurations(&study, |mut c| {
        let s = &mut c.settings;
        if s.env_sampling == EnvSampling::Compensated && s.light_sampling == LightSampling::Nee {
            // Compensation needs MIS: under nee a render samples the plain distribution
            // (EnvSampling::effective), once.
            if importance_listed {
                return None;
            }
            s.env_sampling = EnvSampling::Importance;
        }
        Some(c)
    })?;
    if a.denoise.contains(&Switch::On) && !furnace_denoise::available() {
        return Err(furnace_denoise::DenoiseError::NotBuilt.to_string());
    }
    if study.configs.is_empty() {
        return Err(
            "no configurations: give at least one sampler, sampling method, light sampling, triangle \
             sampling, light selection, environment sampling and backend"
                .into(),
        );
    }
    if dedup(&a.env_sampling).len() > 1
        && dedup(&a.env_sampling).contains(&EnvSampling::Compensated)
        && dedup(&a.light_sampling).contains(&LightSampling::Nee)
    {
        eprintln!(
            "note: under --light-sampling nee the environment is sampled by importance (compensation \
             needs MIS): the compensated configurations with nee are the importance ones"
        );
    }
    warn_compensation_mismatch(&study);
    warn_correlated_seed(&study);
    Ok(study)
}

/// `--reference` and `--reference-compensated`, checked against each other: the second must
/// have compensation on, the first off, and both the same size.
fn load_references(a: &ChartArgs) -> Result<(Reference, Option<Reference>), String> {
    let reference = Reference::load(&a.reference, a.reference_compensation, Switch::Off)?;
    let compensated =
        a.reference_compensated.as_deref().map(|p| Reference::load(p, None, Switch::On)).transpose()?;
    if let Some(rc) = &compensated {
        if rc.compensation != Switch::On {
            return Err(format!(
                "{} records --compensation off: --reference-compensated takes a render with compensation on",
                rc.path.display()
            ));
        }
        if reference.compensation == Switch::On {
            return Err(format!(
                "{} was rendered with compensation on too: --reference takes the render without it when \
                 --reference-compensated is given",
                reference.path.display()
            ));
        }
        if (rc.width, rc.height) != (reference.width, reference.height) {
            return Err(format!(
                "size mismatch: {} is {}×{} but {} is {}×{}",
                rc.path.display(),
                rc.width,
                rc.height,
                reference.path.display(),
                reference.width,
                reference.height
            ));
        }
    }
    Ok((reference, compensated))
}

/// Checks what the furnace references record against the study (scene, camera, bounces) and
/// returns the bounces they record; warns about a reference with too few samples.
fn check_recorded(
    a: &ChartArgs,
    reference: &Reference,
    compensated: Option<&Reference>,
    scene: &Scene,
    scene_name: &str,
) -> Result<Option<u32>, String> {
    let scene_hash = scene.content_hash();
    let mut recorded_bounces = None;
    for r in std::iter::once(reference).chain(compensated) {
        let p = r.path.display();
        if !r.furnace {
            continue;
        }
        let extra = |k: &str| r.metadata.extra.get(k).map(String::as_str);
        if extra(resume::SCENE_HASH) != Some(scene_hash.as_str()) {
            // The environment options are part of the scene: name those the reference had.
            let env: Vec<String> = [
                (resume::ENV, "--env"),
                (resume::ENV_INTENSITY, "--env-intensity"),
                (resume::ENV_ROTATION, "--env-rotation"),
                (resume::ENV_VISIBLE, "--env-visible"),
            ]
            .iter()
            .filter_map(|(k, flag)| extra(k).map(|v| format!("{flag} {v}")))
            .collect();
            let hint = if env.is_empty() {
                String::new()
            } else {
                format!(" (it was rendered with {}: give the same)", env.join(" "))
            };
            return Err(format!(
                "{p} was rendered from another scene (or another version of it) than {scene_name}{hint}"
            ));
        }
        if let Some(c) = extra(resume::CAMERA).filter(|&c| c != "0" && c != resume::FRAMED) {
            return Err(format!(
                "{p} was rendered with {}; furnace chart renders the scene's first camera",
                resume::camera_options(c)
            ));
        }
        if let Some(b) = r.metadata.bounces {
            if b > furnace_render::MAX_BOUNCES {
                return Err(format!(
                    "{p}: attribute 'furnace.bounces' = {b} is more than furnace renders (at most {})",
                    furnace_render::MAX_BOUNCES
                ));
            }
            match (a.bounces, recorded_bounces) {
                (Some(given), _) if given != b => {
                    return Err(format!("{p} was rendered with --bounces {b}, not {given}"));
                }
                (_, Some(other)) if other != b => {
                    return Err(format!("the two references differ in bounces ({other} and {b})"));
                }
                _ => recorded_bounces = Some(b),
            }
        }
        if let Some(n) = r.metadata.spp
            && u64::from(n) < 16 * u64::from(a.spp)
        {
            eprintln!(
                "warning: {p} has {n} spp, less than 16 × --spp {}: its own noise adds to the measured error \
                 at the last checkpoints",
                a.spp
            );
        }
    }
    Ok(recorded_bounces)
}

/// The study's masking: `--masking`, else the reference's, else height-correlated (with a
/// note); warns about each reference rendered with another.
fn study_masking(a: &ChartArgs, reference: &Reference, compensated: Option<&Reference>) -> Masking {
    let masking = match (a.masking, reference.masking) {
        (Some(m), _) => m,
        (None, Some(m)) => m,
        (None, None) => {
            eprintln!(
                "note: {} records no model (not a furnace render): assuming masking height-correlated and \
                 compensation {}; give --masking and --reference-compensation to match the renderer that made \
                 it (Mitsuba 3: --masking separable --reference-compensation off)",
                reference.path.display(),
                resume::cli_name(&reference.compensation)
            );
            Masking::HeightCorrelated
        }
    };
    for r in std::iter::once(reference).chain(compensated) {
        if let Some(m) = r.masking.filter(|&m| m != masking) {
            eprintln!(
                "warning: {} was rendered with --masking {}, the study uses {}: every configuration is biased \
                 against it (reference_matches = false)",
                r.path.display(),
                m.name(),
                masking.name()
            );
        }
    }
    masking
}

/// Warns about the compensation states scored against a reference rendered with the other.
fn warn_compensation_mismatch(study: &Study) {
    for comp in study.compensations() {
        let mut probe = study.configs[0];
        probe.settings.specular.compensation = comp == Switch::On;
        let (r, matches) = study.reference_for(&probe);
        if !matches && r.compensation != comp {
            eprintln!(
                "warning: the configurations with compensation {} are scored against {}, rendered with \
                 compensation {}: their error flattens at that model difference (reference_matches = false; \
                 give --reference-compensated for a matching reference)",
                resume::cli_name(&comp),
                r.path.display(),
                resume::cli_name(&r.compensation)
            );
        }
    }
}

/// Warns about configurations whose samples are the reference's own (same sampler and seed).
fn warn_correlated_seed(study: &Study) {
    let seed_arg = study.args.seed;
    for r in std::iter::once(&study.reference).chain(&study.compensated) {
        let (Some(sampler), Some(seed)) = (&r.metadata.sampler, r.metadata.seed) else { continue };
        if r.furnace
            && seed == u64::from(seed_arg)
            && study.configs.iter().any(|c| c.settings.sampler.name() == sampler)
        {
            eprintln!(
                "warning: {} was rendered with the {sampler} sampler and seed {seed}, as this study's {sampler} \
                 configurations: their first samples are the reference's own, so their error is underestimated \
                 (give another --seed)",
                r.path.display()
            );
        }
    }
}
