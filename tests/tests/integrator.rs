//! The GPU integrator against the CPU reference (furnace-cpu) on the Cornell box.
//!
//! 1. Same sampler, same seed: both estimate the image from the *same* sample points, so the
//!    images must agree far more closely than their noise — per-channel means within 1e-3
//!    relative. Paths may still part where a float differs by an ulp at a branch (FMA
//!    contraction on the GPU), so per-pixel agreement is reported, not required.
//! 2. Independent estimates (random sampler, different seeds), one sample per pass so each
//!    pixel's standard error comes from its own samples: per-channel means within 0.5% and
//!    per-pixel z = (gpu − cpu)/√(se_gpu² + se_cpu²) with |mean| < 0.1 and std ≤ 1.15 (the
//!    issue's bounds; with N = 128 samples the variance estimate inflates z's std by ≈ 1.01).

use furnace_cpu::CpuRenderer;
use furnace_gpu::integrator::{
    FrameParams, GROUP_SIZE, GpuPointLight, HARDWARE_GROUP_SIZE, SceneFeatures, shader_source, tile, tile_of,
    with_group_size,
};
use furnace_gpu::{GpuRenderer, film::FilmPrecision};
use furnace_render::RenderSettings;
use furnace_sampling::SamplerKind;
use furnace_scene::builtin;
use furnace_tests::gpu::test_context;

const SIZE: u32 = 64;

fn settings(sampler: SamplerKind, seed: u32) -> RenderSettings {
    RenderSettings { width: SIZE, height: SIZE, sampler, seed, ..RenderSettings::default() }
}

/// Per-pixel sample means and variances of the mean, from `passes` passes of one sample.
fn per_sample_stats(
    mut pass: impl FnMut(u32) -> Vec<[f64; 3]>,
    passes: u32,
) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
    let n = (SIZE * SIZE) as usize;
    let mut sum = vec![[0.0f64; 3]; n];
    let mut sq = vec![[0.0f64; 3]; n];
    for k in 0..passes {
        for (i, v) in pass(k).iter().enumerate() {
            for c in 0..3 {
                sum[i][c] += v[c];
                sq[i][c] += v[c] * v[c];
            }
        }
    }
    let p = f64::from(passes);
    let mean: Vec<[f64; 3]> = sum.iter().map(|s| s.map(|x| x / p)).collect();
    let var = sq
        .iter()
        .zip(&mean)
        .map(|(q, m)| std::array::from_fn(|c| ((q[c] / p - m[c] * m[c]) * p / (p - 1.0)).max(0.0) / p))
        .collect();
    (mean, var)
}

fn channel_means(img: &[[f64; 3]]) -> [f64; 3] {
    let mut m = [0.0; 3];
    for v in img {
        for c in 0..3 {
            m[c] += v[c] / img.len() as f64;
        }
    }
    m
}

#[test]
fn workgroup_size_matches_wgsl() {
    let src = shader_source(FilmPrecision::F64, SceneFeatures::default());
    let module = naga::front::wgsl::parse_str(&src).unwrap_or_else(|e| panic!("{}", e.emit_to_string(&src)));
    let main = module.entry_points.iter().find(|e| e.name == "main").expect("entry point main");
    assert_eq!(main.workgroup_size, [GROUP_SIZE, 1, 1]);
    for g in (0..=GROUP_SIZE.ilog2()).map(|k| 1 << k) {
        let (w, h) = tile(g);
        assert!(w * h * g == GROUP_SIZE && w >= h && w <= 2 * h, "group_samples {g}: tile {w}×{h}");
    }
    // The hardware size: the one constant rewritten, the workgroup arrays sized by it.
    let wide = with_group_size(&src, HARDWARE_GROUP_SIZE);
    let module =
        naga::front::wgsl::parse_str(&wide).unwrap_or_else(|e| panic!("{}", e.emit_to_string(&wide)));
    let main = module.entry_points.iter().find(|e| e.name == "main").expect("entry point main");
    assert_eq!(main.workgroup_size, [HARDWARE_GROUP_SIZE, 1, 1]);
    assert!(
        wide.contains("array<vec4<f32>, GROUP_SIZE>")
            && wide.contains(&format!("const GROUP_SIZE: u32 = {HARDWARE_GROUP_SIZE}u;"))
            && !wide.contains(&format!("const GROUP_SIZE: u32 = {GROUP_SIZE}u;"))
    );
    for g in (0..=HARDWARE_GROUP_SIZE.ilog2()).map(|k| 1 << k) {
        let (w, h) = tile_of(HARDWARE_GROUP_SIZE, g);
        assert!(w * h * g == HARDWARE_GROUP_SIZE && w >= h && w <= 2 * h, "group_samples {g}: tile {w}×{h}");
    }
}

/// Passes cut into several dispatches of whole tiles (300 × 260 = 78 000 pixels: two or more
/// dispatches of rows on a software adapter, whose dispatches hold 2¹⁶ samples), and images
/// smaller than a tile (they panicked below 8 rows), add each sample to each pixel exactly once,
/// for every grouping.
#[test]
fn dispatches_cover_every_pixel_once() {
    let scene = builtin::cornell_box().unwrap();
    let camera = scene.default_camera();
    for (width, height) in [(300, 260), (1, 1), (8, 4), (3, 1), (1, 5)] {
        let Some(ctx) = test_context() else { return };
        let s = RenderSettings { width, height, bounces: 0, ..RenderSettings::default() };
        let mut r = GpuRenderer::new(ctx, &scene, &camera, s).unwrap();
        let mut first = 0;
        // Every grouping on the small images; 1, 2, 16 on the large one (lavapipe time).
        let groups = if width * height > 64 { &[1, 2, 16][..] } else { &[1, 2, 16, GROUP_SIZE][..] };
        for &g in groups {
            r.set_group_samples(Some(g));
            r.render_pass(first, g).unwrap();
            first += g;
            let film = r.film().unwrap();
            let wrong: Vec<_> = film
                .counts()
                .iter()
                .enumerate()
                .filter(|&(_, &c)| c != u64::from(first))
                .take(5)
                .map(|(i, c)| (i as u32 % width, i as u32 / width, *c))
                .collect();
            assert!(
                wrong.is_empty(),
                "{width}×{height}, group_samples {g}: (x, y, count) not {first}: {wrong:?}"
            );
        }
    }
}

