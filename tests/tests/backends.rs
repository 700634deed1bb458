//! Checks written once and run on both integrators (`furnace_tests::backends::Backend`): what
//! one backend must do, the other must do the same way.

use furnace_render::{Integrator, RenderSettings};
use furnace_sampling::SamplerKind;
use furnace_scene::{Scene, builtin};
use furnace_tests::backends::Backend;
use glam::Vec3;

/// Per-channel mean of the film's pixel means.
fn image_mean(integrator: &mut dyn Integrator) -> [f64; 3] {
    let film = integrator.film().expect("the film");
    assert_eq!(film.rejected(), 0, "non-finite samples");
    let n = film.counts().len();
    let mut m = [0.0f64; 3];
    for i in 0..n {
        let p = film.mean(i);
        for c in 0..3 {
            m[c] += p[c] / n as f64;
        }
    }
    m
}

/// The Cornell box scaled by 1e10 and by 1e-8 renders what it renders at scale 1: ray offsets
/// scale with the scene (`offset_ray_origin_scaled`) and the geometric normal is formed without
/// overflow (`geometric_normal`), on both backends. 32×32 pixels, 4 Sobol samples, same seed at
/// every scale; the image means must agree within 1e-3 relative (the same-sample GPU/CPU
/// parity bar of `tests/integrator.rs`: most paths are the same paths, rounding moves a few).
/// The CPU's deeper per-pixel study over 1e-12 … 1e12 is `tests/stability.rs`.
#[test]
fn scaled_cornell_box_renders_the_same_image() {
    let settings =
        RenderSettings { width: 32, height: 32, sampler: SamplerKind::Sobol, seed: 5, ..Default::default() };
    for backend in Backend::ALL {
        let mut means = vec![];
        for s in [1.0f32, 1e10, 1e-8] {
            let mut scene = builtin::cornell_box().expect("the built-in Cornell box");
            scene.scale_lengths(s);
            let Some(mut integrator) = backend.open_default(&scene, settings) else { return };
            integrator.render_pass(0, 4).expect("a pass");
            let m = image_mean(integrator.as_mut());
            eprintln!("{backend}, s = {s:e}: image mean {m:?}");
            means.push(m);
        }
        for (k, s) in [(1, "1e10"), (2, "1e-8")] {
            for c in 0..3 {
                let ratio = means[k][c] / means[0][c];
                assert!(
                    (ratio - 1.0).abs() < 1e-3,
                    "{backend}, channel {c}: mean at {s} / mean at 1 = {ratio} ({means:?})"
                );
            }
        }
    }
}

/// The fixed-N samplers (Hammersley, CMJ) need N, render samples 0…N−1, refuse a pass that
/// reaches sample N with the sampler's error (naming N and the sample), and the refused pass
/// adds nothing to the film.
#[test]
fn fixed_n_samplers_need_n_and_stop_at_n() {
    let scene = builtin::furnace_sphere(builtin::lambert(Vec3::ONE), 8);
    for backend in Backend::ALL {
        for sampler in [SamplerKind::Hammersley, SamplerKind::Cmj] {
            let settings = RenderSettings { width: 8, height: 8, sampler, ..Default::default() };
            let camera = scene.default_camera();
            let err = backend.open(&scene, &camera, settings).err();
            if backend == Backend::Gpu && furnace_tests::gpu::test_context().is_none() {
                return;
            }
            assert!(err.is_some(), "{backend}, {sampler}: opened without N");
            let settings = RenderSettings { sample_count: Some(4), ..settings };
            let Some(mut integrator) = backend.open_default(&scene, settings) else { return };
            integrator.render_pass(0, 4).expect("samples 0…3 are within N");
            let err = integrator.render_pass(4, 1).expect_err("sample 4 of N = 4").to_string();
            assert!(err.contains("N = 4") && err.contains("sample 4"), "{backend}, {sampler}: {err}");
            let film = integrator.film().expect("the film");
            assert!(
                film.counts().iter().all(|&c| c == 4),
                "{backend}, {sampler}: the refused pass added samples"
            );
        }
    }
}

/// Every sampler renders the white furnace (a Lambert sphere of albedo 1 under a sky of
/// radiance 1): every pixel is 1.
#[test]
fn every_sampler_renders_the_white_furnace() {
    let scene: Scene = builtin::furnace_sphere(builtin::lambert(Vec3::ONE), 32);
    for backend in Backend::ALL {
        for sampler in SamplerKind::ALL {
            let settings =
                RenderSettings { width: 8, height: 8, sampler, sample_count: Some(16), ..Default::default() };
            let Some(mut integrator) = backend.open_default(&scene, settings) else { return };
            integrator.render_pass(0, 16).expect("render");
            let film = integrator.film().expect("the film");
            for i in 0..film.counts().len() {
                for (c, v) in film.mean(i).to_array().into_iter().enumerate() {
                    // Tolerance 1e-2: each pixel is exact up to paths lost at the flat
                    // triangles' edges (at most one of 16 here would be 6%, none is expected at
                    // this tessellation).
                    assert!((v - 1.0).abs() < 1e-2, "{backend}, {sampler}: pixel {i} channel {c} = {v}");
                }
            }
        }
    }
}

