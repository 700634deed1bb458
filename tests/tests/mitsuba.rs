//! Both integrators against Mitsuba 3 (`tests/data/references/cbox/`, `lights/`, `envmap/`,
//! `glass/`, an independent renderer): the CPU at the references' resolution or 64², the GPU
//! (lavapipe in CI) at 32² against the references averaged over blocks. The bar:
//!
//! * per-channel image-mean ratio ours/Mitsuba within ±0.5%;
//! * per-pixel z-scores `z = (ours − ref)/√(se_ours² + se_ref²)` (over every pixel and channel
//!   whose denominator is not 0) with standard deviation in [0.9, 1.15]; z mean and the fraction
//!   with |z| > 3 are reported.
//!
//! We render with Mitsuba's material model (`SpecularOptions::mitsuba()`: separable masking, no
//! compensation) and the random sampler. A candidate's own standard error comes from the spread of
//! its passes, each of 1 or 2 samples per pixel (few large passes would make z follow Student's t
//! with a standard deviation above the bar before any bias).
//!
//! Each test's size and sample count is the cheapest at which an unbiased render meets the bar at
//! every seed measured, with margin: rare bright paths (a sky through a hole, a GGX tail, a
//! caustic) skew per-pixel estimates and lift z's standard deviation above 1 until enough samples
//! per compared pixel have drawn them. Downsampling the references by box averaging is exact for
//! this camera and filter (`downsampling_keeps_the_image_mean_and_pools_the_errors`). The
//! measurements behind every budget, how to repeat them (`examples/mitsuba_budget.rs`,
//! `examples/reference_budget.rs`) and each test's figures at seed 11 are in
//! `docs/reference-tests.md`. Tests too slow for a software adapter are `#[ignore]`d and run with
//! `--ignored` on a hardware GPU.
//!
//! `gltf_default_model_fails_the_bar_*` renders with the glTF default model instead of Mitsuba's
//! (only the metal sphere changes): it must fail, on the ratio alone, so the bar can fail.

use furnace_brdf::SpecularOptions;
use furnace_render::{PointLightSampling, RenderSettings};
use furnace_sampling::SamplerKind;
use furnace_tests::backends::Backend;
use furnace_tests::cbox::{self, Comparison, Estimate, Image, Reference};
use glam::DVec3;
use std::path::PathBuf;
use std::time::Instant;

/// The bar (see the module docs).
const MAX_RATIO_ERROR: f64 = 5e-3;
const Z_STD_RANGE: (f64, f64) = (0.9, 1.15);
/// Fixed seed of the random sampler (docs/reference-tests.md: the spread over seeds).
const SEED: u32 = 11;

/// What a backend renders: its image size and one-sample passes per reference.
struct Plan {
    /// Width; the height keeps the reference's aspect ratio.
    size: u32,
    bounces: u32,
    passes: u32,
    spp_per_pass: u32,
}

/// The configurations docs/reference-tests.md derives.
fn plan(backend: Backend, stem: &str) -> Plan {
    let (size, bounces, passes, spp_per_pass) = match (backend, stem) {
        (Backend::Cpu, "cbox_ref_direct") => (256, 1, 512, 1),
        (Backend::Cpu, "cbox_ref_bounces4") => (256, 4, 128, 1),
        (Backend::Cpu, "cbox_point_ref_bounces4") => (64, 4, 512, 1),
        (Backend::Cpu, "cbox_area_ref_bounces4") => (64, 4, 512, 1),
        (Backend::Cpu, "cbox_many_lights_ref_bounces4") => (64, 4, 4096, 1),
        (Backend::Cpu, "cbox_sun_disc_ref_bounces4") => (64, 4, 512, 1),
        // The caustic's skew needs many samples per compared pixel (docs/reference-tests.md).
        (Backend::Cpu, "envmap_spheres_ref_bounces4") => (20, 4, 32768, 1),
        (Backend::Gpu, "cbox_ref_direct") => (32, 1, 1024, 1),
        (Backend::Gpu, "cbox_ref_bounces4") => (32, 4, 256, 1),
        (Backend::Gpu, "cbox_point_ref_bounces4") => (32, 4, 512, 2),
        (Backend::Gpu, "cbox_area_ref_bounces4") => (32, 4, 256, 2),
        (Backend::Gpu, "cbox_sun_disc_ref_bounces4") => (32, 4, 128, 2),
        (Backend::Gpu, "envmap_spheres_ref_bounces4") => (20, 4, 512, 64),
        // The glass box's caustics skew every pixel's estimate (docs/reference-tests.md): 65 536 spp at 16².
        (Backend::Cpu, "glass_box_ref_bounces8") => (16, 8, 4096, 16),
        (Backend::Cpu, "glass_absorb_ref_bounces8") => (64, 8, 1024, 1),
        // Full size on a hardware GPU (ignored in CI), as many samples as the references.
        (Backend::Gpu, "glass_box_ref_bounces8" | "glass_absorb_ref_bounces8") => (256, 8, 512, 128),
        _ => panic!("no plan for {backend}, {stem}"),
    };
    Plan { size, bounces, passes, spp_per_pass }
}