/// A scene without emitters, a sun or a sun disc gets a shader without their code, variables or
/// binding (not code behind a `false` constant, which still costs the GPU time: BENCHMARKS.md).
#[test]
fn absent_light_features_compose_no_code() {
    let bare = shader_source(FilmPrecision::F64, SceneFeatures::default());
    for absent in [
        "sample_emitter",
        "sun_disc",
        "ray_pdf",
        "emitters",
        "power_heuristic",
        "light_bvh",
        "environment",
        "fn env_",
        "ENV_VISIBLE",
        "film_aov",
        "aov_albedo",
        "fn converge",
        "film_converged",
        "fn dielectric_",
        "scene_transmission",
        "scene_layers",
        "fn sheen_",
        "fn layers_",
        "scene_iridescence",
        "scene_specular",
        "brdf_film_",
        ".film_",
        "scene_diffuse_transmission",
        "fn dt_",
        "scene_anisotropy",
        "fn hit_anisotropy",
        "frame_with_tangent",
        ".alpha_y",
        "GgxAlpha = vec2",
        "SPECTRUM_",
        "fn spectrum_",
        "wavelength",
        "fn hit_material_estimate",
        "shadow_query",
        "fn absorption",
        "to_sun",
        "#if",
    ] {
        assert!(!bare.contains(absent), "{absent} in the shader of a scene without light samples");
    }
    // Glass without dispersion: no wavelength, no spectrum tables; with it, both.
    let glass = shader_source(FilmPrecision::F64, SceneFeatures { transmission: true, ..Default::default() });
    assert!(!glass.contains("wavelength") && !glass.contains("SPECTRUM_"));
    let prism = shader_source(
        FilmPrecision::F64,
        SceneFeatures { transmission: true, dispersion: true, ..Default::default() },
    );
    assert!(prism.contains("path.wavelength = s.lambda;") && prism.contains("const SPECTRUM_WEIGHT"));
    // Without instances: one traversal, no TLAS, no instance bindings or placing; with them all.
    for absent in
        ["tlas_nodes", "var<storage, read> instances", "trv_instance", "scene_place_point", "struct Instance"]
    {
        assert!(!glass.contains(absent), "{absent} in the shader of a scene without instances");
    }
    let forest = shader_source(FilmPrecision::F64, SceneFeatures { instances: true, ..Default::default() });
    for present in [
        "var<storage, read> tlas_nodes",
        "fn trv_traverse_instances",
        "fn scene_place_point",
        "struct Instance",
    ] {
        assert!(forest.contains(present), "{present} missing from the shader of a scene with instances");
    }
    // A delta sun: its shadow ray, and nothing of the disc's samples.
    let sun = shader_source(FilmPrecision::F64, SceneFeatures { delta_sun: true, ..Default::default() });
    assert!(sun.contains("let to_sun") && !sun.contains("sample_sun_disc") && !sun.contains("ray_pdf"));
    let all = shader_source(
        FilmPrecision::F64,
        SceneFeatures { point_lights: true, emitters: true, sun_disc: true, ..Default::default() },
    );
    for present in ["fn sample_emitter", "fn sample_sun_disc", "ray_pdf: f32", "var<storage, read> emitters"]
    {
        assert!(all.contains(present), "{present} missing from the shader of a scene with every light");
    }
    // Chosen by power: no light-BVH code; by the BVH: no alias-table code.
    assert!(!all.contains("light_bvh") && all.contains("fn emitter_select"));
    let bvh = shader_source(
        FilmPrecision::F64,
        SceneFeatures {
            point_lights: true,
            emitters: true,
            sun_disc: true,
            light_bvh: true,
            ..Default::default()
        },
    );
    assert!(bvh.contains("fn light_bvh_sample") && !bvh.contains("fn emitter_select"));
    // Triangles sampled by area: the spherical triangle is never formed; by solid angle it is.
    let solid_angle = |s: &str| s.contains("let omega = spherical_triangle_solid_angle(");
    assert!(!solid_angle(&all) && !solid_angle(&bvh));
    let by_solid_angle = shader_source(
        FilmPrecision::F64,
        SceneFeatures { emitters: true, solid_angle_triangles: true, ..Default::default() },
    );
    assert!(solid_angle(&by_solid_angle));
    // Nothing is counted but in the counting kernel.
    for shader in [&bare, &sun, &all, &bvh, &by_solid_angle] {
        assert!(!shader.contains("rays_traced") && !shader.contains("trace_stats.nodes +="));
    }
    // Transmission: the dielectric and its records; sheets' shadow-ray filter only with sheets.
    let glass = shader_source(FilmPrecision::F64, SceneFeatures { transmission: true, ..Default::default() });
    for present in ["fn dielectric_sample", "var<storage, read> scene_transmission", "fn absorption"] {
        assert!(glass.contains(present), "{present} missing from the shader of a scene with glass");
    }
    assert!(!glass.contains("shadow_query"), "the sheets' filter in a shader without sheets");
    for absent in ["fn dt_", "scene_diffuse_transmission", "DT_MIN_PROBABILITY"] {
        assert!(!glass.contains(absent), "{absent} in the shader of a scene without diffuse transmission");
    }
    let translucent = shader_source(
        FilmPrecision::F64,
        SceneFeatures { transmission: true, diffuse_transmission: true, ..Default::default() },
    );
    for present in ["fn dt_eval", "var<storage, read> scene_diffuse_transmission", "fn hit_material_estimate"]
    {
        assert!(translucent.contains(present), "{present} missing from a diffuse transmission shader");
    }
    let sheets = shader_source(
        FilmPrecision::F64,
        SceneFeatures { transmission: true, thin_walled: true, ..Default::default() },
    );
    assert!(sheets.contains("shadow_query"));
    // An environment only looked up: its texels, no CDFs, no light samples, no MIS weights.
    let env = shader_source(FilmPrecision::F64, SceneFeatures { environment: true, ..Default::default() });
    assert!(env.contains("fn env_radiance") && env.contains("var<storage, read> environment"));
    for absent in ["env_sample", "env_pdf", "sample_environment", "ray_pdf", "power_heuristic"] {
        assert!(!env.contains(absent), "{absent} in the shader of an environment without light samples");
    }
    let sampled = shader_source(
        FilmPrecision::F64,
        SceneFeatures { environment: true, env_sampling: true, ..Default::default() },
    );
    for present in ["fn env_sample", "fn env_pdf", "fn sample_environment", "ray_pdf: f32"] {
        assert!(
            sampled.contains(present),
            "{present} missing from the shader of a light-sampled environment"
        );
    }
}

