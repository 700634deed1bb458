//! Environment maps where they could fail, measured (the figures are in `docs/stability.md`):
//!
//! * `one_texel_environment_is_a_white_furnace` — a 1 × 1 map: a Lambert sphere of albedo 1
//!   inside a constant environment looks like the environment, whichever strategy gathers it.
//! * `a_single_bright_texel_makes_no_fireflies` — a map black but for one texel of 10⁶: every
//!   sample of direct light on a white sphere stays under the bound MIS with importance sampling
//!   predicts (BSDF sampling alone exceeds it ten-thousandfold).
//! * `a_huge_map_loads_samples_and_renders` — an 8192 × 4096 map: time and memory to build its
//!   distribution and render a first pass, on the CPU and on the GPU adapter if there is one.

use furnace_cpu::CpuRenderer;
use furnace_render::{EnvSampling, LightSampling, RenderSettings};
use furnace_sampling::SamplerKind;
use furnace_scene::{Environment, EnvironmentMap, Scene, builtin};
use glam::Vec3;
use std::sync::Arc;
use std::time::Instant;

/// The white sphere of `builtin::furnace_sphere` lit only by `env`.
fn sphere_in(env: Environment) -> Scene {
    let mut scene = builtin::furnace_sphere(builtin::lambert(Vec3::ONE), 64);
    scene.set_sky(Vec3::ZERO);
    scene.set_environment(Some(env));
    scene
}

fn settings(bounces: u32, light_sampling: LightSampling, env_sampling: EnvSampling) -> RenderSettings {
    RenderSettings {
        width: 24,
        height: 24,
        bounces,
        sampler: SamplerKind::Sobol,
        seed: 5,
        light_sampling,
        env_sampling,
        ..Default::default()
    }
}

/// A 1 × 1 map of 0.5 at intensity 2: radiance 1 from every direction. A convex Lambert sphere of
/// albedo 1 reflects exactly 1 at one bounce (every reflected ray escapes), so every pixel's
/// expectation is 1, sphere or background. Each configuration's image mean must be 1 within 0.3 %
/// (256 spp of 576 pixels: the per-pixel spread is ≈ 0.3 (MIS) to 0.6 (one strategy) per sample,
/// so the image mean's standard error is ≤ 0.6/√(147 456) = 0.16 %, and Sobol's stratification
/// brings it lower; 0.3 % is ≥ 2 of those); no pixel may leave [0.75, 1.25] (a pixel's standard
/// error is ≤ 0.05 with light samples alone, whose uniform-in-(u, v) directions of a one-row map
/// crowd the poles: 5 of them).
#[test]
fn one_texel_environment_is_a_white_furnace() {
    let env = Environment {
        intensity: 2.0,
        ..Environment::new(Arc::new(EnvironmentMap::constant(Vec3::splat(0.5))))
    };
    let scene = sphere_in(env);
    for (light, env_sampling) in [
        (LightSampling::Mis, EnvSampling::Importance),
        (LightSampling::Mis, EnvSampling::Compensated),
        (LightSampling::Mis, EnvSampling::Off),
        (LightSampling::Nee, EnvSampling::Importance),
    ] {
        let cpu = CpuRenderer::with_default_camera(scene.clone(), settings(1, light, env_sampling)).unwrap();
        let mut film = cpu.new_film();
        cpu.render_into(&mut film, 0, 256).unwrap();
        let n = film.counts().len();
        let means: Vec<f64> = (0..n).map(|i| film.mean(i).element_sum() / 3.0).collect();
        let mean = means.iter().sum::<f64>() / n as f64;
        let (lo, hi) = means.iter().fold((f64::MAX, f64::MIN), |(a, b), &m| (a.min(m), b.max(m)));
        eprintln!("light {light}, env {env_sampling}: image mean {mean:.5}, pixels {lo:.4} … {hi:.4}");
        assert_eq!(film.rejected(), 0);
        assert!((mean - 1.0).abs() < 3e-3, "{light}/{env_sampling}: image mean {mean}");
        assert!(lo > 0.75 && hi < 1.25, "{light}/{env_sampling}: a pixel at {lo} or {hi}");
    }
}

