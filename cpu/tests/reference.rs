//! The Cornell box against Mitsuba 3 (`tests/data/cbox/`, an independent renderer): bias test.
//!
//! The 256×256 references are averaged over 4×4 blocks to 64×64; with a one-pixel box filter
//! that is exactly what a 64×64 render converges to (a block's mean is the mean over its area),
//! so the comparison needs no resampling assumptions. We render with Mitsuba's material model
//! (`SpecularOptions::mitsuba()`: separable masking, no compensation) and the random sampler in
//! `PASSES` independent passes, estimate each pixel's standard error from the passes, and
//! compute per-pixel `z = (ours − ref)/√(se_ours² + se_ref²)`.
//!
//! An unbiased renderer gives z of mean ≈ 0 and, with 8 passes, standard deviation ≈ 1.18
//! (Student's t with 7 degrees of freedom; see the references' README). Tolerances: |mean z|
//! < 0.1 (the standard error of the mean of 4096 z-values is ~0.02; a bias of 1% in a pixel
//! of 5% relative noise shifts z by 0.2), std z < 1.35, and per-channel image means within
//! 4 of their standard errors of the reference's. 256 samples per pixel per pass: with 32, rare
//! bright paths (the metal sphere's GGX tail reaching the sky) are missing from all 8 passes of
//! some pixels, whose estimated error is then 0 and z meaningless. On failure the candidate,
//! reference and z images are written to `target/test-output/furnace-cpu/`.

use furnace_brdf::SpecularOptions;
use furnace_cpu::{RenderSettings, Renderer};
use furnace_sampling::SamplerKind;
use glam::DVec3;
use std::path::Path;

const SIZE: u32 = 64;
const BLOCK: usize = 4;
const PASSES: u32 = 8;

/// An RGB EXR as `(width, height, row-major pixels)`.
fn read_exr(name: &str) -> (usize, usize, Vec<DVec3>) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/cbox").join(name);
    let image = exr::prelude::read_first_rgba_layer_from_file(
        &path,
        |resolution, _| (resolution.width(), resolution.height(), vec![DVec3::ZERO; resolution.area()]),
        |(w, _, pixels), position, (r, g, b, _a): (f32, f32, f32, f32)| {
            pixels[position.y() * *w + position.x()] = DVec3::new(r.into(), g.into(), b.into());
        },
    )
    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    image.layer_data.channel_data.pixels
}

/// The reference and its standard error, averaged over `BLOCK × BLOCK` blocks.
fn reference(stem: &str) -> (Vec<DVec3>, Vec<DVec3>) {
    let (w, h, mean) = read_exr(&format!("{stem}.exr"));
    let (_, _, stderr) = read_exr(&format!("{stem}_stderr.exr"));
    assert_eq!((w, h), (SIZE as usize * BLOCK, SIZE as usize * BLOCK));
    let mut m = vec![DVec3::ZERO; (SIZE * SIZE) as usize];
    let mut v = vec![DVec3::ZERO; (SIZE * SIZE) as usize];
    let n = (BLOCK * BLOCK) as f64;
    for y in 0..h {
        for x in 0..w {
            let i = (y / BLOCK) * SIZE as usize + x / BLOCK;
            m[i] += mean[y * w + x] / n;
            // Pixels' errors are independent: the block mean's variance is Σ se²/n².
            v[i] += stderr[y * w + x] * stderr[y * w + x] / (n * n);
        }
    }
    (m, v.into_iter().map(|v| v.map(f64::sqrt)).collect())
}

fn compare(stem: &str, bounces: u32, spp: u32) {
    let (ref_mean, ref_se) = reference(stem);
    let scene = furnace_scene::builtin::cornell_box().expect("the built-in Cornell box");
    let settings = RenderSettings {
        width: SIZE,
        height: SIZE,
        bounces,
        sampler: SamplerKind::Random,
        seed: 11,
        specular: SpecularOptions::mitsuba(),
        ..Default::default()
    };
    let renderer = Renderer::new(scene, settings).expect("a progressive sampler");
    let passes: Vec<Vec<DVec3>> = (0..PASSES)
        .map(|p| {
            let mut film = renderer.new_film();
            renderer.render_pass(&mut film, p * spp, spp).expect("render");
            assert_eq!(film.rejected(), 0);
            (0..SIZE * SIZE).map(|i| film.pixel(i % SIZE, i / SIZE)).collect()
        })
        .collect();
    let n = f64::from(PASSES);
    let pixels = (SIZE * SIZE) as usize;
    let mut zs = Vec::with_capacity(pixels * 3);
    let mut z_image = vec![DVec3::ZERO; pixels];
    let mut candidate = vec![DVec3::ZERO; pixels];
    let (mut ours_total, mut ours_var, mut ref_total) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
    for i in 0..pixels {
        let mean = passes.iter().map(|p| p[i]).sum::<DVec3>() / n;
        let var = passes.iter().map(|p| (p[i] - mean) * (p[i] - mean)).sum::<DVec3>() / (n - 1.0) / n;
        candidate[i] = mean;
        ours_total += mean;
        ours_var += var;
        ref_total += ref_mean[i];
        let se = (var + ref_se[i] * ref_se[i]).map(f64::sqrt);
        for c in 0..3 {
            if se[c] > 0.0 {
                let z = (mean[c] - ref_mean[i][c]) / se[c];
                z_image[i][c] = z;
                zs.push(z);
            }
        }
    }
    let p = pixels as f64;
    let (ours_img, ref_img, img_se) = (ours_total / p, ref_total / p, ours_var.map(f64::sqrt) / p);
    let z_mean = zs.iter().sum::<f64>() / zs.len() as f64;
    let z_std = (zs.iter().map(|z| (z - z_mean).powi(2)).sum::<f64>() / (zs.len() as f64 - 1.0)).sqrt();
    println!(
        "{stem}: image mean {ours_img:.5} ± {img_se:.6} vs Mitsuba {ref_img:.5} (ratio {:.4}); z mean {z_mean:.3}, std {z_std:.3} over {} values",
        ours_img / ref_img,
        zs.len()
    );
    let means_ok = (0..3).all(|c| (ours_img[c] - ref_img[c]).abs() < 4.0 * img_se[c]);
    if !(means_ok && z_mean.abs() < 0.1 && z_std < 1.35) {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/test-output/furnace-cpu");
        std::fs::create_dir_all(&dir).expect("an output folder");
        for (name, image) in [("candidate", &candidate), ("reference", &ref_mean), ("z", &z_image)] {
            let path = dir.join(format!("{stem}_{name}.exr"));
            exr::prelude::write_rgb_file(&path, SIZE as usize, SIZE as usize, |x, y| {
                let v = image[y * SIZE as usize + x].as_vec3();
                (v.x, v.y, v.z)
            })
            .expect("writing a diagnostic EXR");
        }
        panic!(
            "{stem}: image means {ours_img} ± {img_se} vs {ref_img}, z mean {z_mean}, std {z_std}; \
             candidate, reference and z images in {}",
            dir.display()
        );
    }
}

#[test]
fn cornell_box_direct_matches_mitsuba() {
    compare("cbox_ref_direct", 1, 256);
}

#[test]
fn cornell_box_four_bounces_matches_mitsuba() {
    compare("cbox_ref_bounces4", 4, 256);
}