/// The scenes of the references: `cbox_ref_*` is the built-in Cornell box; the others are the
/// glTF files beside their references.
fn case(stem: &str) -> (&'static str, furnace_scene::Scene) {
    match stem {
        "cbox_ref_direct" | "cbox_ref_bounces4" => {
            ("cbox", furnace_scene::builtin::cornell_box().expect("the built-in Cornell box"))
        }
        "cbox_point_ref_bounces4"
        | "cbox_area_ref_bounces4"
        | "cbox_many_lights_ref_bounces4"
        | "cbox_sun_disc_ref_bounces4" => {
            let file = stem.trim_end_matches("_ref_bounces4");
            let path = furnace_tests::data::reference(&format!("lights/{file}.gltf"));
            let scene = furnace_scene::Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
            assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
            ("lights", scene)
        }
        "glass_box_ref_bounces8" | "glass_absorb_ref_bounces8" => {
            let file = stem.trim_end_matches("_ref_bounces8");
            let path = furnace_tests::data::reference(&format!("glass/{file}.gltf"));
            let scene = furnace_scene::Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
            assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
            ("glass", scene)
        }
        "envmap_spheres_ref_bounces4" => {
            let path = furnace_tests::data::reference("envmap/envmap_spheres.gltf");
            let scene = furnace_scene::Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
            assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
            assert!(scene.environment().is_some(), "the scene names its environment map");
            ("envmap", scene)
        }
        _ => panic!("no scene for {stem}"),
    }
}

/// `{stem}.exr` and `{stem}_stderr.exr` of `folder`, downsampled to `size` pixels wide.
fn reference(folder: &str, stem: &str, size: u32) -> Reference {
    let full = Reference::load_in(folder, stem);
    if full.mean.width == size as usize {
        return full;
    }
    cbox::downsample(&full, full.mean.width / size as usize)
}

/// `passes` passes of one sample per pixel on `backend`; each pixel's mean and standard error
/// from its own samples. `None` when GPU tests are skipped.
fn render(
    backend: Backend,
    scene: &furnace_scene::Scene,
    (width, height): (u32, u32),
    bounces: u32,
    (specular, point_lights): (SpecularOptions, PointLightSampling),
    passes: u32,
    spp_per_pass: u32,
) -> Option<Estimate> {
    let settings = RenderSettings {
        width,
        height,
        bounces,
        sampler: SamplerKind::Random,
        seed: SEED,
        specular,
        point_lights,
        ..Default::default()
    };
    let mut integrator = backend.open_default(scene, settings)?;
    Some(cbox::render_passes(integrator.as_mut(), passes, spp_per_pass))
}

fn passes_bar(c: &Comparison) -> bool {
    (c.ratio() - 1.0).abs().max_element() < MAX_RATIO_ERROR
        && (Z_STD_RANGE.0..=Z_STD_RANGE.1).contains(&c.z_std)
}

fn table(
    backend: Backend,
    stem: &str,
    model: &str,
    (size, height, block): (u32, u32, u32),
    passes: (u32, u32),
    c: &Comparison,
    seconds: f64,
) -> String {
    format!(
        "| backend | reference | model | size | passes × spp | ratio R, G, B (± se) | z mean | z std | \\|z\\| > 3 | max \\|z\\| | z values | time |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|\n\
         | {backend} | {stem} | {model} | {size}×{height} ({block}×{block} blocks) | {} × {} | {} | {seconds:.1} s |",
        passes.0,
        passes.1,
        c.cells()
    )
}

/// A render compared with a (downsampled) reference, and the table that describes it.
struct Outcome {
    name: String,
    reference: Reference,
    candidate: Estimate,
    comparison: Comparison,
    table: String,
}

impl Outcome {
    /// Writes the candidate, its standard error, the reference, its error, the z image and the
    /// table to `target/test-output/mitsuba/`; returns the folder.
    fn write(&self) -> PathBuf {
        let dir = furnace_tests::data::output_dir("mitsuba");
        for (what, image) in [
            ("candidate", &self.candidate.mean),
            ("candidate_stderr", &self.candidate.stderr),
            ("reference", &self.reference.mean),
            ("reference_stderr", &self.reference.stderr),
            ("z", &self.comparison.z_image),
        ] {
            image.write_exr(&dir.join(format!("{}_{what}.exr", self.name)));
        }
        std::fs::write(dir.join(format!("{}.md", self.name)), format!("{}\n", self.table))
            .expect("writing the table");
        dir
    }
}