/// 256 × 128 texels, black but texel (80, 40) at 10⁶: a sun of 1.4° × 1.4° whose light a white
/// sphere receives (direct light only, the environment hidden from the camera).
///
/// The bound: a light sample adds `f·L·cos/p_l·w ≤ (ρ/π)·M` with `M = max L/p_l` over the map
/// (the largest radiance in a cell × `2π² sin θ` at its row's widest / the cell's density, from
/// the sampler's own tables); a BSDF sample adds `ρ·L·w_b` with
/// `w_b = p_b²/(p_b² + p_l²) ≤ p_b/(2 p_l)` and `p_b ≤ 1/π`, so at most `(ρ/π)·M/2`. Every
/// sample of a path is therefore below `1.5·(ρ/π)·M`. With BSDF sampling alone a sample that
/// finds the texel adds up to `ρ·10⁶`: fireflies, far above what importance sampling ever adds.
#[test]
fn a_single_bright_texel_makes_no_fireflies() {
    let (w, h) = (256u32, 128u32);
    let mut texels = vec![Vec3::ZERO; (w * h) as usize];
    texels[(40 * w + 80) as usize] = Vec3::splat(1e6);
    let map = Arc::new(EnvironmentMap::new(w, h, texels, "one texel").unwrap().0);
    let env = Environment { visible: false, ..Environment::new(map.clone()) };
    let sampler = env.sampler(false).unwrap();
    let d = sampler.distribution();
    let mut m = 0.0f64;
    for j in 0..h {
        let (t0, t1) = (
            std::f64::consts::PI * f64::from(j) / f64::from(h),
            std::f64::consts::PI * f64::from(j + 1) / f64::from(h),
        );
        let sin_max = if t0 <= std::f64::consts::FRAC_PI_2 && t1 >= std::f64::consts::FRAC_PI_2 {
            1.0
        } else {
            t0.sin().max(t1.sin())
        };
        for i in 0..w {
            // The bilinear lookup in a cell never exceeds its 3 × 3 neighbourhood of texels.
            let l_max = (-1..=1)
                .flat_map(|a| (-1..=1).map(move |b| (a, b)))
                .map(|(a, b)| {
                    let (ii, jj) =
                        ((i as i64 + a).rem_euclid(w as i64), (j as i64 + b).clamp(0, h as i64 - 1));
                    map.texels()[(jj * w as i64 + ii) as usize].max_element()
                })
                .fold(0.0f32, f32::max);
            let p = d.cell_pdf(i, j);
            if l_max > 0.0 {
                assert!(p > 0.0, "cell ({i}, {j}) sends light but cannot be sampled");
                let two_pi2 = 2.0 * std::f64::consts::PI * std::f64::consts::PI;
                m = m.max(f64::from(l_max) * two_pi2 * sin_max / f64::from(p));
            }
        }
    }
    let bound = 1.5 * m / std::f64::consts::PI;
    let scene = sphere_in(env);
    let mut worst = Vec::new();
    for env_sampling in [EnvSampling::Importance, EnvSampling::Off] {
        let cpu =
            CpuRenderer::with_default_camera(scene.clone(), settings(1, LightSampling::Mis, env_sampling))
                .unwrap();
        let (mut max, mut sum, mut n) = (0.0f32, 0.0f64, 0u64);
        for y in 0..24 {
            for x in 0..24 {
                for index in 0..64 {
                    let v = cpu.sample(x, y, index);
                    assert!(v.is_finite(), "{env_sampling}: sample {v} at ({x}, {y})");
                    max = max.max(v.max_element());
                    sum += f64::from(v.x);
                    n += 1;
                }
            }
        }
        let mean = sum / n as f64;
        eprintln!(
            "one texel of 1e6, env sampling {env_sampling}: largest sample {max:.4e} = {:.3} × the MIS bound {bound:.4e}; \
             image mean {mean:.4e}",
            f64::from(max) / bound
        );
        worst.push((env_sampling, f64::from(max), mean));
    }
    let (_, importance, _) = worst[0];
    let (_, off, _) = worst[1];
    assert!(importance <= bound, "a sample of {importance:e} exceeds the bound {bound:e}");
    assert!(off > 10.0 * importance, "BSDF sampling alone should make fireflies: largest {off:e}");
}

