//! glTF `alphaMode: MASK` with `alphaCutoff`: camera rays and sun shadow rays pass through the
//! cut-out parts of a surface and stop at the rest.
//!
//! The scene (written in memory, `furnace_tests::gltf`): a 2 m × 2 m quad at height 1 m whose base
//! colour texture is an 8×8 checkerboard of alpha 0.8 (solid) and 0.6 (cut out), with
//! `alphaCutoff` 0.7 — so a renderer that ignores the cutoff (glTF's default 0.5) or the mask
//! sees it solid, and one that inverts the test sees the other half. Below it a 6 m × 6 m
//! floor at height 0. Both quads face up; the masked one is single-sided and emits red, the
//! floor is a white Lambert surface (albedo 0.5) emitting dim blue. The sun comes from 30°
//! off the zenith; the sky is black.
//!
//! The bilinear 0.7-contour of a checkerboard of 0.6 and 0.8 texels is exactly the texel
//! edges (`f − 0.7 = −0.1·(2s − 1)(2t − 1)` between four texel centres), so the mask is an
//! exact checkerboard of 0.25 m cells and each pixel's expected value follows analytically:
//! pixels wholly inside one cell (or outside the quad) are compared with it exactly; pixels
//! across a cell edge must lie between the two values; and the image mean is compared with
//! the exact fraction of cut-out area.

use furnace_tests::gltf;

use furnace_cpu::CpuRenderer;
use furnace_render::RenderSettings;
use furnace_sampling::SamplerKind;
use furnace_scene::Scene;
use glam::{DVec3, Vec2, Vec3};
use gltf::{MaterialDesc, Quad, SceneDesc, TopCamera};
use std::f32::consts::PI;

const CELLS: u32 = 8;
const CUTOFF: f32 = 0.7;
const SOLID_ALPHA: u8 = 204; // 0.8
const CUT_ALPHA: u8 = 153; // 0.6
pub(super) const QUAD_HEIGHT: f32 = 1.0;
pub(super) const ALBEDO: f32 = 0.5;
pub(super) const FLOOR_EMISSION: Vec3 = Vec3::new(0.0, 0.0, 0.25);
pub(super) const QUAD_EMISSION: Vec3 = Vec3::new(1.0, 0.0, 0.0);
pub(super) const SUN_IRRADIANCE: Vec3 = Vec3::new(2.0, 2.0, 2.0);
/// 60 pixels over 2.4 m: cell edges (every 0.25 m) do not fall on pixel edges, so some
/// pixels straddle them.
pub(super) const SIZE: u32 = 60;
pub(super) const HALF_VIEW: f32 = 1.2;

pub(super) fn sun_direction() -> Vec3 {
    // Travelling down, 30° from the vertical, towards +x and a little +z.
    let theta = 30f32.to_radians();
    Vec3::new(theta.sin() * 0.8, -theta.cos(), theta.sin() * 0.6).normalize()
}

fn masked_quad() -> Quad {
    let texture = gltf::png(CELLS, CELLS, |i, j| {
        let a = if (i + j) % 2 == 0 { SOLID_ALPHA } else { CUT_ALPHA };
        [255, 255, 255, a]
    });
    Quad {
        x: [-1.0, 1.0],
        z: [-1.0, 1.0],
        y: QUAD_HEIGHT,
        tangent: None,
        material: MaterialDesc {
            albedo: Vec3::splat(0.5),
            emissive: QUAD_EMISSION,
            base_color_png: Some(texture),
            mask_cutoff: Some(CUTOFF),
            double_sided: false,
            ..MaterialDesc::default()
        },
    }
}

/// Whether the masked quad is *solid* at `(x, z)`: inside it and on a cell of alpha 0.8;
/// `None` within `margin` of a cell edge or of the quad's border (undecidable in f32).
fn solid_at(quad: &Quad, x: f32, z: f32, margin: f32) -> Option<bool> {
    let uv = quad.uv(x, z) * CELLS as f32;
    let near_edge = |t: f32| (t - t.round()).abs() < margin * CELLS as f32 / 2.0;
    if near_edge(uv.x) || near_edge(uv.y) {
        return None;
    }
    if !(0.0..CELLS as f32).contains(&uv.x) || !(0.0..CELLS as f32).contains(&uv.y) {
        return Some(false);
    }
    // Texel (i, j) covers u ∈ [i, i+1)/8, v ∈ [j, j+1)/8; texel row j is image row j.
    let (i, j) = (uv.x.floor() as u32, uv.y.floor() as u32);
    Some((i + j) % 2 == 0)
}

