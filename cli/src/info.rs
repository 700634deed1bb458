//! `furnace info`: what a scene holds, as the loader sees it, and the render settings that the
//! settings flags make (one line per row of `furnace_render::fields::FIELDS`).

use crate::args::InfoArgs;
use furnace_render::RenderSettings;
use furnace_render::fields::FIELDS;
use furnace_scene::{Camera, Projection, Scene};
use glam::Vec3;

pub fn run(a: &InfoArgs) -> Result<(), String> {
    let settings = &a.settings.settings;
    // Refused as `furnace render` refuses it.
    if a.settings.given("env-sampling") {
        crate::env::check_sampling(settings.env_sampling, settings.light_sampling)?;
    }
    let options = a.load.options();
    let scene = crate::render::load_scene(Some(&a.scene), &options)?;
    print!("{}", describe(&scene));
    print!("{}", describe_extensions(&scene.extensions));
    print!("{}", describe_variants(&scene, a.load.variant.as_deref()));
    print!("{}", describe_animations(&scene));
    print!("{}", describe_settings(settings, scene.point_lights().count()));
    Ok(())
}

/// The glTF extensions the file lists, one line each: `required` where the file requires it,
/// and whether furnace honours it or ignores it.
fn describe_extensions(extensions: &[furnace_scene::ExtensionUse]) -> String {
    if extensions.is_empty() {
        return format!("{:<16}none\n", "extensions");
    }
    let mut out = format!(
        "{:<16}{} (the file's extensionsUsed and extensionsRequired)\n",
        "extensions",
        extensions.len()
    );
    for e in extensions {
        let required = if e.required { "required" } else { "used" };
        let honoured = if e.honoured() { "honoured" } else { "ignored" };
        out.push_str(&format!("  {:<34}{required}, {honoured}\n", e.name));
    }
    out
}

/// The file's KHR_materials_variants, one line (nothing without them): each variant's index
/// and name, the one `loaded` (`--variant`, by name or index) marked.
fn describe_variants(scene: &Scene, loaded: Option<&str>) -> String {
    if scene.variants.is_empty() {
        return String::new();
    }
    let loaded = loaded.and_then(|w| {
        scene
            .variants
            .iter()
            .position(|n| n == w)
            .or_else(|| w.parse().ok().filter(|&i| i < scene.variants.len()))
    });
    let names: Vec<String> = scene
        .variants
        .iter()
        .enumerate()
        .map(|(i, n)| format!("{i} '{n}'{}", if Some(i) == loaded { " (loaded)" } else { "" }))
        .collect();
    format!("{:<16}{}: {}\n", "variants", names.len(), names.join(", "))
}

/// The file's animations, one line (nothing without them): each animation's index, name and
/// duration, the one the scene is posed by (`--animation`, `--time`) marked with its time.
fn describe_animations(scene: &Scene) -> String {
    if scene.animations.is_empty() {
        return String::new();
    }
    let listed: Vec<String> = scene
        .animations
        .iter()
        .enumerate()
        .map(|(i, a)| {
            let posed = match scene.posed_by {
                Some((p, t)) if p == i => format!(" (loaded at {t} s)"),
                _ => String::new(),
            };
            format!("{i} '{}' {} s{posed}", a.name, a.duration)
        })
        .collect();
    format!("{:<16}{}: {}\n", "animations", listed.len(), listed.join(", "))
}

/// The render settings, one line per field: its flag and its value as the flag takes it
/// (`not set` for an option that is off), marked `(default)` where it is the command line's
/// default or the value of [`RenderSettings::default`] (an option not set), and followed by the
/// method used where another setting or the scene decides it (`auto` point-light sampling for
/// `point_lights` lights, compensated environment sampling without MIS).
fn describe_settings(settings: &RenderSettings, point_lights: usize) -> String {
    let defaults = RenderSettings::default();
    let mut out =
        String::from("settings        as `furnace render` takes them (the flags given, else the defaults)\n");
    for f in FIELDS {
        let value = (f.get)(settings);
        let default = value.as_deref() == f.default || value == (f.get)(&defaults);
        let flag = format!("--{}", f.flag);
        let value = value.unwrap_or_else(|| "not set".into());
        let used = used(f.flag, settings, point_lights).map(|u| format!(", {u}")).unwrap_or_default();
        out.push_str(&format!("  {flag:<21}{value}{}{used}\n", if default { " (default)" } else { "" }));
    }
    out
}

