//! Shared meshes placed by instances: what the loader stores, and the CPU's two-level traversal
//! rendering the same image as the scene copied into world space ([`Scene::flattened`], what
//! the GPU renders) from the same samples.

use furnace_cpu::CpuRenderer;
use furnace_render::{Film, RenderSettings};
use furnace_scene::{Light, Scene, Sky};
use glam::{DVec3, Vec3};

fn load(relative: &str) -> Scene {
    Scene::load(furnace_tests::data::scene(relative)).unwrap()
}

fn render(scene: &Scene, settings: RenderSettings, spp: u32) -> Film {
    let cpu = CpuRenderer::with_default_camera(scene.clone(), settings).unwrap();
    let mut film = cpu.new_film();
    cpu.render_into(&mut film, 0, spp).unwrap();
    film
}

/// `EXT_mesh_gpu_instancing`'s 125 cubes are one mesh of 12 triangles placed 125 times; copied
/// into world space they are the 1500 triangles the extension describes, within the same bounds.
#[test]
fn simple_instancing_stores_its_cube_once() {
    let scene = load("SimpleInstancing/glTF/SimpleInstancing.gltf");
    let inst = &scene.instancing;
    assert_eq!((inst.meshes.len(), inst.instances.len()), (1, 125));
    assert_eq!(scene.geometry.triangle_count(), 12);
    assert_eq!(scene.stats().instanced_triangles, 1500);
    let flat = scene.flattened();
    assert_eq!(flat.geometry.triangle_count(), 1500);
    assert!(flat.instancing.is_empty());
    let ((lo, hi), (flo, fhi)) = (scene.bounds(), flat.bounds());
    assert!(
        (lo - flo).abs().max_element() < 1e-5 && (hi - fhi).abs().max_element() < 1e-5,
        "{lo} {hi} vs {flo} {fhi}"
    );
}

/// Per-channel mean of `a − b` over the image, with its standard error (pixels independent).
fn difference(a: &Film, b: &Film, width: u32, height: u32) -> (DVec3, DVec3, f64) {
    let n = f64::from(width * height);
    let (mut sum, mut sq, mut mean_a) = (DVec3::ZERO, DVec3::ZERO, 0.0);
    for y in 0..height {
        for x in 0..width {
            let d = a.pixel(x, y) - b.pixel(x, y);
            sum += d;
            sq += d * d;
            mean_a += a.pixel(x, y).element_sum() / 3.0 / n;
        }
    }
    let mean = sum / n;
    let var = (sq / n - mean * mean) * (n / (n - 1.0));
    (mean, (var / n).map(f64::sqrt), mean_a)
}

/// The instanced scene and its world-space copy, rendered by the CPU from the same samples,
/// agree: the mean difference per channel within 4σ of its standard error (σ from the paired
/// pixel differences: the two renders share their samples, so they differ only where a path
/// takes another turn, and a real difference of the geometry or shading shows at once; 4σ:
/// a false alarm once in 16 000 runs per channel) and below 0.5 % of the image's mean. Scenes:
/// 125 instanced cubes; the nvpro Cornell box (two instances of one box among world triangles,
/// lit by an emissive ceiling kept in world space); NegativeScaleTest (mirroring instances,
/// textures and normal maps, whose frames the instance carries); the scenes without a light of their
/// own under a white sky.
#[test]
fn instanced_and_flattened_scenes_render_alike_on_the_cpu() {
    for (name, spp) in [
        ("SimpleInstancing/glTF/SimpleInstancing.gltf", 16),
        ("CornellBox-nvpro/cornellBox.gltf", 32),
        ("NegativeScaleTest/glTF/NegativeScaleTest.gltf", 16),
    ] {
        let mut scene = load(name);
        assert!(!scene.instancing.is_empty(), "{name}: no instances");
        if !scene.has_own_light() {
            // A white sky (the CLI would add its studio).
            scene.lights.push(Light::Sky(Sky { radiance: Vec3::ONE }));
        }
        let settings = RenderSettings { width: 96, height: 72, bounces: 4, ..RenderSettings::default() };
        let instanced = render(&scene, settings, spp);
        let flat = render(&scene.flattened(), settings, spp);
        assert_eq!(instanced.rejected(), 0, "{name}: NaN or infinite samples");
        let (mean, error, level) = difference(&instanced, &flat, settings.width, settings.height);
        eprintln!("{name}: mean difference {mean:.6} ± {error:.6} of a mean {level:.4}");
        for c in 0..3 {
            assert!(
                mean[c].abs() <= 4.0 * error[c] + 1e-12,
                "{name}: channel {c} differs by {mean} ± {error}"
            );
            assert!(mean[c].abs() <= 5e-3 * level, "{name}: channel {c} differs by {mean} of {level}");
        }
    }
}

/// The GPU bytes `furnace info` states for a scene's BVH ([`furnace_accel::AccelBytes`], from the
/// CPU's structure, without a device) are the bytes the GPU integrator uploads for a flat scene,
/// and for an instanced one its BVHs and TLAS less the identity instance's two TLAS nodes and
/// the instance records (the GPU places its world triangles by an instance of their own). A
/// test of the statement, not of a speed: exact bytes.
#[test]
fn the_stated_gpu_bvh_bytes_are_those_uploaded() {
    let settings = RenderSettings { width: 8, height: 8, ..RenderSettings::default() };
    let flat = furnace_scene::builtin::cornell_box().unwrap();
    let forest = furnace_scene::builtin::forest(4, 2);
    for scene in [&flat, &forest] {
        let stated = CpuRenderer::accel_for(scene).bytes();
        let Some(ctx) = furnace_tests::gpu::test_context() else {
            eprintln!("no GPU adapter (not even a software one): skipped");
            return;
        };
        let gpu = furnace_gpu::GpuRenderer::new(ctx, scene, &scene.default_camera(), settings).unwrap();
        let instances = scene.instancing.instances.len();
        let records = if instances == 0 {
            0
        } else {
            (instances + usize::from(scene.instancing.world_triangles > 0))
                * size_of::<furnace_gpu::traverse::GpuInstance>()
        };
        // One more TLAS leaf (the world's identity instance) adds a leaf and an inner node.
        let world_nodes = if instances > 0 && scene.instancing.world_triangles > 0 {
            2 * size_of::<furnace_accel::TlasNode>()
        } else {
            0
        };
        assert_eq!(
            gpu.bvh_bytes() as usize,
            stated.gpu_bvh + stated.gpu_tlas + world_nodes + records,
            "{}: {stated:?}",
            scene.name
        );
    }
}