/// Vertex colours and a second UV set render as the file draws them, alike on both backends:
/// the Khronos VertexColorTest (COLOR_0 on a textured quad) and MultiUVTest (an emissive
/// texture on TEXCOORD_1), each under a white sky, 48×48 pixels × 8 Sobol samples, same seed.
/// The GPU's image mean must be the CPU's within 1e-3 relative (the same-sample parity bar of
/// `tests/integrator.rs`), and the attribute must matter: without the colours, or with the
/// emissive texture read at UV0, the CPU's image moves by an RMS of more than 5 % of its mean
/// (the moves measured are printed; a backend that ignored the attribute would then fail the
/// parity).
#[test]
fn vertex_colors_and_uv_sets_render_alike_on_both_backends() {
    type Strip = fn(&mut Scene);
    let cases: [(&str, Strip); 2] = [
        ("VertexColorTest/glTF/VertexColorTest.gltf", |s| s.geometry.colors.clear()),
        ("MultiUVTest/glTF/MultiUVTest.gltf", |s| {
            for m in &mut s.materials {
                if let Some(t) = &mut m.emissive_texture {
                    t.tex_coord = 0;
                }
            }
        }),
    ];
    let settings =
        RenderSettings { width: 48, height: 48, sampler: SamplerKind::Sobol, seed: 3, ..Default::default() };
    for (file, strip) in cases {
        let mut scene = Scene::load(furnace_tests::data::scene(file)).expect(file);
        scene.lights.push(furnace_scene::Light::Sky(furnace_scene::Sky { radiance: Vec3::ONE }));
        let mut stripped = scene.clone();
        strip(&mut stripped);
        let render = |backend: Backend, scene: &Scene| {
            let mut integrator = backend.open_default(scene, settings)?;
            integrator.render_pass(0, 8).expect("a pass");
            let film = integrator.film().expect("the film");
            Some((0..film.counts().len()).map(|i| film.mean(i)).collect::<Vec<_>>())
        };
        let mean = |image: &[glam::DVec3]| image.iter().sum::<glam::DVec3>() / image.len() as f64;
        let cpu = render(Backend::Cpu, &scene).expect("the CPU backend");
        let without = render(Backend::Cpu, &stripped).expect("the CPU backend");
        let rms = (cpu.iter().zip(&without).map(|(a, b)| (*a - *b).length_squared()).sum::<f64>()
            / cpu.len() as f64)
            .sqrt();
        let moved = rms / mean(&cpu).length();
        eprintln!("{file}: cpu mean {}, RMS move without the attribute {moved:.3} of it", mean(&cpu));
        assert!(moved > 0.05, "{file}: the attribute changes the image by only {moved}");
        let Some(gpu) = render(Backend::Gpu, &scene) else { return };
        let (g, c) = (mean(&gpu), mean(&cpu));
        eprintln!("{file}: gpu mean {g}");
        for k in 0..3 {
            assert!((g[k] / c[k] - 1.0).abs() < 1e-3, "{file}, channel {k}: gpu {g} vs cpu {c}");
        }
    }
}

/// KHR_materials_unlit on both backends: UnlitTest's orange and blue objects (CC BY 4.0, in
/// `tests/data`) under a grey sky and a bright sun show their base colour as is: every sample
/// sees the sky, the orange or the blue exactly, so every pixel must be a convex combination
/// of those three colours (solved per pixel; a lit or shaded surface falls outside), and most
/// of the objects' pixels must be the colour itself.
#[test]
fn unlit_surfaces_show_their_base_colour_on_both_backends() {
    use furnace_scene::{Light, Sky, Sun};
    let mut scene =
        Scene::load(furnace_tests::data::scene("UnlitTest/glTF/UnlitTest.gltf")).expect("UnlitTest");
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert!(scene.materials[0].unlit && scene.materials[1].unlit, "{:?}", scene.materials);
    let sky = Vec3::splat(0.5);
    scene.lights.push(Light::Sky(Sky { radiance: sky }));
    scene.lights.push(Light::Sun(Sun::delta(Vec3::new(-0.3, -1.0, -0.5).normalize(), Vec3::splat(5.0))));
    let (orange, blue) =
        (scene.materials[0].base_color_factor.truncate(), scene.materials[1].base_color_factor.truncate());
    let basis = glam::DMat3::from_cols(orange.as_dvec3(), blue.as_dvec3(), sky.as_dvec3());
    let inverse = basis.inverse();
    let settings =
        RenderSettings { width: 64, height: 48, sampler: SamplerKind::Sobol, seed: 2, ..Default::default() };
    for backend in Backend::ALL {
        let Some(mut integrator) = backend.open_default(&scene, settings) else { return };
        integrator.render_pass(0, 16).expect("a pass");
        let film = integrator.film().expect("the film");
        let (mut pure_orange, mut pure_blue) = (0, 0);
        for i in 0..film.counts().len() {
            let v = film.mean(i);
            let w = inverse * v;
            // Tolerance: f32 rounding of 16 samples' sum, and of the solve (1e-5).
            assert!(
                w.min_element() > -1e-5 && (w.element_sum() - 1.0).abs() < 1e-5,
                "{backend}: pixel {i} = {v} is not a mixture of the two colours and the sky ({w})"
            );
            pure_orange += usize::from(w.x > 1.0 - 1e-5);
            pure_blue += usize::from(w.y > 1.0 - 1e-5);
        }
        eprintln!("{backend}: {pure_orange} pixels exactly orange, {pure_blue} exactly blue");
        assert!(pure_orange > 150 && pure_blue > 150, "{backend}: {pure_orange}, {pure_blue}");
    }
}