/// The method a setting resolves to where it is not the value given: `None` where it is.
fn used(flag: &str, settings: &RenderSettings, point_lights: usize) -> Option<String> {
    match flag {
        "point-lights" => {
            let used = settings.point_lights.effective(point_lights);
            (used != settings.point_lights)
                .then(|| format!("{} for this scene's {point_lights} point and spot lights", used.name()))
        }
        "env-sampling" => {
            let used = settings.env_sampling.effective(settings.light_sampling);
            (used != settings.env_sampling)
                .then(|| format!("{} with --light-sampling {}", used.name(), settings.light_sampling.name()))
        }
        _ => None,
    }
}

fn v3(v: Vec3) -> String {
    format!("({:.4}, {:.4}, {:.4})", v.x, v.y, v.z)
}

/// A camera's projection and position.
fn describe_camera(camera: &Camera) -> String {
    let projection = match camera.projection {
        Projection::Perspective { yfov, aspect_ratio } => {
            let aspect = aspect_ratio.map_or_else(|| "not given".into(), |r| format!("{r:.4}"));
            format!("perspective, yfov {:.2}°, aspect ratio {aspect}", yfov.to_degrees())
        }
        Projection::Orthographic { xmag, ymag } => format!("orthographic, xmag {xmag}, ymag {ymag}"),
    };
    format!("{projection}, at {}", v3(Vec3::from(camera.world_from_camera.translation)))
}

/// The report, one `key: value` line per item (a line per light), then the warnings.
fn describe(scene: &Scene) -> String {
    let s = scene.stats();
    let mut out = String::new();
    let mut line = |k: &str, v: String| out.push_str(&format!("{k:<16}{v}\n"));
    line("scene", scene.name.clone());
    if s.instances == 0 {
        line("triangles", s.triangles.to_string());
    } else {
        line(
            "triangles",
            format!("{} stored, {} in the image (the instances counted)", s.triangles, s.instanced_triangles),
        );
        let world = scene.instancing.world_triangles;
        line(
            "instancing",
            format!(
                "{} meshes stored once ({} triangles), placed by {} instances ({} bytes); {world} triangles in world space",
                s.meshes,
                s.triangles - world as usize,
                s.instances,
                s.instance_bytes
            ),
        );
    }
    // The structure the renderers trace (the default light's probe builds it too, when it runs).
    let mut accel = None;
    let decision =
        scene.environment().is_none().then(|| crate::default_light::decide_with(scene, &mut accel));
    let accel = accel.unwrap_or_else(|| furnace_cpu::CpuRenderer::accel_for(scene));
    line("memory", memory(scene, &s, &accel.bytes()));
    drop(accel);
    line("vertices", s.vertices.to_string());
    line("dropped", format!("{} zero-area triangles (they cannot be hit)", s.dropped_triangles));
    line("materials", format!("{} (including glTF's default material)", s.materials));
    line(
        "textures",
        format!(
            "{} ({} images, {} bytes of texels)",
            scene.textures.len(),
            scene.images.len(),
            s.texture_bytes
        ),
    );
    let emitters = furnace_scene::Emitters::new(scene);
    if scene.lights.is_empty() && emitters.is_none() {
        line("lights", "none (black sky)".into());
    }
    for light in &scene.lights {
        line("light", light.to_string());
    }
    if let Some(e) = &emitters {
        // Σ luminance · area is the power up to π: π·L·A for a Lambertian emitter.
        let power = std::f32::consts::PI * e.total_weight();
        line(
            "emitters",
            format!(
                "{} emissive triangles, luminous power {power:.4} W (luminance-weighted), chosen for light samples by \
                 the light BVH (--light-selection power: by power)",
                e.len()
            ),
        );
    }
    if let Some(d) = decision
        && d.why != crate::default_light::Why::Sky
    {
        let text = if d.studio {
            let none = if scene.has_own_light() { "its own lights alone" } else { "none" };
            format!(
                "studio: `furnace render` adds the built-in studio environment: {} (--env none for {none}, \
                 --env FILE for another map)",
                d.reason()
            )
        } else {
            format!("none: {} (--env studio or --env FILE to add one)", d.reason())
        };
        line("default light", text);
    }
    if scene.cameras.is_empty() {
        let camera = describe_camera(&scene.default_camera());
        line("camera", format!("none in the file; framed around the geometry: {camera}"));
    } else {
        let n = scene.cameras.len();
        line("cameras", format!("{n} (render one with --camera INDEX; the default is 0)"));
        for (i, camera) in scene.cameras.iter().enumerate() {
            line(&format!("  camera {i}"), describe_camera(camera));
        }
    }
    line(
        "bytes/triangle",
        format!(
            "{:.1} ({} bytes of geometry{})",
            s.bytes_per_triangle,
            s.geometry_bytes,
            if s.stores_uvs { ", UVs stored" } else { "" }
        ),
    );
    line("warnings", scene.warnings.len().to_string());
    for w in &scene.warnings {
        out.push_str(&format!("  warning: {w}\n"));
    }
    out
}