/// Renders `stem`'s configuration on `backend` with `specular` and compares it with the
/// reference; `None` when GPU tests are skipped.
fn evaluate(
    backend: Backend,
    stem: &str,
    model: (SpecularOptions, PointLightSampling),
    model_name: &str,
) -> Option<Outcome> {
    let plan = plan(backend, stem);
    let (bounces, passes) = (plan.bounces, plan.passes);
    let (folder, scene) = case(stem);
    let full_width = Reference::load_in(folder, stem).mean.width as u32;
    let reference = reference(folder, stem, plan.size);
    let height = reference.mean.height as u32;
    let start = Instant::now();
    let candidate = render(backend, &scene, (plan.size, height), bounces, model, passes, plan.spp_per_pass)?;
    let seconds = start.elapsed().as_secs_f64();
    let mask = cbox::pixels_without_visible_emitters(&scene, plan.size);
    let comparison = cbox::compare_masked(&candidate, &reference, mask.as_deref());
    let shape = (plan.size, height, full_width / plan.size);
    let table = table(backend, stem, model_name, shape, (passes, plan.spp_per_pass), &comparison, seconds);
    println!("{table}");
    let name = format!("{stem}_{backend}_{}_{model_name}", plan.size).replace(' ', "_");
    Some(Outcome { name, reference, candidate, comparison, table })
}

fn compare(backend: Backend, stem: &str) {
    compare_with(backend, stem, PointLightSampling::default());
}

/// [`compare`] with the point lights gathered by `point_lights`.
fn compare_with(backend: Backend, stem: &str, point_lights: PointLightSampling) {
    let model = match point_lights {
        PointLightSampling::One => "Mitsuba, one point light per event",
        _ => "Mitsuba",
    };
    let Some(o) = evaluate(backend, stem, (SpecularOptions::mitsuba(), point_lights), model) else { return };
    let c = &o.comparison;
    if !passes_bar(c) {
        let dir = o.write();
        panic!(
            "{backend}, {stem}: ratio {:.5} (bar ±{MAX_RATIO_ERROR}), z std {:.3} (bar {Z_STD_RANGE:?}); \
             candidate, its standard error, the reference, z images and the table in {}",
            c.ratio(),
            c.z_std,
            dir.display()
        );
    }
}

/// The bar is sharp enough to see a wrong material model: the glTF default (height-correlated
/// masking, Turquin compensation) instead of Mitsuba's, on the metal sphere only, at the
/// 4-bounce test's settings. It must fail the ratio part of the bar (by itself: measured 1.028
/// for red, ±0.0015, on the GPU), not just the noisier z part.
fn gltf_default_model_fails(backend: Backend) {
    let stem = "cbox_ref_bounces4";
    let Some(o) =
        evaluate(backend, stem, (SpecularOptions::default(), PointLightSampling::All), "glTF default")
    else {
        return;
    };
    let c = &o.comparison;
    let worst = (c.ratio() - 1.0).abs().max_element();
    if worst < MAX_RATIO_ERROR {
        let dir = o.write();
        panic!(
            "{backend}: the glTF default model came within the bar on the ratio: {:.5} (bar ±{MAX_RATIO_ERROR}), \
             z std {:.3}: the test cannot tell the models apart; images and table in {}",
            c.ratio(),
            c.z_std,
            dir.display()
        );
    }
}

#[test]
fn downsampling_keeps_the_image_mean_and_pools_the_errors() {
    // A 4×4 image with distinct values and errors, averaged over 2×2 blocks.
    let pixels = |f: fn(usize) -> f64| (0..16).map(|k| DVec3::new(f(k), 2.0 * f(k), 0.0)).collect();
    let r = Reference {
        name: "synthetic".into(),
        mean: Image { width: 4, height: 4, pixels: pixels(|k| k as f64) },
        stderr: Image { width: 4, height: 4, pixels: pixels(|k| 1.0 + (k % 3) as f64) },
    };
    let d = cbox::downsample(&r, 2);
    assert_eq!((d.mean.width, d.mean.height), (2, 2));
    // Block (1, 0) holds pixels 2, 3, 6, 7: mean 4.5; errors 3, 1, 1, 2: √(9+1+1+4)/4.
    assert_eq!(d.mean.pixels[1], DVec3::new(4.5, 9.0, 0.0));
    assert!((d.stderr.pixels[1].x - 15f64.sqrt() / 4.0).abs() < 1e-15, "{:?}", d.stderr.pixels[1]);
    // The image mean is unchanged (exactly: sums of small integers), and so is the standard
    // error of the image mean, √(Σ se²)/n, that the ratio's error comes from.
    assert_eq!(d.mean.mean(), r.mean.mean());
    let var_of_mean =
        |i: &Image| i.pixels.iter().map(|s| s.x * s.x).sum::<f64>() / (i.pixels.len() as f64).powi(2);
    assert!((var_of_mean(&d.stderr) - var_of_mean(&r.stderr)).abs() < 1e-15);
}