fn scene() -> (Scene, Quad) {
    let quad = masked_quad();
    let floor = Quad {
        x: [-3.0, 3.0],
        z: [-3.0, 3.0],
        y: 0.0,
        tangent: None,
        material: MaterialDesc {
            albedo: Vec3::splat(ALBEDO),
            emissive: FLOOR_EMISSION,
            ..MaterialDesc::default()
        },
    };
    let desc = SceneDesc {
        quads: vec![quad.clone(), floor],
        cameras: vec![
            // Above the masked quad: sees it and, through its cut-outs, the floor.
            TopCamera { position: Vec3::new(0.0, 3.0, 0.0), half_size: HALF_VIEW },
            // Between the quad and the floor: sees the floor and the quad's shadow on it.
            TopCamera { position: Vec3::new(0.0, 0.5, 0.0), half_size: HALF_VIEW },
        ],
        sun: Some((sun_direction(), SUN_IRRADIANCE)),
        sky: Vec3::ZERO,
    };
    (desc.load("alpha_mask.gltf"), quad)
}

/// Renders `spp` samples per pixel (random sampler, fixed seed) with camera `camera`.
fn render(camera: usize, bounces: u32, spp: u32) -> (Vec<DVec3>, Scene, Quad) {
    let (mut scene, quad) = scene();
    scene.cameras.swap(0, camera);
    let settings = RenderSettings {
        width: SIZE,
        height: SIZE,
        bounces,
        sampler: SamplerKind::Random,
        seed: 5,
        ..Default::default()
    };
    let renderer = CpuRenderer::with_default_camera(scene.clone(), settings).expect("a progressive sampler");
    let mut film = renderer.new_film();
    renderer.render_into(&mut film, 0, spp).expect("render");
    assert_eq!(film.rejected(), 0);
    let pixels = (0..SIZE * SIZE).map(|i| film.pixel(i % SIZE, i / SIZE)).collect();
    (pixels, scene, quad)
}

/// Where the camera ray through film point `p` meets the plane at height `y` (the cameras
/// look straight down, so this is the ray's origin moved down).
fn ground_point(scene: &Scene, p: Vec2, y: f32) -> Vec3 {
    let ray = scene.default_camera().generate_ray(p, SIZE, SIZE);
    let t = (ray.origin.y - y) / -ray.direction.y;
    ray.origin + t * ray.direction
}

/// Checks every pixel against `expected(corner points)`: `Some(value)` when the pixel's four
/// corners agree, else `None` (then the pixel must lie between `low` and `high`). Returns the
/// mismatches as a table, and the counts of exact and mixed pixels.
fn check_pixels(
    image: &[DVec3],
    classify: impl Fn(Vec2) -> Option<bool>,
    values: (DVec3, DVec3),
) -> (Vec<String>, usize, usize) {
    let mut failures = Vec::new();
    let (mut exact, mut mixed) = (0, 0);
    let (when_false, when_true) = values;
    for y in 0..SIZE {
        for x in 0..SIZE {
            let v = image[(y * SIZE + x) as usize];
            let corners: Vec<Option<bool>> = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                .iter()
                .map(|&(dx, dy)| classify(Vec2::new(x as f32 + dx, y as f32 + dy)))
                .collect();
            let all = |b: bool| corners.iter().all(|&c| c == Some(b));
            let expected = if all(true) {
                Some(when_true)
            } else if all(false) {
                Some(when_false)
            } else {
                None
            };
            match expected {
                Some(e) => {
                    exact += 1;
                    // Tolerance: f32 rounding of one BRDF evaluation and the film's mean.
                    if (v - e).abs().max_element() > 1e-5 * e.max_element().max(1.0) {
                        failures.push(format!("| ({x}, {y}) | {v:.5} | {e:.5} |"));
                    }
                }
                None => {
                    mixed += 1;
                    // A mixture of the two values; the margin is the same f32 rounding as above.
                    let (lo, hi) = (when_false.min(when_true), when_false.max(when_true));
                    if v.cmplt(lo - 1e-5).any() || v.cmpgt(hi + 1e-5).any() {
                        failures.push(format!("| ({x}, {y}) | {v:.5} | between {lo:.4} and {hi:.4} |"));
                    }
                }
            }
        }
    }
    (failures, exact, mixed)
}