/// The driver inlines a copy of the traversal at each call site and of the path code at each
/// call of it: the integrator calls the path code once and traces every ray of a path and of its
/// sampled lights through one `trace_query` call (point lights, a shadow ray per light, keep a
/// second one, `shadow`, only when there are more than the queue holds): a second copy of either
/// costs the GPU measurable time (BENCHMARKS.md).
#[test]
fn one_traversal_and_one_path_code_per_shader() {
    let calls = |source: &str, call: &str| source.matches(call).count();
    let every = SceneFeatures {
        emitters: true,
        delta_sun: true,
        sun_disc: true,
        environment: true,
        env_sampling: true,
        transmission: true,
        thin_walled: true,
        blend: true,
        unlit: true,
        aovs: true,
        adaptive: true,
        ..Default::default()
    };
    for (name, features) in [
        ("bare", SceneFeatures::default()),
        ("delta sun", SceneFeatures { delta_sun: true, ..Default::default() }),
        ("emitters, light BVH", SceneFeatures { emitters: true, light_bvh: true, ..Default::default() }),
        ("every sampled light, glass, AOVs", every),
    ] {
        let s = shader_source(FilmPrecision::F64, features);
        // traverse.wgsl's own wrappers call trace_query twice; the integrator once more.
        assert_eq!(calls(&s, "trace_query("), 4, "{name}: trace_query's definition and calls");
        assert_eq!(calls(&s, "trace_query(query_origin"), 1, "{name}: the integrator's one trace call");
        // trace_closest and trace_any: defined, never called (trace_any is called by `shadow`
        // alone, composed only for point lights past the queue); no point-light code at all.
        assert_eq!(calls(&s, "trace_closest("), 1, "{name}: trace_closest called");
        assert_eq!(calls(&s, "trace_any("), 1, "{name}: trace_any called");
        assert!(!s.contains("fn shadow(") && !s.contains("gather_point_lights("), "{name}: point-light code");
        assert_eq!(calls(&s, "trace_samples("), 2, "{name}: the path code's definition and one call");
        let kinds = features.shadow_kinds();
        assert!(s.contains(&format!("const SHADOW_KINDS: u32 = {kinds}u;")), "{name}: SHADOW_KINDS");
    }
    assert_eq!(every.shadow_kinds(), 4, "delta sun, emitters, sun disc, environment");
    // Point lights: queued, a slot each, up to MAX_QUEUED_POINT_LIGHTS; more are traced where
    // they are gathered, through `shadow` (a second traversal call).
    let queued = SceneFeatures { point_lights: true, queued_point_lights: 2, ..every };
    let s = shader_source(FilmPrecision::F64, queued);
    assert_eq!(queued.shadow_kinds(), 6);
    assert!(s.contains("const SHADOW_KINDS: u32 = 6u;") && s.contains("const SHADOW_SLOTS: u32 = 6u;"));
    assert_eq!(calls(&s, "trace_query("), 4, "queued point lights: trace_query's definition and calls");
    assert_eq!(calls(&s, "trace_any("), 1, "queued point lights: trace_any called");
    assert!(
        !s.contains("fn shadow(")
            && s.contains("defer_shadow(bsdf, o.xyz, wi, d * (1.0 - SHADOW_EPSILON), contribution);")
    );
    let many = SceneFeatures { point_lights: true, queued_point_lights: 0, ..every };
    let s = shader_source(FilmPrecision::F64, many);
    assert_eq!(many.shadow_kinds(), 4);
    assert_eq!(calls(&s, "* shadow(bsdf"), 1, "many point lights: `shadow` in their loop");
    assert_eq!(calls(&s, "trace_any("), 2, "many point lights: trace_any called by `shadow`");
}

#[test]
fn frame_params_layout_matches_wgsl() {
    furnace_tests::layout::assert_gpu_struct::<FrameParams>(&shader_source(
        FilmPrecision::F64,
        SceneFeatures::default(),
    ));
    // Every feature composed at once: the code behind each HAS_* constant must validate, with
    // either light selection.
    for light_bvh in [false, true] {
        furnace_tests::layout::assert_gpu_struct::<FrameParams>(&shader_source(
            FilmPrecision::F32Pass,
            SceneFeatures {
                point_lights: true,
                emitters: true,
                delta_sun: true,
                sun_disc: true,
                light_bvh,
                environment: true,
                env_sampling: true,
                aovs: light_bvh,
                adaptive: light_bvh,
                transmission: true,
                thin_walled: light_bvh,
                // Blended surfaces with and without thin-walled sheets: `shadow_query` is
                // declared for either.
                blend: !light_bvh,
                unlit: light_bvh,
                solid_angle_triangles: light_bvh,
                trace_counters: !light_bvh,
                queued_point_lights: if light_bvh { 3 } else { 0 },
                vertex_attributes: light_bvh,
                uv_sets: light_bvh,
                vertex_colors: light_bvh,
                clearcoat: light_bvh,
                sheen: !light_bvh,
                iridescence: light_bvh,
                specular_textures: light_bvh,
                diffuse_transmission: light_bvh,
                // Both ways: with and without textures (VERTEX_ATTRIBUTES).
                anisotropy: true,
                dispersion: !light_bvh,
                one_point_light: !light_bvh,
                // The two-level traversal, with every feature and with them all but a few.
                instances: true,
                split_triangles: light_bvh,
            },
        ));
    }
    // AOVs and adaptive sampling's GPU test on an f64 film (the F32Pass one is composed above).
    let f64_all =
        shader_source(FilmPrecision::F64, SceneFeatures { aovs: true, adaptive: true, ..Default::default() });
    assert!(f64_all.contains("fn converge(") && f64_all.contains("film_aov"));
    furnace_tests::layout::assert_gpu_struct::<FrameParams>(&f64_all);
    furnace_tests::layout::assert_gpu_struct::<GpuPointLight>(&shader_source(
        FilmPrecision::F64,
        SceneFeatures::default(),
    ));
    furnace_tests::layout::assert_gpu_struct::<furnace_gpu::scene::GpuTransmission>(&shader_source(
        FilmPrecision::F64,
        SceneFeatures { transmission: true, ..Default::default() },
    ));
    furnace_tests::layout::assert_gpu_struct::<furnace_gpu::scene::GpuDiffuseTransmission>(&shader_source(
        FilmPrecision::F64,
        SceneFeatures { transmission: true, diffuse_transmission: true, ..Default::default() },
    ));
    furnace_tests::layout::assert_gpu_struct::<furnace_gpu::scene::GpuAnisotropy>(&shader_source(
        FilmPrecision::F64,
        SceneFeatures { anisotropy: true, ..Default::default() },
    ));
}

#[test]
fn same_samples_give_the_same_image() {
    same_samples(&builtin::cornell_box().unwrap());
}