/// The memory line: the bytes the scene takes on the host (its arrays, the BVHs, the instances
/// with their transforms and TLAS) and on a GPU (the packed scene, the BVHs, the TLAS and the
/// instance records), each per stored triangle and per instance. The GPU's film and path
/// buffers, which depend on the image size, are not counted (`furnace bench` reports all).
fn memory(scene: &Scene, s: &furnace_scene::SceneStats, a: &furnace_accel::AccelBytes) -> String {
    let mib = |b: usize| b as f64 / 1_048_576.0;
    let per = |b: usize, n: usize| b as f64 / n.max(1) as f64;
    let instances = s.instances;
    let gpu_scene = furnace_gpu::scene::SceneBuffers::new(scene, u64::MAX).map(|b| b.bytes() as usize);
    // The GPU places the world triangles by an identity instance of their own.
    let gpu_records = if instances == 0 {
        0
    } else {
        (instances + usize::from(scene.instancing.world_triangles > 0))
            * size_of::<furnace_gpu::traverse::GpuInstance>()
    };
    let per_instance = |b: usize| {
        if instances == 0 { String::new() } else { format!(", {:.0} per instance", per(b, instances)) }
    };
    let host_instances = s.instance_bytes + a.instances;
    let host = format!(
        "host {:.1} MiB ({:.1} bytes per stored triangle with its BVH{})",
        mib(s.geometry_bytes + a.bvh + host_instances),
        per(s.geometry_bytes + a.bvh, s.triangles),
        per_instance(host_instances)
    );
    let gpu = match gpu_scene {
        Ok(scene_bytes) => format!(
            "GPU {:.1} MiB ({:.1} bytes per stored triangle with its BVH{}) and the film",
            mib(scene_bytes + a.gpu_bvh + a.gpu_tlas + gpu_records),
            per(scene_bytes + a.gpu_bvh, s.triangles),
            per_instance(a.gpu_tlas + gpu_records)
        ),
        Err(e) => format!("GPU: {e}"),
    };
    format!("{host}; {gpu}")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 64-emitter box holds 8 W in all (the references' README): the emitters' line says so
    /// from the triangles' areas and luminances.
    #[test]
    fn describes_the_emitters_with_their_power() {
        let path = furnace_tests::data::reference("lights/cbox_many_lights.gltf");
        let text = describe(&Scene::load(path).unwrap());
        assert!(text.contains("emitters        128 emissive triangles, luminous power 7.99"), "{text}");
    }

    #[test]
    fn describes_the_cornell_box() {
        let text = describe(&furnace_scene::builtin::cornell_box().unwrap());
        assert!(text.contains("triangles       20516"), "{text}");
        assert!(text.contains("light           sun travelling"), "{text}");
        assert!(text.contains("light           sky of radiance"), "{text}");
        assert!(text.contains("perspective, yfov 45.00°"), "{text}");
        assert!(!text.contains("default light"), "{text}");
    }

    #[test]
    fn says_when_the_studio_would_light_the_scene() {
        let mut scene = furnace_scene::builtin::cornell_box().unwrap();
        scene.lights.clear();
        for m in &mut scene.materials {
            m.emissive = Vec3::ZERO;
        }
        let text = describe(&scene);
        assert!(
            text.contains(
                "default light   studio: `furnace render` adds the built-in studio environment: it has no \
                 light of its own (--env none for none"
            ),
            "{text}"
        );
    }

    /// A line per field, in the table's order, with its flag and value; `(default)` on those
    /// left at the command line's default.
    #[test]
    fn describes_every_setting_from_the_table() {
        let mut settings = RenderSettings { bounces: 7, clamp: Some(2.5), ..RenderSettings::default() };
        settings.light_sampling = furnace_render::LightSampling::Nee;
        let text = describe_settings(&settings, 5);
        let lines: Vec<&str> = text.lines().skip(1).collect();
        assert_eq!(lines.len(), FIELDS.len(), "{text}");
        for (line, f) in lines.iter().zip(FIELDS) {
            assert!(line.starts_with(&format!("  --{} ", f.flag)), "{line}");
        }
        assert!(text.contains("  --bounces            7\n"), "{text}");
        assert!(text.contains("  --sampler            sobol (default)\n"), "{text}");
        assert!(text.contains("  --light-sampling     nee\n"), "{text}");
        assert!(text.contains("  --clamp              2.5\n"), "{text}");
        assert!(text.contains("  --noise-threshold    not set (default)\n"), "{text}");
        // What another setting or the scene makes of them.
        assert!(
            text.contains(
                "  --point-lights       auto (default), one for this scene's 5 point and spot lights\n"
            ),
            "{text}"
        );
        assert!(
            text.contains(
                "  --env-sampling       compensated (default), importance with --light-sampling nee\n"
            ),
            "{text}"
        );
        let text = describe_settings(&RenderSettings::default(), 0);
        assert!(text.contains("  --env-sampling       compensated (default)\n"), "{text}");
    }

    /// One line per extension, required or only used, honoured or ignored.
    #[test]
    fn lists_the_extensions_and_what_furnace_does_with_them() {
        let use_ = |name: &str, required| furnace_scene::ExtensionUse { name: name.into(), required };
        let text = describe_extensions(&[
            use_("EXT_mesh_gpu_instancing", true),
            use_("ACME_not_an_extension", false),
        ]);
        assert_eq!(
            text,
            "extensions      2 (the file's extensionsUsed and extensionsRequired)\n\
             \x20 EXT_mesh_gpu_instancing           required, honoured\n\
             \x20 ACME_not_an_extension             used, ignored\n",
        );
        assert_eq!(describe_extensions(&[]), "extensions      none\n");
    }

    #[test]
    fn lists_every_camera_with_its_index() {
        let mut scene = furnace_scene::builtin::cornell_box().unwrap();
        let n = scene.cameras.len();
        assert!(n >= 1, "the Cornell box has its camera");
        let mut second = scene.cameras[0];
        second.projection = Projection::Orthographic { xmag: 2.0, ymag: 1.5 };
        scene.cameras.push(second);
        let text = describe(&scene);
        assert!(text.contains(&format!("cameras         {}", n + 1)), "{text}");
        assert!(text.contains(&format!("  camera {n}      orthographic, xmag 2, ymag 1.5")), "{text}");
        scene.cameras.clear();
        let text = describe(&scene);
        assert!(text.contains("camera          none in the file; framed around the geometry"), "{text}");
    }
}