fn write_failure(name: &str, image: &[DVec3], failures: &[String]) -> String {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/test-output/furnace-cpu");
    std::fs::create_dir_all(&dir).expect("an output folder");
    let exr = dir.join(format!("{name}.exr"));
    exr::prelude::write_rgb_file(&exr, SIZE as usize, SIZE as usize, |x, y| {
        let v = image[y * SIZE as usize + x].as_vec3();
        (v.x, v.y, v.z)
    })
    .expect("writing the image");
    let table = dir.join(format!("{name}.md"));
    let text = format!("| pixel | got | expected |\n|---|---|---|\n{}\n", failures.join("\n"));
    std::fs::write(&table, text).expect("writing the table");
    format!("{} pixels wrong; image {}, table {}", failures.len(), exr.display(), table.display())
}

/// The camera above the quad, 0 bounces (emission only): red where the quad is solid, the
/// floor's blue through the cut-outs and around the quad.
#[test]
fn camera_rays_pass_through_cutouts() {
    let (image, scene, quad) = render(0, 0, 16);
    let classify = |p: Vec2| {
        let q = ground_point(&scene, p, QUAD_HEIGHT);
        solid_at(&quad, q.x, q.z, 1e-4)
    };
    let values = (FLOOR_EMISSION.as_dvec3(), QUAD_EMISSION.as_dvec3());
    let (failures, exact, mixed) = check_pixels(&image, classify, values);
    // The red fraction of the image: the quad covers (2/2.4)² of it, half of that solid.
    let red = image.iter().map(|v| v.x).sum::<f64>() / image.len() as f64;
    let expected_red = 0.5 * (2.0 / (2.0 * f64::from(HALF_VIEW))).powi(2);
    println!(
        "camera through cut-outs: {exact} pixels exact, {mixed} mixed; red fraction {red:.4} (expected {expected_red:.4})"
    );
    if !failures.is_empty() {
        panic!("{}", write_failure("alpha_mask_camera", &image, &failures));
    }
    assert!(exact > 2000 && mixed > 200, "the test covers both kinds of pixel: {exact}, {mixed}");
    // Tolerance 0.01: only the ~900 mixed pixels are noisy (16 Bernoulli samples each, σ ≤ 1/8),
    // so the fraction's standard error is ≤ √900/8/3600 ≈ 1e-3; 0.01 is 10σ. A mask ignored or
    // inverted moves it by ≥ 0.35.
    assert!((red - expected_red).abs() < 0.01, "red fraction {red} vs {expected_red}");
}

/// The camera between the quad and the floor, 1 bounce: the floor is lit by the sun where the
/// shadow ray from it passes a cut-out (or misses the quad) and dark where it meets a solid
/// cell.
#[test]
fn shadow_rays_pass_through_cutouts() {
    let (image, scene, quad) = render(1, 1, 16);
    let l = -sun_direction();
    let classify = |p: Vec2| {
        let f = ground_point(&scene, p, 0.0);
        let q = f + l * ((QUAD_HEIGHT - f.y) / l.y);
        // Lit = the quad is *not* solid where the shadow ray crosses it.
        solid_at(&quad, q.x, q.z, 1e-4).map(|solid| !solid)
    };
    let lit = (ALBEDO / PI * SUN_IRRADIANCE * l.y).as_dvec3() + FLOOR_EMISSION.as_dvec3();
    let dark = FLOOR_EMISSION.as_dvec3();
    let (failures, exact, mixed) = check_pixels(&image, classify, (dark, lit));
    // The lit fraction from the image mean against the same from the analytic classification
    // on a fine grid of the film (every 1/16 pixel), which is exact up to its 1/16 resolution.
    let lit_fraction =
        image.iter().map(|v| (v.x - dark.x) / (lit.x - dark.x)).sum::<f64>() / image.len() as f64;
    let grid = 16 * SIZE;
    let expected = (0..grid * grid)
        .filter(|i| {
            let p = Vec2::new((i % grid) as f32 + 0.5, (i / grid) as f32 + 0.5) / 16.0;
            classify(p).unwrap_or(false)
        })
        .count() as f64
        / f64::from(grid * grid);
    println!(
        "shadows through cut-outs: {exact} pixels exact, {mixed} mixed; lit fraction {lit_fraction:.4} (expected {expected:.4})"
    );
    if !failures.is_empty() {
        panic!("{}", write_failure("alpha_mask_shadow", &image, &failures));
    }
    assert!(exact > 2000 && mixed > 200, "the test covers both kinds of pixel: {exact}, {mixed}");
    // Tolerance 0.01, as for the camera test: ≥ 10 standard errors of the mixed pixels' noise,
    // plus the grid's resolution error (edge pixels undecided on it count as dark: ≤ 3e-3).
    // Ignoring the mask in shadow rays would make the quad's whole shadow dark (≥ 0.25 less).
    assert!((lit_fraction - expected).abs() < 0.01, "lit fraction {lit_fraction} vs {expected}");
}