/// The point-light box with a spot light added (cone and range window): the point-light loop,
/// the spot cone and the range on both sides, every light gathered and one chosen per event;
/// then with two more lights, more than the shadow queue's slots (the GPU's other path when
/// all are gathered).
#[test]
fn same_samples_give_the_same_image_with_point_and_spot_lights() {
    let path = furnace_tests::data::reference("lights/cbox_point.gltf");
    let mut scene = furnace_scene::Scene::load(&path).unwrap();
    scene.lights.push(furnace_scene::Light::Point(furnace_scene::PointLight {
        position: glam::Vec3::new(0.5, 1.8, -0.3),
        intensity: glam::Vec3::new(3.0, 2.0, 1.0),
        range: Some(1.6),
        spot: Some(furnace_scene::SpotCone {
            direction: glam::Vec3::new(-0.3, -1.0, 0.2).normalize(),
            cos_inner: 0.9,
            cos_outer: 0.7,
        }),
    }));
    assert_eq!(scene.point_lights().count(), 3);
    same_samples(&scene);
    // One light per event, chosen by power (the choice's table and bisection on both sides).
    let one = RenderSettings {
        point_lights: furnace_render::PointLightSampling::One,
        ..settings(SamplerKind::Sobol, 3)
    };
    same_samples_with(&scene, one);
    // Past the shadow queue's point-light slots: traced where they are gathered.
    for x in [-0.6f32, 0.6] {
        scene.lights.push(furnace_scene::Light::Point(furnace_scene::PointLight {
            position: glam::Vec3::new(x, 1.2, 0.4),
            intensity: glam::Vec3::new(0.4, 0.5, 0.6),
            range: None,
            spot: None,
        }));
    }
    // Five lights: `auto` (the default) chooses one per event; every light's shadow ray is
    // traced where it is gathered only when all are asked for.
    assert!(scene.point_lights().count() as u32 > furnace_gpu::integrator::MAX_QUEUED_POINT_LIGHTS);
    assert!(furnace_render::PointLightSampling::Auto.chooses(scene.point_lights().count()));
    same_samples(&scene);
    let all = RenderSettings {
        point_lights: furnace_render::PointLightSampling::All,
        ..settings(SamplerKind::Sobol, 3)
    };
    same_samples_with(&scene, all);
}

/// The emissive-quad box, the 64-emitter box and the sun-disc box: emitter selection (alias
/// table), triangle sampling by solid angle and by area, cone sampling, the MIS weights of
/// light samples and of BSDF hits on emitters and on the disc, on both sides; and the two
/// single strategies (NEE only on the emitters, BSDF only on the disc: the flags that switch
/// the weights).
#[test]
fn same_samples_give_the_same_image_with_emitters_and_a_sun_disc() {
    use furnace_render::LightSampling::{Bsdf, Mis, Nee};
    use furnace_render::LightSelection::{Bvh, Power};
    use furnace_render::TriangleSampling::{Area, SolidAngle};
    for (file, strategies) in [
        ("cbox_area", &[(Mis, SolidAngle, Bvh), (Mis, Area, Power)][..]),
        // Power selection is cbox_area's second variant; here the light BVH over many emitters.
        ("cbox_many_lights", &[(Mis, SolidAngle, Bvh), (Nee, SolidAngle, Bvh)][..]),
        ("cbox_sun_disc", &[(Mis, SolidAngle, Bvh), (Bsdf, SolidAngle, Bvh)][..]),
    ] {
        let path = furnace_tests::data::reference(&format!("lights/{file}.gltf"));
        let scene = furnace_scene::Scene::load(&path).unwrap();
        for &(light_sampling, triangle_sampling, light_selection) in strategies {
            eprintln!(
                "{file}, light sampling {light_sampling}, triangles by {triangle_sampling}, chosen by {light_selection}"
            );
            same_samples_with(
                &scene,
                RenderSettings {
                    light_sampling,
                    triangle_sampling,
                    light_selection,
                    ..settings(SamplerKind::Sobol, 3)
                },
            );
        }
    }
}

/// The environment-map reference scene (a 512 × 256 HDR sky with a 1° sun of 2·10⁴): the
/// lookup, importance sampling (plain and compensated) and the MIS weights of both strategies,
/// BSDF rays only (`off`), light samples only (`nee`); rotated 70° and unseen by the camera.
#[test]
fn same_samples_give_the_same_image_with_an_environment_map() {
    use furnace_render::EnvSampling::{Compensated, Importance, Off};
    use furnace_render::LightSampling::{Mis, Nee};
    let path = furnace_tests::data::reference("envmap/envmap_spheres.gltf");
    let mut scene = furnace_scene::Scene::load(&path).unwrap();
    for (light_sampling, env_sampling) in
        [(Mis, Importance), (Mis, Compensated), (Mis, Off), (Nee, Importance)]
    {
        eprintln!("environment: light sampling {light_sampling}, env sampling {env_sampling}");
        same_samples_with(
            &scene,
            RenderSettings { light_sampling, env_sampling, ..settings(SamplerKind::Sobol, 3) },
        );
    }
    let mut env = scene.environment().unwrap().clone();
    env.rotation = 70f32.to_radians();
    env.visible = false;
    scene.set_environment(Some(env));
    eprintln!("environment rotated 70°, not visible");
    same_samples_with(&scene, settings(SamplerKind::Sobol, 3));
}

#[test]
fn same_samples_give_the_same_image_with_a_sample_clamp() {
    let scene = builtin::cornell_box().unwrap();
    let clamped = RenderSettings { clamp: Some(0.5), ..settings(SamplerKind::Sobol, 3) };
    // The clamp bounds every sample's largest channel, so every pixel's mean too, and it
    // darkens the image (the sun-lit floor and the sky exceed 0.5).
    let render = |s: RenderSettings| {
        let cpu = CpuRenderer::with_default_camera(scene.clone(), s).unwrap();
        let mut film = cpu.new_film();
        cpu.render_into(&mut film, 0, 4).unwrap();
        film
    };
    let (c, u) = (render(clamped), render(settings(SamplerKind::Sobol, 3)));
    let n = (SIZE * SIZE) as usize;
    for i in 0..n {
        assert!(c.mean(i).max_element() <= 0.5 + 1e-6, "pixel {i}: {:?}", c.mean(i));
    }
    let total = |f: &furnace_render::Film| (0..n).map(|i| f.mean(i).element_sum()).sum::<f64>();
    assert!(total(&c) < 0.99 * total(&u), "the clamp darkens: {} vs {}", total(&c), total(&u));
    same_samples_with(&scene, clamped);
}

fn same_samples(scene: &furnace_scene::Scene) {
    same_samples_with(scene, settings(SamplerKind::Sobol, 3));
}