/// Scenes with instances render alike on both backends: the CPU traces the shared meshes
/// through its two-level structure, the GPU renders the instances copied into world space.
/// SimpleInstancing's 125 cubes and NegativeScaleTest's mirroring instances under a white sky,
/// the nvpro Cornell box (two instances of one box) under its own light; 48×48 pixels × 8 Sobol
/// samples, same seed: the GPU's image mean within 1e-3 relative of the CPU's (the same-sample
/// parity bar of `tests/integrator.rs`).
#[test]
fn instanced_scenes_render_alike_on_both_backends() {
    let settings =
        RenderSettings { width: 48, height: 48, sampler: SamplerKind::Sobol, seed: 3, ..Default::default() };
    for file in [
        "SimpleInstancing/glTF/SimpleInstancing.gltf",
        "NegativeScaleTest/glTF/NegativeScaleTest.gltf",
        "CornellBox-nvpro/cornellBox.gltf",
    ] {
        let mut scene = Scene::load(furnace_tests::data::scene(file)).expect(file);
        assert!(!scene.instancing.is_empty(), "{file}: no instances");
        if !scene.has_own_light() {
            scene.lights.push(furnace_scene::Light::Sky(furnace_scene::Sky { radiance: Vec3::ONE }));
        }
        let render = |backend: Backend| {
            let mut integrator = backend.open_default(&scene, settings)?;
            integrator.render_pass(0, 8).expect("a pass");
            let film = integrator.film().expect("the film");
            Some(
                (0..film.counts().len()).map(|i| film.mean(i)).sum::<glam::DVec3>()
                    / film.counts().len() as f64,
            )
        };
        let c = render(Backend::Cpu).expect("the CPU backend");
        let Some(g) = render(Backend::Gpu) else { return };
        eprintln!("{file}: cpu mean {c}, gpu mean {g}");
        for k in 0..3 {
            assert!((g[k] / c[k] - 1.0).abs() < 1e-3, "{file}, channel {k}: gpu {g} vs cpu {c}");
        }
    }
}

/// A BVH whose triangle slots do not fit one binding takes two (`SPLIT_TRIANGLES`): forced here
/// by packing a flattened one-plant forest within a limit of 70 % of its triangle buffer (above
/// its vertex buffer, the next largest), the film is the
/// same to the bit as the one binding's (the same triangles, tested in the same order), and the
/// split composes the second binding only then.
#[test]
fn triangles_over_one_binding_render_the_same_from_two() {
    if furnace_tests::gpu::test_context().is_none() {
        eprintln!("no GPU adapter (not even a software one): skipped");
        return;
    }
    let scene = furnace_scene::builtin::forest(1, 0).flattened();
    let g = &scene.geometry;
    let bvh =
        furnace_accel::Bvh::from_indexed(&g.positions, &g.triangles, furnace_accel::BuildOptions::default());
    let slots = bvh.gpu_triangles().len() as u64 * size_of::<furnace_accel::GpuTriangle>() as u64;
    let settings = RenderSettings { width: 32, height: 24, bounces: 3, ..RenderSettings::default() };
    let camera = scene.default_camera();
    let render = |limit: u64| {
        let ctx = furnace_tests::gpu::test_context().expect("the adapter found above");
        let mut r = furnace_gpu::GpuRenderer::with_bvh_within(ctx, &scene, &bvh, &camera, settings, limit)
            .unwrap_or_else(|e| panic!("limit {limit}: {e}"));
        r.render_pass(0, 2).unwrap();
        (r.film().unwrap(), r.bvh_bytes())
    };
    let (one, one_bytes) = render(u64::MAX);
    let (two, two_bytes) = render(slots * 7 / 10);
    assert!(one.to_rgb_f32().iter().any(|&v| v > 0.0), "the image is not black");
    let bits = |f: &furnace_render::Film| f.to_rgb_f32().iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&one), bits(&two), "the split film differs");
    assert_eq!(one_bytes, two_bytes, "the same bytes in two bindings");
}