#[test]
fn cornell_box_direct_matches_mitsuba_cpu() {
    compare(Backend::Cpu, "cbox_ref_direct");
}

#[test]
fn cornell_box_four_bounces_matches_mitsuba_cpu() {
    compare(Backend::Cpu, "cbox_ref_bounces4");
}

#[test]
fn cornell_box_direct_matches_mitsuba_gpu() {
    compare(Backend::Gpu, "cbox_ref_direct");
}

#[test]
fn cornell_box_four_bounces_matches_mitsuba_gpu() {
    compare(Backend::Gpu, "cbox_ref_bounces4");
}

#[test]
fn point_lights_match_mitsuba_cpu() {
    compare(Backend::Cpu, "cbox_point_ref_bounces4");
}

#[test]
fn point_lights_match_mitsuba_gpu() {
    compare(Backend::Gpu, "cbox_point_ref_bounces4");
}

/// One point light per event, chosen by power (`--point-lights one`), as Mitsuba chooses one
/// emitter per event (uniformly there): the same expectation, more noise per sample, which z
/// measures against the candidate's own standard error.
#[test]
fn point_lights_one_per_event_match_mitsuba_cpu() {
    compare_with(Backend::Cpu, "cbox_point_ref_bounces4", PointLightSampling::One);
}

#[test]
fn point_lights_one_per_event_match_mitsuba_gpu() {
    compare_with(Backend::Gpu, "cbox_point_ref_bounces4", PointLightSampling::One);
}

#[test]
fn emissive_quad_matches_mitsuba_cpu() {
    compare(Backend::Cpu, "cbox_area_ref_bounces4");
}

#[test]
fn emissive_quad_matches_mitsuba_gpu() {
    compare(Backend::Gpu, "cbox_area_ref_bounces4");
}

#[test]
fn many_emitters_match_mitsuba_cpu() {
    compare(Backend::Cpu, "cbox_many_lights_ref_bounces4");
}

#[test]
fn sun_disc_matches_mitsuba_cpu() {
    compare(Backend::Cpu, "cbox_sun_disc_ref_bounces4");
}

#[test]
fn sun_disc_matches_mitsuba_gpu() {
    compare(Backend::Gpu, "cbox_sun_disc_ref_bounces4");
}

#[test]
fn environment_map_matches_mitsuba_cpu() {
    compare(Backend::Cpu, "envmap_spheres_ref_bounces4");
}

#[test]
#[ignore = "32 768 spp: minutes on a software adapter; run with --ignored on a hardware GPU"]
fn environment_map_matches_mitsuba_gpu() {
    compare(Backend::Gpu, "envmap_spheres_ref_bounces4");
}

#[test]
fn glass_matches_mitsuba_cpu() {
    compare(Backend::Cpu, "glass_absorb_ref_bounces8");
}

#[test]
#[ignore = "65 536 spp per pixel (the caustic's skew, above): 20 s alone, about 50 s of CI's 2 busy cores; \
            CI traces the glass box on both backends from the same samples (tests/integrator.rs) and checks \
            its interfaces in closed form (glass_cases/closed_forms.rs); run with --ignored"]
fn glass_box_matches_mitsuba_cpu() {
    compare(Backend::Cpu, "glass_box_ref_bounces8");
}

#[test]
#[ignore = "full size, 65 536 spp: a hardware GPU's work (run with --ignored); in CI the GPU traces the CPU's paths (tests/integrator.rs)"]
fn glass_matches_mitsuba_gpu() {
    compare(Backend::Gpu, "glass_absorb_ref_bounces8");
    compare(Backend::Gpu, "glass_box_ref_bounces8");
}

#[test]
fn gltf_default_model_fails_the_bar_cpu() {
    gltf_default_model_fails(Backend::Cpu);
}

#[test]
fn gltf_default_model_fails_the_bar_gpu() {
    gltf_default_model_fails(Backend::Gpu);
}