/// The glass box with its smooth sphere made absorbing (glass_absorb's σ_a): smooth and rough
/// (α 0.1) dielectric interfaces, a thin-walled sheet (straight passes, shadow rays crossing it
/// with T′), Beer–Lambert in a volume; 8 bounces, Mitsuba's masking. 24², 16 spp: lavapipe
/// traces glass paths ~7× slower than the box's, and compiles each shader variant once (this
/// one, transmission with sheets, is also `tests/glass_cases/closed_forms.rs`'s).
#[test]
fn same_samples_give_the_same_image_with_glass() {
    {
        let path = furnace_tests::data::reference("glass/glass_box.gltf");
        let mut scene = furnace_scene::Scene::load(&path).unwrap();
        assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
        let sphere = scene.materials.iter_mut().find(|m| m.volume && m.roughness_factor == 0.0).unwrap();
        sphere.absorption = glam::Vec3::new(0.351, 1.703, 4.013);
        same_samples_with(&scene, glass_settings());
    }
}

/// The layers above the material (KHR_materials_clearcoat, KHR_materials_sheen): the clear-coat
/// spheres of the PBR references with sheens added to every other material (coat alone, sheen
/// alone, both), lit by their sun and sky; the helmet under a coat with its own normal map (the
/// coat's frame tilted from the shading frame); and the glass box with a coat and a sheen on its
/// transmissive materials (the layers over a dielectric: delta events weighted through them,
/// shadow rays crossing a coated sheet).
#[test]
fn same_samples_give_the_same_image_with_clearcoat_and_sheen() {
    let path = furnace_tests::data::reference("pbr/pbr_clearcoat.gltf");
    let mut scene = furnace_scene::Scene::load(&path).unwrap();
    for (i, m) in scene.materials.iter_mut().enumerate().filter(|(i, _)| i % 2 == 1) {
        m.layers.sheen = Some(furnace_scene::SheenLayer {
            color: glam::Vec3::new(0.9, 0.5, 0.3),
            color_texture: None,
            roughness: 0.2 + 0.1 * i as f32,
            roughness_texture: None,
        });
    }
    same_samples_with(
        &scene,
        RenderSettings { width: 32, height: 24, bounces: 3, ..settings(SamplerKind::Sobol, 5) },
    );
    // A coat with its own normal map over a normal-mapped base (the coat's frame tilted from
    // the shading frame): the helmet's normal map, at scale 0.4 for the coat.
    let mut helmet = lit_helmet();
    for m in &mut helmet.materials {
        m.layers.clearcoat = Some(furnace_scene::ClearcoatLayer {
            factor: 1.0,
            texture: None,
            roughness: 0.15,
            roughness_texture: None,
            normal_texture: m.normal_texture,
            normal_scale: 0.4,
        });
    }
    same_samples_with(
        &helmet,
        RenderSettings { width: 24, height: 24, bounces: 2, ..settings(SamplerKind::Sobol, 7) },
    );
    let mut glass =
        furnace_scene::Scene::load(furnace_tests::data::reference("glass/glass_box.gltf")).unwrap();
    for m in glass.materials.iter_mut().filter(|m| m.is_transmissive()) {
        m.layers.clearcoat = Some(furnace_scene::ClearcoatLayer {
            factor: 0.8,
            texture: None,
            roughness: 0.2,
            roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
        });
        m.layers.sheen = Some(furnace_scene::SheenLayer {
            color: glam::Vec3::new(0.3, 0.6, 0.9),
            color_texture: None,
            roughness: 0.5,
            roughness_texture: None,
        });
    }
    same_samples_with(&glass, glass_settings());
}

/// Same samples, same image with KHR_materials_iridescence: the helmet under a film read from
/// textures (weight from its metallic-roughness texture's G, thickness from its G between 100
/// and 900 nm) and a clear coat over it (the film beneath a layer); and the glass box with films
/// on its transmissive materials (the interface's coloured reflectance: delta events, the rough
/// slab, shadow rays through a filmed sheet).
#[test]
fn same_samples_give_the_same_image_with_iridescence() {
    let mut helmet = lit_helmet();
    let varying = varying_texture(&mut helmet);
    for m in &mut helmet.materials {
        m.iridescence = Some(furnace_scene::Iridescence {
            factor: 1.0,
            texture: varying,
            ior: 1.4,
            thickness_minimum: 100.0,
            thickness_maximum: 900.0,
            thickness_texture: m.metallic_roughness_texture,
        });
        m.layers.clearcoat = Some(furnace_scene::ClearcoatLayer {
            factor: 0.5,
            texture: None,
            roughness: 0.2,
            roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
        });
    }
    same_samples_with(
        &helmet,
        RenderSettings { width: 24, height: 24, bounces: 2, ..settings(SamplerKind::Sobol, 13) },
    );
    let mut glass =
        furnace_scene::Scene::load(furnace_tests::data::reference("glass/glass_box.gltf")).unwrap();
    for m in glass.materials.iter_mut().filter(|m| m.is_transmissive()) {
        m.iridescence = Some(furnace_scene::Iridescence {
            factor: 0.8,
            texture: None,
            ior: 1.8,
            thickness_minimum: 0.0,
            thickness_maximum: 450.0,
            thickness_texture: None,
        });
    }
    same_samples_with(&glass, glass_settings());
}

/// KHR_materials_diffuse_transmission on both integrators from the same samples: the
/// reference's back-lit sheets; the clear-coat scene's spheres made translucent (every other one
/// a solid with absorption, KHR_materials_volume: paths enter through the lobe, are absorbed
/// inside and leave through it), some under a sheen; the helmet with its base colour texture
/// as both diffuse transmission textures (the A channel, the sRGB RGB); the glass box with
/// diffuse transmission beside its dielectrics (the lobe within the transmissive mixture).
#[test]
fn same_samples_give_the_same_image_with_diffuse_transmission() {
    use furnace_scene::{DiffuseTransmissionFactors, Scene};
    use glam::Vec3;
    let lobe = |factor: f32, color: Vec3| DiffuseTransmissionFactors {
        factor,
        texture: None,
        color,
        color_texture: None,
    };
    let sheets = Scene::load(furnace_tests::data::reference("pbr/pbr_diffuse_transmission.gltf")).unwrap();
    same_samples_with(
        &sheets,
        RenderSettings { width: 40, height: 16, bounces: 3, ..settings(SamplerKind::Sobol, 5) },
    );
    let mut spheres = Scene::load(furnace_tests::data::reference("pbr/pbr_clearcoat.gltf")).unwrap();
    for (i, m) in spheres.materials.iter_mut().enumerate() {
        m.diffuse_transmission = Some(lobe(0.3 + 0.15 * (i % 5) as f32, Vec3::new(0.9, 0.6, 0.3)));
        m.double_sided = true;
        m.volume = i % 2 == 0;
        m.absorption = Vec3::new(0.5, 1.0, 2.0);
        if i % 3 == 0 {
            m.layers.sheen = Some(furnace_scene::SheenLayer {
                color: Vec3::new(0.4, 0.5, 0.9),
                color_texture: None,
                roughness: 0.4,
                roughness_texture: None,
            });
        }
    }
    same_samples_with(
        &spheres,
        RenderSettings { width: 32, height: 24, bounces: 4, ..settings(SamplerKind::Sobol, 6) },
    );
    let mut helmet = lit_helmet();
    for m in &mut helmet.materials {
        m.diffuse_transmission = Some(DiffuseTransmissionFactors {
            texture: m.base_color_texture,
            color_texture: m.base_color_texture,
            ..lobe(0.8, Vec3::new(1.0, 0.8, 0.6))
        });
        m.double_sided = true;
    }
    same_samples_with(
        &helmet,
        RenderSettings { width: 24, height: 24, bounces: 2, ..settings(SamplerKind::Sobol, 7) },
    );
    let mut glass = Scene::load(furnace_tests::data::reference("glass/glass_box.gltf")).unwrap();
    for m in &mut glass.materials {
        m.diffuse_transmission = Some(lobe(0.5, Vec3::new(0.8, 0.9, 1.0)));
        m.double_sided = true;
    }
    same_samples_with(&glass, glass_settings());
}

