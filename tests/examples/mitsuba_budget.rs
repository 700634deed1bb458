//! How many samples per pixel does `tests/mitsuba.rs` need at 32² (the Mitsuba
//! references box-downsampled 8×8) to meet the bar reliably?
//!
//! ```sh
//! cargo run --profile test -p furnace-tests --example mitsuba_budget -- --backend gpu --bounces 4 --seeds 3 --max-spp 512
//! ```
//!
//! Renders the built-in Cornell box at `--size` (32) with Mitsuba's model (`--model gltf`: the
//! glTF default instead), random sampler, seeds `--first-seed` (100), 101, …, one sample per
//! pass up to `--max-spp`, on the GPU (`--backend gpu`, the test's adapter) or with the CPU
//! twin (`--backend cpu`, same sampler and paths), and evaluates every prefix N ∈ {32, 64, …}
//! against the downsampled reference. `--crop C`: only the central C×C pixels. `--lights point`:
//! the point-light box of `tests/data/references/lights/` (4 bounces); `--lights area`,
//! `many_lights`, `sun_disc`: the other light references there. `--glass box|absorb` (with
//! `--bounces 8`): the glass references of `tests/data/references/glass/`.

use furnace_brdf::SpecularOptions;
use furnace_cpu::CpuRenderer;
use furnace_gpu::GpuRenderer;
use furnace_render::RenderSettings;
use furnace_sampling::SamplerKind;
use furnace_tests::cbox::{self, BatchEstimator, Estimate, Image, Reference};
use furnace_tests::gpu::test_context;
use glam::DVec3;
use rayon::prelude::*;
use std::time::Instant;

fn crop(img: &Image, c: usize) -> Image {
    let o = (img.width - c) / 2;
    let mut pixels = Vec::with_capacity(c * c);
    for y in o..o + c {
        for x in o..o + c {
            pixels.push(img.pixels[y * img.width + x]);
        }
    }
    Image { width: c, height: c, pixels }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let opt = |name: &str| args.iter().position(|a| a == name).and_then(|i| args.get(i + 1)).cloned();
    let flag = |name: &str, default: u32| opt(name).and_then(|s| s.parse().ok()).unwrap_or(default);
    let (bounces, seeds, max_spp) = (flag("--bounces", 4), flag("--seeds", 1), flag("--max-spp", 512));
    let first_seed = flag("--first-seed", 100);
    let size = flag("--size", 32);
    let crop_size = flag("--crop", size) as usize;
    let gpu = opt("--backend").as_deref() != Some("cpu");
    let specular = if opt("--model").as_deref() == Some("gltf") {
        SpecularOptions::default()
    } else {
        SpecularOptions::mitsuba()
    };
    // `--lights point`: the point-light box of `references/lights/` instead of the Cornell box.
    // `--glass box|absorb`: a glass reference of `references/glass/` (8 bounces).
    let lights = opt("--lights");
    let glass = opt("--glass");
    let (folder, file, stem) = match (glass.as_deref(), lights.as_deref(), bounces) {
        (Some(kind), _, _) => ("glass", format!("glass_{kind}"), format!("glass_{kind}_ref_bounces8")),
        (None, Some(kind), _) => ("lights", format!("cbox_{kind}"), format!("cbox_{kind}_ref_bounces4")),
        (None, None, 1) => ("cbox", String::new(), "cbox_ref_direct".to_string()),
        (None, None, _) => ("cbox", String::new(), "cbox_ref_bounces4".to_string()),
    };
    let stem = stem.as_str();
    let full = match folder {
        "cbox" => Reference::load(stem),
        _ => Reference::load_in(folder, stem),
    };
    let base_scene = match folder {
        "cbox" => furnace_scene::builtin::cornell_box().expect("the built-in Cornell box"),
        _ => furnace_scene::Scene::load(furnace_tests::data::reference(&format!("{folder}/{file}.gltf")))
            .expect("the reference's scene"),
    };
    let factor = full.mean.width / size as usize;
    let small = cbox::downsample(&full, factor);
    let reference = Reference {
        name: stem.to_owned(),
        mean: crop(&small.mean, crop_size),
        stderr: crop(&small.stderr, crop_size),
    };
    // Scenes with emitters: the image-mean ratio over the pixels that show none (as the test).
    let mask =
        cbox::pixels_without_visible_emitters(&base_scene, size).filter(|_| crop_size == size as usize);
    let checkpoints: Vec<u32> = (5..=16).map(|k| 1u32 << k).filter(|&n| n <= max_spp).collect();
    println!(
        "{stem}, {size}² (crop {crop_size}²), {} backend, {:?}",
        if gpu { "gpu" } else { "cpu" },
        opt("--model").unwrap_or("mitsuba".into())
    );
    println!(
        "| seed | spp | ratio R, G, B (± se) | z mean | z std | \\|z\\|>3 | max \\|z\\| (pixel) | z values | s |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    let n = (size * size) as usize;
    for seed in first_seed..first_seed + seeds {
        let settings = RenderSettings {
            width: size,
            height: size,
            bounces,
            sampler: SamplerKind::Random,
            seed,
            specular,
            ..Default::default()
        };
        let scene = base_scene.clone();
        let start = Instant::now();
        let mut estimators = vec![BatchEstimator::new(1); n];
        let mut gpu_renderer = gpu.then(|| {
            GpuRenderer::new(test_context().unwrap(), &scene, &scene.default_camera(), settings).unwrap()
        });
        let cpu_renderer = CpuRenderer::with_default_camera(scene.clone(), settings).unwrap();
        let mut prev = furnace_render::Film::new(size, size);
        for k in 0..max_spp {
            if let Some(g) = gpu_renderer.as_mut() {
                g.render_pass(k, 1).unwrap();
                let now = g.film().unwrap();
                assert_eq!(now.rejected(), 0);
                for (i, e) in estimators.iter_mut().enumerate() {
                    e.push(DVec3::from_array(std::array::from_fn(|c| now.sums()[i][c] - prev.sums()[i][c])));
                }
                prev = now;
            } else {
                estimators.par_iter_mut().enumerate().for_each(|(i, e)| {
                    let (x, y) = (i as u32 % size, i as u32 / size);
                    e.push(cpu_renderer.sample(x, y, k).as_dvec3());
                });
            }
            if checkpoints.contains(&(k + 1)) {
                let per: Vec<(DVec3, DVec3)> = estimators.iter().map(BatchEstimator::estimate).collect();
                let img = |f: fn(&(DVec3, DVec3)) -> DVec3| {
                    crop(
                        &Image {
                            width: size as usize,
                            height: size as usize,
                            pixels: per.iter().map(f).collect(),
                        },
                        crop_size,
                    )
                };
                let est = Estimate { mean: img(|p| p.0), stderr: img(|p| p.1) };
                let c = cbox::compare_masked(&est, &reference, mask.as_deref());
                println!("| {seed} | {} | {} | {:.1} |", k + 1, c.cells(), start.elapsed().as_secs_f64());
            }
        }
    }
}