/// A smooth sky with a small sun, `w × h` texels, computed per texel (no file).
fn sky(w: u32, h: u32) -> EnvironmentMap {
    let sun = Vec3::new(0.3, 0.6, -0.74).normalize();
    let texels = (0..h)
        .flat_map(|j| (0..w).map(move |i| (i, j)))
        .map(|(i, j)| {
            let uv = glam::Vec2::new((i as f32 + 0.5) / w as f32, (j as f32 + 0.5) / h as f32);
            let d = furnace_scene::uv_to_direction(uv);
            let base = if d.y > 0.0 { Vec3::new(0.4, 0.6, 1.0) * (0.5 + d.y) } else { Vec3::splat(0.2) };
            base + if d.dot(sun) > 0.99996 { Vec3::splat(5e4) } else { Vec3::ZERO }
        })
        .collect();
    EnvironmentMap::new(w, h, texels, format!("sky {w}x{h}")).unwrap().0
}

/// 8192 × 4096 (2²⁵ texels, 384 MiB of f32 RGB): the map, its distribution (two f32 CDFs, 128
/// MiB, built through three f64 arrays of the cells, 768 MiB, freed after), the CPU renderer and
/// one pass at 32², then the GPU renderer where there is an adapter (its buffers: texels, 384
/// MiB, and CDFs, 128 MiB; an adapter that cannot bind that many bytes must say so in one error
/// naming the buffer, not fail later: lavapipe binds 128 MiB). Prints each step's time; asserts only that all of it works.
#[test]
fn a_huge_map_loads_samples_and_renders() {
    let t = Instant::now();
    let map = Arc::new(sky(8192, 4096));
    let build = t.elapsed().as_secs_f64();
    let env = Environment::new(map.clone());
    let t = Instant::now();
    let sampler = env.sampler(false).expect("not black");
    let sample_build = t.elapsed().as_secs_f64();
    let cdf_bytes =
        4 * (sampler.distribution().conditional_cdf().len() + sampler.distribution().marginal_cdf().len());
    let scene = sphere_in(env);
    let s =
        RenderSettings { width: 32, height: 32, ..settings(2, LightSampling::Mis, EnvSampling::Importance) };
    let t = Instant::now();
    let cpu = CpuRenderer::with_default_camera(scene.clone(), s).unwrap();
    let mut film = cpu.new_film();
    cpu.render_into(&mut film, 0, 1).unwrap();
    let first = t.elapsed().as_secs_f64();
    eprintln!(
        "8192×4096: map {:.0} MiB built in {build:.2} s; distribution {:.0} MiB in {sample_build:.2} s; CPU renderer \
         and a first 32² pass {first:.2} s",
        map.bytes() as f64 / 1048576.0,
        cdf_bytes as f64 / 1048576.0
    );
    assert_eq!(film.rejected(), 0);
    assert!(film.mean(16 * 32 + 16).element_sum() > 0.0, "the sphere is lit");
    let Some(ctx) = furnace_tests::gpu::test_context() else { return };
    let t = Instant::now();
    let camera = scene.default_camera();
    match furnace_gpu::GpuRenderer::new(ctx, &scene, &camera, s) {
        Ok(mut gpu) => {
            gpu.render_pass(0, 1).unwrap();
            let g = gpu.film().unwrap();
            eprintln!("GPU: renderer and a first pass {:.2} s", t.elapsed().as_secs_f64());
            assert_eq!(g.rejected(), 0);
        }
        Err(e) => {
            let msg = e.to_string();
            eprintln!("GPU: {msg}");
            assert!(msg.contains("environment map"), "an adapter too small must say which buffer: {msg}");
        }
    }
}