/// The helmet's metallic-roughness image with its G in R and its B in A, as a new texture (the
/// image's R, occlusion, is near 0 and its A 1: the copy's R and A vary over the model).
fn varying_texture(helmet: &mut furnace_scene::Scene) -> Option<furnace_scene::TextureRef> {
    let t = helmet.materials.iter().find_map(|m| m.metallic_roughness_texture)?;
    let source = helmet.textures[t.texture as usize];
    let mut varying = helmet.images[source.image as usize].clone();
    varying.texels.iter_mut().for_each(|t| *t = [t[1], t[1], t[2], t[2]]);
    helmet.images.push(varying);
    helmet.textures.push(furnace_scene::Texture { image: helmet.images.len() as u32 - 1, ..source });
    Some(furnace_scene::TextureRef { texture: helmet.textures.len() as u32 - 1, ..t })
}

/// Same samples, same image with KHR_materials_specular textures: the helmet made a dielectric
/// (metallic 0, so the specular weight and colour decide its whole reflection) with
/// specularTexture varying over it (A channel, linear) and its base colour texture as
/// specularColorTexture (sRGB).
#[test]
fn same_samples_give_the_same_image_with_specular_textures() {
    let mut helmet = lit_helmet();
    let varying = varying_texture(&mut helmet);
    assert!(varying.is_some(), "the helmet has a metallic-roughness texture");
    for m in &mut helmet.materials {
        m.metallic_factor = 0.0;
        m.specular_textures =
            furnace_scene::SpecularTextures { specular: varying, color: m.base_color_texture };
    }
    same_samples_with(
        &helmet,
        RenderSettings { width: 24, height: 24, bounces: 2, ..settings(SamplerKind::Sobol, 17) },
    );
}

/// Same samples, same image with KHR_materials_anisotropy: the helmet (normal-mapped, with
/// tangents) anisotropic with the direction and strength read from a texture that varies over
/// it, rotated, under a clear coat (the coat's normal in the anisotropic frame); and the glass
/// box, whose files have no tangents (the stretched lobe in the plain frame), anisotropic on its
/// transmissive materials (the opaque part of the transmissive mixture) and the rest.
#[test]
fn same_samples_give_the_same_image_with_anisotropy() {
    let mut helmet = lit_helmet();
    let varying = varying_texture(&mut helmet);
    assert!(!helmet.geometry.tangents.is_empty(), "the helmet has tangents");
    for m in &mut helmet.materials {
        m.anisotropy = Some(furnace_scene::Anisotropy { strength: 0.8, rotation: 0.7, texture: varying });
        m.layers.clearcoat = Some(furnace_scene::ClearcoatLayer {
            factor: 0.5,
            texture: None,
            roughness: 0.2,
            roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
        });
    }
    same_samples_with(
        &helmet,
        RenderSettings { width: 24, height: 24, bounces: 2, ..settings(SamplerKind::Sobol, 19) },
    );
    let mut glass =
        furnace_scene::Scene::load(furnace_tests::data::reference("glass/glass_box.gltf")).unwrap();
    for m in &mut glass.materials {
        m.anisotropy = Some(furnace_scene::Anisotropy { strength: 0.9, rotation: 0.0, texture: None });
    }
    same_samples_with(&glass, glass_settings());
}

/// Same samples, same image with a rough thin-walled sheet: the glass box's sheet at roughness
/// 0.3 and 0.8 (its reflection and mirrored transmission lobes, light samples from behind it,
/// shadow rays it blocks).
#[test]
fn same_samples_give_the_same_image_with_rough_sheets() {
    for roughness in [0.3, 0.8] {
        let mut glass =
            furnace_scene::Scene::load(furnace_tests::data::reference("glass/glass_box.gltf")).unwrap();
        let sheets: Vec<_> = glass.materials.iter_mut().filter(|m| m.is_thin_walled()).collect();
        assert!(!sheets.is_empty(), "the glass box has a sheet");
        for m in sheets {
            m.roughness_factor = roughness;
        }
        same_samples_with(&glass, glass_settings());
    }
}

/// Same samples, same image with dispersive solids: the glass box's smooth and rough solids at
/// dispersion 1 (V_d = 20) and 5 (the wavelength drawn at the first solid, its RGB weight, the
/// index at it on every later crossing, red indices clamped at 1 where the interface vanishes).
#[test]
fn same_samples_give_the_same_image_with_dispersion() {
    for dispersion in [1.0, 5.0] {
        let mut glass =
            furnace_scene::Scene::load(furnace_tests::data::reference("glass/glass_box.gltf")).unwrap();
        let solids: Vec<_> = glass.materials.iter_mut().filter(|m| m.is_transmissive() && m.volume).collect();
        assert!(solids.len() >= 2, "the glass box has a smooth and a rough solid");
        for m in solids {
            m.dispersion = dispersion;
        }
        same_samples_with(&glass, glass_settings());
    }
}

/// DamagedHelmet under a white sky and a sun from the front left above (the file has no light:
/// unlit, its same-samples images would be its emission alone). Neither light is sampled from a
/// table, so the two backends' paths part only where their floats do.
fn lit_helmet() -> furnace_scene::Scene {
    use furnace_scene::{Light, Sky, Sun};
    use glam::Vec3;
    let mut helmet =
        furnace_scene::Scene::load(furnace_tests::data::scene("DamagedHelmet/glTF-Binary/DamagedHelmet.glb"))
            .unwrap();
    helmet.lights.push(Light::Sky(Sky { radiance: Vec3::splat(0.5) }));
    helmet.lights.push(Light::Sun(Sun {
        direction: Vec3::new(0.4, -0.5, -0.8).normalize(),
        irradiance: Vec3::splat(3.0),
        angular_radius: 0.0,
    }));
    helmet
}

/// The glass box's settings for the same-samples tests: 24², 8 bounces, Mitsuba's masking.
fn glass_settings() -> RenderSettings {
    RenderSettings {
        width: 24,
        height: 24,
        bounces: 8,
        specular: furnace_brdf::SpecularOptions::mitsuba(),
        ..settings(SamplerKind::Sobol, 3)
    }
}

fn same_samples_with(scene: &furnace_scene::Scene, s: RenderSettings) {
    let Some(ctx) = test_context() else { return };
    let scene = scene.clone();
    let camera = scene.default_camera();
    const SPP: u32 = 16;
    let cpu = CpuRenderer::with_default_camera(scene.clone(), s).unwrap();
    let mut film = cpu.new_film();
    cpu.render_into(&mut film, 0, SPP).unwrap();
    let mut gpu = GpuRenderer::new(ctx, &scene, &camera, s).unwrap();
    eprintln!("adapter {}, film {:?}", gpu.context().describe(), gpu.film_precision());
    gpu.render_pass(0, SPP).unwrap();
    let g = gpu.film().unwrap();
    assert_eq!(g.rejected(), 0);
    let (width, n) = (s.width, (s.width * s.height) as usize);
    let mut close = 0;
    let (mut gm, mut cm) = ([0.0f64; 3], [0.0f64; 3]);
    for i in 0..n {
        assert_eq!(g.counts()[i], u64::from(SPP), "pixel {i} sample count");
        let gp = g.mean(i);
        let cp = film.pixel(i as u32 % width, i as u32 / width).to_array();
        let rel = (0..3).map(|c| (gp[c] - cp[c]).abs() / cp[c].abs().max(1e-3)).fold(0.0, f64::max);
        close += usize::from(rel < 1e-4);
        for c in 0..3 {
            gm[c] += gp[c] / n as f64;
            cm[c] += cp[c] / n as f64;
        }
    }
    eprintln!("same samples: {close}/{n} pixels within 1e-4; means gpu {gm:?} cpu {cm:?}");
    for c in 0..3 {
        let rel = (gm[c] - cm[c]).abs() / cm[c];
        assert!(rel < 1e-3, "channel {c}: GPU mean {} vs CPU {} (rel {rel:e})", gm[c], cm[c]);
    }
    // The same sample points must give the same paths: a twin that is merely unbiased agrees in
    // ~0 % of pixels, and one that reads a texture's wrong channel still in ~80 %, while the
    // backends' float differences alone part ≤ 6 % of paths (the environment map's, whose
    // table lookups split at cell edges; the others ≤ 2 %). Hence 90 %.
    assert!(close * 10 >= n * 9, "only {close}/{n} pixels agree within 1e-4 with the same sample points");
}

#[test]
fn independent_estimates_agree_within_noise() {
    let Some(ctx) = test_context() else { return };
    let scene = builtin::cornell_box().unwrap();
    let camera = scene.default_camera();
    const PASSES: u32 = 128;
    let cpu = CpuRenderer::with_default_camera(scene.clone(), settings(SamplerKind::Random, 1)).unwrap();
    let mut film = cpu.new_film();
    let (cm, cv) = per_sample_stats(
        |k| {
            film.clear();
            cpu.render_into(&mut film, k, 1).unwrap();
            (0..SIZE * SIZE).map(|i| film.pixel(i % SIZE, i / SIZE).to_array()).collect()
        },
        PASSES,
    );
    let mut gpu = GpuRenderer::new(ctx, &scene, &camera, settings(SamplerKind::Random, 2)).unwrap();
    let mut prev = gpu.film().unwrap();
    let (gm, gv) = per_sample_stats(
        |k| {
            gpu.render_pass(k, 1).unwrap();
            let now = gpu.film().unwrap();
            let v = (0..(SIZE * SIZE) as usize)
                .map(|i| std::array::from_fn(|c| now.sums()[i][c] - prev.sums()[i][c]))
                .collect();
            prev = now;
            v
        },
        PASSES,
    );
    let (a, b) = (channel_means(&gm), channel_means(&cm));
    let mut zs = Vec::new();
    for i in 0..gm.len() {
        for c in 0..3 {
            let se = (gv[i][c] + cv[i][c]).sqrt();
            if se > 0.0 {
                zs.push((gm[i][c] - cm[i][c]) / se);
            }
        }
    }
    let zn = zs.len() as f64;
    let zmean = zs.iter().sum::<f64>() / zn;
    let zstd = (zs.iter().map(|z| (z - zmean).powi(2)).sum::<f64>() / zn).sqrt();
    eprintln!("independent: means gpu {a:?} cpu {b:?}; z mean {zmean:.3}, std {zstd:.3} over {zn} values");
    for c in 0..3 {
        let ratio = a[c] / b[c];
        assert!((ratio - 1.0).abs() < 5e-3, "channel {c}: GPU/CPU mean ratio {ratio}");
    }
    assert!(zmean.abs() < 0.1, "z mean {zmean}");
    assert!(zstd <= 1.15, "z std {zstd}");
}

#[test]
fn grouping_samples_does_not_change_a_bit() {
    let Some(ctx) = test_context() else { return };
    let scene = builtin::cornell_box().unwrap();
    let camera = scene.default_camera();
    // 20×13: rows and columns that no tile divides, so partial workgroups are exercised.
    let s = RenderSettings { width: 20, height: 13, ..settings(SamplerKind::Sobol, 5) };
    let mut gpu = GpuRenderer::new(ctx, &scene, &camera, s).unwrap();
    let mut films = Vec::new();
    // (group_samples, pass sizes): one invocation per pixel; 4 and 64 (capped at the pass's
    // sample count) invocations per pixel; uneven passes.
    for (group, passes) in [(1, vec![8]), (4, vec![8]), (64, vec![8]), (2, vec![3, 5]), (8, vec![1, 7])] {
        gpu.set_group_samples(Some(group));
        gpu.load_film(&furnace_render::Film::new(s.width, s.height)).unwrap();
        let mut first = 0;
        for n in passes {
            gpu.render_pass(first, n).unwrap();
            first += n;
        }
        films.push((group, gpu.film().unwrap()));
    }
    let (_, reference) = &films[0];
    assert!(reference.counts().iter().all(|&c| c == 8));
    for (group, f) in &films[1..] {
        let same = f.counts() == reference.counts()
            && f.sums()
                .iter()
                .zip(reference.sums())
                .all(|(a, b)| a.to_array().map(f64::to_bits) == b.to_array().map(f64::to_bits));
        assert!(same, "group_samples {group}: the film differs from one invocation per pixel");
    }
}

#[test]
fn traversal_counters_are_exact_for_primary_rays_and_plausible() {
    let Some(ctx) = test_context() else { return };
    let scene = builtin::cornell_box().unwrap();
    let camera = scene.default_camera();
    let s = RenderSettings { width: 16, height: 16, bounces: 0, ..RenderSettings::default() };
    let mut gpu = GpuRenderer::new(ctx, &scene, &camera, s).unwrap();
    gpu.set_count_rays(true).unwrap();
    gpu.set_group_samples(Some(2));
    gpu.render_pass(0, 2).unwrap();
    let c = gpu.take_trace_counts().unwrap();
    assert_eq!(c.rays, 16 * 16 * 2, "{c:?}");
    // Every closest-hit ray starts at the root (≥ 1 node) and a ray that hits tested ≥ 1 triangle;
    // the box is closed but for its ceiling hole, so most do.
    assert!(c.nodes >= c.rays && c.triangles >= c.rays / 2, "{c:?}");
    // A 20k-triangle CWBVH is ~8 levels deep: the stack (32) never overflows.
    assert!(c.fallbacks == 0 && (1..=32).contains(&c.max_stack_depth), "{c:?}");
    assert_eq!(gpu.take_trace_counts().unwrap(), Default::default(), "taking the counts resets them");
}

/// Counting is a kernel of its own: off by default, on when asked, off again, and the films of
/// the two kernels are the same bits (counting changes what is recorded, never a path).
#[test]
fn ray_counter_counts_every_ray_only_when_asked() {
    use furnace_render::{Film, Integrator};
    let Some(ctx) = test_context() else { return };
    let scene = builtin::cornell_box().unwrap();
    let camera = scene.default_camera();
    // No bounces: exactly one closest-hit ray per sample (the Cornell box has no sun).
    let s = RenderSettings { width: 16, height: 16, bounces: 0, ..RenderSettings::default() };
    let mut gpu = GpuRenderer::new(ctx, &scene, &camera, s).unwrap();
    gpu.render_pass(0, 2).unwrap();
    assert_eq!(gpu.take_ray_count().unwrap(), 0, "counting is off by default");
    gpu.render_pass(2, 3).unwrap();
    let rendered = gpu.film().unwrap();
    gpu.set_film(&Film::new(s.width, s.height)).unwrap();
    gpu.set_count_rays(true).unwrap();
    gpu.render_pass(0, 2).unwrap();
    assert_eq!(gpu.take_ray_count().unwrap(), 16 * 16 * 2);
    gpu.render_pass(2, 3).unwrap();
    assert_eq!(gpu.take_ray_count().unwrap(), 16 * 16 * 3);
    assert_eq!(gpu.take_ray_count().unwrap(), 0, "taking the count resets it");
    assert_eq!(gpu.film().unwrap().sums(), rendered.sums(), "the counting kernel's film");
    gpu.set_count_rays(false).unwrap();
    gpu.render_pass(5, 1).unwrap();
    assert_eq!(gpu.take_ray_count().unwrap(), 0, "counting is off again");
    assert!(gpu.bvh_bytes() > 0 && gpu.scene_bytes() > 0);
}

// Glass against closed forms and the WGSL dielectric's parity: modules of this test binary
// rather than binaries of their own (each test binary of this crate costs CI a link).
/// A split render on the GPU: samples 0..5 and 5..12 traced into two fresh films (the second
/// part starting at an index no pass of a single run starts at) and added equal the film of
/// 0..12 from one pass — the GPU addresses samples by their global index, as `furnace render
/// --samples` and `furnace merge` need. Counts exactly; sums to the rounding of their additions:
/// `merge_bound` for `f64` films; for films summed per pass in `f32` (GPUs without `f64`), each
/// of the three pass sums is within `(k−1)·2⁻²⁴·Σx` of exact, so `2·(n−1)·2⁻²⁴·Σx` bounds them.
#[test]
fn gpu_parts_add_up_to_one_run() {
    use furnace_render::{Film, Integrator, merge_bound};
    let Some(ctx) = test_context() else { return };
    let scene = builtin::cornell_box().unwrap();
    let s = RenderSettings { width: 16, height: 16, ..settings(SamplerKind::Sobol, 3) };
    let mut gpu = GpuRenderer::new(ctx, &scene, &scene.default_camera(), s).unwrap();
    gpu.render_pass(0, 12).unwrap();
    let whole = gpu.film().unwrap();
    let mut merged = Film::new(s.width, s.height);
    for (first, n) in [(5, 7), (0, 5)] {
        gpu.set_film(&Film::new(s.width, s.height)).unwrap();
        gpu.render_pass(first, n).unwrap();
        merged.add_film(&gpu.film().unwrap()).unwrap();
    }
    assert_eq!(merged.counts(), whole.counts());
    assert_eq!(merged.rejected(), whole.rejected());
    let precision = gpu.film_precision();
    for (i, (m, w)) in merged.sums().iter().zip(whole.sums()).enumerate() {
        let n = whole.counts()[i];
        let relative = match precision {
            FilmPrecision::F64 => merge_bound(n),
            FilmPrecision::F32Pass => 2.0 * (n as f64 - 1.0) * 2f64.powi(-24) + merge_bound(n),
        };
        let bound = relative * w.max_element();
        let diff = (*m - *w).abs().max_element();
        assert!(diff <= bound, "pixel {i} ({precision:?}): parts {m} one run {w}: |Δ| {diff:e} > {bound:e}");
    }
}

#[path = "glass_cases/dielectric_parity.rs"]
mod dielectric_parity;
#[path = "glass_cases/closed_forms.rs"]
mod glass;

/// Same samples, same image with instances: NegativeScaleTest (mirroring instances, textures
/// and normal maps whose frames the instance carries) under a white sky, and the built-in forest
/// of 12 instances (three shared meshes, a sun and a sky), through both two-level traversals.
#[test]
fn same_samples_give_the_same_image_with_instances() {
    use furnace_scene::{Light, Sky};
    let mut negative = furnace_scene::Scene::load(furnace_tests::data::scene(
        "NegativeScaleTest/glTF/NegativeScaleTest.gltf",
    ))
    .unwrap();
    negative.lights.push(Light::Sky(Sky { radiance: glam::Vec3::ONE }));
    assert!(!negative.instancing.is_empty());
    let s = RenderSettings { width: 32, height: 32, ..settings(SamplerKind::Sobol, 5) };
    same_samples_with(&negative, s);
    same_samples_with(&builtin::forest(12, 3), s);
}
