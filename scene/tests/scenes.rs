//! Loading real scenes: the reference Cornell box (values checked against the file), textured
//! and PBR-textured models, missing-file errors, and the built-in scenes.

use furnace_scene::{AlphaMode, ColorSpace, Projection, Scene, SceneError, builtin};
use glam::{Vec2, Vec3};
use std::path::{Path, PathBuf};

/// A scene of the workspace's test data (`tests/data/scenes/`).
fn data(p: &str) -> PathBuf {
    furnace_tests::data::scene(p)
}

#[test]
fn cbox_matches_the_file() {
    let s = Scene::load(data("cbox/cbox.gltf")).expect("cbox loads");
    assert_eq!(s.geometry.triangle_count(), 20_516);
    assert_eq!(s.dropped_triangles, 0);
    // Sky: scenes[0].extras.background_radiance_rgb, exactly.
    assert_eq!(s.sky(), Vec3::new(0.35, 0.5, 0.8));
    // Sun: irradiance colour × intensity = (1, 0.95, 0.85) × 3; direction of travel as the
    // file's extras record it (tolerance: f32 quaternion rotation, ~1e-7 per component).
    let sun = *s.sun().expect("a sun");
    assert!((sun.irradiance - Vec3::new(3.0, 2.85, 2.55)).abs().max_element() < 1e-6);
    let travel = Vec3::new(-0.240_007_68, -0.960_030_7, -0.144_004_6);
    assert!((sun.direction - travel).length() < 1e-5, "{:?}", sun.direction);
    // Camera at (0, 1, 3.8) looking at (0, 1, 0), yfov π/4.
    let cam = s.default_camera();
    let Projection::Perspective { yfov, aspect_ratio } = cam.projection else {
        panic!("perspective expected");
    };
    assert_eq!(yfov, std::f32::consts::FRAC_PI_4);
    assert_eq!(aspect_ratio, Some(1.0));
    let centre = cam.generate_ray(Vec2::new(128.0, 128.0), 256, 256);
    assert!((centre.origin - Vec3::new(0.0, 1.0, 3.8)).length() < 1e-6);
    assert!((centre.direction - Vec3::NEG_Z).length() < 1e-6);
    // Row 0 is the top: the ray through the top-centre pixel edge goes up by yfov/2.
    let top = cam.generate_ray(Vec2::new(128.0, 0.0), 256, 256);
    assert!((top.direction.y / -top.direction.z - (yfov / 2.0).tan()).abs() < 1e-6);
    // Materials: Lambert walls (metallic 0, specular 0, two-sided), metal sphere.
    let white = &s.materials[0];
    assert_eq!(white.metallic_factor, 0.0);
    assert_eq!(white.specular_factor, 0.0);
    assert!(white.double_sided);
    assert!(s.materials.iter().any(|m| m.metallic_factor == 1.0));
    assert!(s.geometry.uvs.is_empty(), "no texture: no UVs stored");
    // The embedded GLB is the same scene.
    let b = builtin::cornell_box().expect("built-in cbox");
    assert_eq!(b.geometry, s.geometry);
    assert_eq!((&b.lights, b.cameras.clone()), (&s.lights, s.cameras.clone()));
    println!("cbox: {:?}", s.stats());
}

#[test]
fn box_textured_samples_linear_srgb() {
    for f in ["BoxTextured/glTF/BoxTextured.gltf", "BoxTextured/glTF-Binary/BoxTextured.glb"] {
        let s = Scene::load(data(f)).expect("BoxTextured loads");
        assert_eq!(s.geometry.triangle_count(), 12);
        assert_eq!(s.geometry.uvs.len(), s.geometry.positions.len());
        let m = &s.materials[0];
        let t = m.base_color_texture.expect("base colour texture");
        assert_eq!(t.color_space, ColorSpace::Srgb);
        let img = &s.images[s.textures[t.texture as usize].image as usize];
        // At a texel centre the bilinear lookup is that texel, sRGB-decoded.
        let (x, y) = (img.width / 3, img.height / 2);
        let uv = Vec2::new((x as f32 + 0.5) / img.width as f32, (y as f32 + 0.5) / img.height as f32);
        let raw = img.texels[(y * img.width + x) as usize];
        let got = t.sample_bilinear(uv, &s.textures, &s.images);
        let want = furnace_scene::srgb_to_linear(raw[0] as f32 / 255.0);
        // Tolerance: the lerp weights at a texel centre are exact up to f32 rounding of uv.
        assert!((got.x - want).abs() < 1e-4, "{got} vs {want}");
        let ms = m.evaluate(&furnace_scene::VertexAttributes::from_uv(uv), &s.textures, &s.images);
        assert!(ms.base_color.is_finite());
    }
}

#[test]
fn missing_files_give_clear_errors() {
    // A .gltf whose buffer file is missing names that file.
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("missing-buffer");
    std::fs::create_dir_all(&dir).expect("tmp dir");
    let json = std::fs::read_to_string(data("Box/glTF/Box.gltf")).expect("Box.gltf");
    std::fs::write(dir.join("Box.gltf"), json).expect("write");
    let e = Scene::load(dir.join("Box.gltf")).unwrap_err();
    assert!(matches!(e, SceneError::Io { .. }) && e.to_string().contains("Box0.bin"), "{e}");
    let e = Scene::load(dir.join("nope.gltf")).unwrap_err();
    assert!(e.to_string().contains("nope.gltf"), "{e}");
}

#[test]
fn cameras_file_has_perspective_and_orthographic() {
    let s = Scene::load(data("Cameras/glTF/Cameras.gltf")).expect("Cameras loads");
    assert_eq!(s.cameras.len(), 2);
    assert!(matches!(s.cameras[0].projection, Projection::Perspective { .. }));
    assert!(matches!(s.cameras[1].projection, Projection::Orthographic { .. }));
    let r = s.cameras[1].generate_ray(Vec2::new(0.5, 0.5), 4, 4);
    assert!(r.direction.is_normalized());
}

#[test]
fn damaged_helmet_has_every_texture() {
    let p = data("DamagedHelmet/glTF-Binary/DamagedHelmet.glb");
    let s = Scene::load(p).expect("DamagedHelmet loads");
    assert_eq!(s.geometry.triangle_count(), 15_452);
    let m = &s.materials[0];
    assert!(m.base_color_texture.is_some() && m.metallic_roughness_texture.is_some());
    assert!(m.normal_texture.is_some() && m.emissive_texture.is_some());
    assert_eq!(m.alpha_mode, AlphaMode::Opaque);
    // A normal map needs tangents: one per vertex, unit length, orthogonal to the shading normal
    // (tolerance 2e-3: snorm16 and octahedral quantisation plus f32 Gram–Schmidt).
    let g = &s.geometry;
    assert_eq!(g.tangents.len(), g.positions.len());
    for t in (0..g.triangle_count()).step_by(97) {
        let tangent = g.tangent(t, 0.3, 0.3).expect("tangents present");
        let normal = g.shading_normal(t, 0.3, 0.3).expect("normals present");
        assert!((tangent.truncate().length() - 1.0).abs() < 2e-3 && tangent.w.abs() == 1.0, "{tangent}");
        assert!(tangent.truncate().dot(normal).abs() < 0.05, "triangle {t}: {tangent} vs {normal}");
    }
    println!("DamagedHelmet: {:?}", s.stats());
    for w in &s.warnings {
        println!("  warning: {w}");
    }
}

#[test]
fn large_and_lenient_scenes() {
    let s = Scene::load(data("MetalRoughSpheresNoTextures/glTF-Binary/MetalRoughSpheresNoTextures.glb"))
        .expect("MetalRoughSpheresNoTextures loads");
    println!("MetalRoughSpheresNoTextures: {:?}", s.stats());
    assert!(s.geometry.triangle_count() + s.dropped_triangles >= 1_000_000);
    let s = Scene::load(data("CornellBox-nvpro/cornellBox.gltf"))
        .expect("nvpro loads (emissive 10 warns, does not fail)");
    assert!(!s.warnings.is_empty());
    println!("CornellBox-nvpro: {:?}", s.stats());
}

#[test]
fn furnace_sphere_is_a_closed_unit_sphere() {
    let s = builtin::furnace_sphere(builtin::lambert(Vec3::ONE), 32);
    assert_eq!(s.sky(), Vec3::ONE);
    assert!(s.sun().is_none());
    assert_eq!(s.geometry.triangle_count(), 64 * 62);
    for (i, p) in s.geometry.positions.iter().enumerate() {
        // Tolerance: f32 sin/cos products.
        assert!((p.length() - 1.0).abs() < 1e-6);
        let n = furnace_scene::oct_decode(s.geometry.normals[i]);
        assert!(n.dot(*p) > 0.9999);
    }
    // Outward winding: every geometric normal points away from the centre.
    for t in 0..s.geometry.triangle_count() {
        let [a, b, c] = s.geometry.triangle(t).expect("in range");
        assert!((b - a).cross(c - a).dot(a + b + c) > 0.0, "triangle {t} winds inwards");
    }
}

/// Möller–Trumbore, two-sided: the distance to the triangle along the ray, if it is hit.
fn ray_triangle(o: Vec3, d: Vec3, [a, b, c]: [Vec3; 3]) -> Option<f32> {
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let s = o - a;
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    let t = e2.dot(q) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 1e-4).then_some(t)
}

/// Triangles of `scene` wound against their own shading normals (at the centroid).
fn wound_against_normals(scene: &furnace_scene::Scene) -> Vec<usize> {
    let g = &scene.geometry;
    (0..g.triangle_count())
        .filter(|&t| {
            let [a, b, c] = g.triangle(t).expect("in range");
            g.shading_normal(t, 1.0 / 3.0, 1.0 / 3.0).is_some_and(|n| (b - a).cross(c - a).dot(n) < 0.0)
        })
        .collect()
}

#[test]
fn built_in_scenes_are_wound_as_their_normals_face() {
    let scenes = [
        builtin::cornell_box().unwrap(),
        builtin::furnace_sphere(builtin::lambert(Vec3::ONE), 16),
        builtin::forest(3, 1),
    ];
    for scene in &scenes {
        let bad = wound_against_normals(scene);
        assert!(
            bad.is_empty(),
            "{}: {} triangles wound against their normals, e.g. {:?}",
            scene.name,
            bad.len(),
            &bad[..bad.len().min(4)]
        );
    }
}

#[test]
fn sunlit_interior_has_the_requested_size_and_lets_the_sun_in_only_through_windows() {
    let shell = builtin::sunlit_interior(0);
    let shell_tris = shell.geometry.triangle_count();
    for target in [10_000u32, 100_000, 1_000_000] {
        let s = builtin::sunlit_interior(target);
        let n = s.geometry.triangle_count();
        // Tolerance 5%: sphere tessellation is rounded to whole rings.
        assert!((n as f64 / target as f64 - 1.0).abs() < 0.05, "target {target}: {n} triangles");
        let half = builtin::INTERIOR_ROOM * glam::Vec3::new(0.5, 1.0, 0.5);
        for t in 0..n {
            let [a, b, c] = s.geometry.triangle(t).expect("in range");
            let front = (b - a).cross(c - a);
            assert!(front.length() > 0.0, "target {target}: triangle {t} is degenerate");
            // Wound as its normals face (a double-sided surface seen from its back is shaded with
            // the normal reversed: a floor wound downwards renders black from inside the room).
            let n = s.geometry.shading_normal(t, 1.0 / 3.0, 1.0 / 3.0).expect("normals");
            assert!(front.dot(n) > 0.0, "target {target}: triangle {t} is wound against its normal {n}");
            for p in [a, b, c] {
                // 1e-4 m: f32 rounding of the wall positions.
                assert!(p.abs().cmple(half + 1e-4).all() && p.y >= -1e-4, "{p} outside the room");
            }
        }
        assert!(s.stats().bytes_per_triangle < 40.0, "compact storage");
    }
    // Light enters only through the windows: from a grid of floor points, look towards the sun
    // through the room shell (brute force). Some floor must be sunlit, most must not, and every
    // escaping ray must leave through a window opening in the +x wall.
    let sun = *shell.sun().expect("a sun");
    let to_sun = -sun.direction;
    let walls: Vec<[Vec3; 3]> = (0..shell_tris).filter_map(|t| shell.geometry.triangle(t)).collect();
    let (mut lit, mut total) = (0, 0);
    for i in 0..48 {
        for j in 0..40 {
            let p = Vec3::new(-5.875 + i as f32 * 0.25, 1e-3, -4.875 + j as f32 * 0.25);
            total += 1;
            if walls.iter().all(|&tri| ray_triangle(p, to_sun, tri).is_none()) {
                lit += 1;
                // Where it crosses x = +6, it must be inside a window.
                let t = (6.0 - p.x) / to_sun.x;
                let q = p + t * to_sun;
                assert!(
                    builtin::INTERIOR_WINDOWS
                        .iter()
                        .any(|([za, zb], [ya, yb])| q.z > *za && q.z < *zb && q.y > *ya && q.y < *yb),
                    "light leak at {q}"
                );
            }
        }
    }
    let fraction = lit as f64 / total as f64;
    assert!(fraction > 0.02 && fraction < 0.5, "sunlit floor fraction {fraction}");
}

#[test]
fn scale_lengths_scales_lengths_only() {
    let mut scene = builtin::cornell_box().unwrap();
    let mut ortho = scene.cameras[0];
    ortho.projection = Projection::Orthographic { xmag: 1.5, ymag: 1.0 };
    scene.cameras.push(ortho);
    let before = scene.clone();
    // A power of two: every product is exact, so equality is exact.
    scene.scale_lengths(4.0);
    let g = (&scene.geometry, &before.geometry);
    assert!(g.0.positions.iter().zip(&g.1.positions).all(|(a, b)| *a == 4.0 * *b));
    assert_eq!(g.0.normals, g.1.normals);
    assert_eq!(g.0.tangents, g.1.tangents);
    assert_eq!(g.0.triangles, g.1.triangles);
    for (a, b) in scene.cameras.iter().zip(&before.cameras) {
        assert_eq!(a.world_from_camera.translation, 4.0 * b.world_from_camera.translation);
        assert_eq!(a.world_from_camera.matrix3, b.world_from_camera.matrix3);
    }
    assert_eq!(scene.cameras[0].projection, before.cameras[0].projection);
    assert_eq!(scene.cameras[1].projection, Projection::Orthographic { xmag: 6.0, ymag: 4.0 });
    assert_eq!(scene.lights, before.lights);
    for bad in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        let r = std::panic::catch_unwind(|| builtin::cornell_box().unwrap().scale_lengths(bad));
        assert!(r.is_err(), "scale_lengths({bad}) must refuse");
    }
}

/// MeshPrimitiveModes draws one hexagon per mode: the triangle list, strip and fan each cover
/// the same area, wound the same way (all face the camera), and the four point and line
/// primitives are skipped, each with a warning naming it.
#[test]
fn strips_and_fans_are_triangulated_and_points_and_lines_skipped() {
    let s = Scene::load(data("MeshPrimitiveModes/glTF/MeshPrimitiveModes.gltf")).expect("loads");
    let g = &s.geometry;
    // A list of 18 indices, a strip of 6 and a fan of 8 (6 triangles, 4, 6).
    assert_eq!(g.triangle_count(), 16);
    let triangles: Vec<[Vec3; 3]> = (0..16).map(|t| g.triangle(t).unwrap()).collect();
    let cross = |[a, b, c]: [Vec3; 3]| (b - a).cross(c - a);
    let area = |t: &[[Vec3; 3]]| t.iter().map(|&x| cross(x).length() / 2.0).sum::<f32>();
    let (list, rest) = triangles.split_at(6);
    let (strip, fan) = rest.split_at(4);
    // Relative 1e-5: a sum of a few f32 products of coordinates of order 1.
    for (mode, t) in [("strip", strip), ("fan", fan)] {
        assert!((area(t) / area(list) - 1.0).abs() < 1e-5, "{mode}: {} vs {}", area(t), area(list));
    }
    let facing = cross(list[0]).normalize();
    for (i, &t) in triangles.iter().enumerate() {
        assert!(cross(t).normalize().dot(facing) > 0.999, "triangle {i} is wound the other way");
    }
    let skipped: Vec<&str> = s
        .warnings
        .iter()
        .filter(|w| w.message.contains("points and lines"))
        .map(|w| w.path.as_str())
        .collect();
    assert_eq!(
        skipped,
        [
            "meshes[0].primitives[0]",
            "meshes[1].primitives[0]",
            "meshes[2].primitives[0]",
            "meshes[3].primitives[0]"
        ]
    );
}

/// An image that only a transmission texture samples is decoded (it was left a 1×1
/// placeholder, so the texture read white and the factor alone showed).
#[test]
fn an_image_only_a_transmission_texture_uses_is_decoded() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("transmission-texture");
    std::fs::create_dir_all(&dir).expect("tmp dir");
    let src = data("BoxTextured/glTF");
    for f in ["BoxTextured0.bin", "CesiumLogoFlat.png"] {
        std::fs::copy(src.join(f), dir.join(f)).expect("copy");
    }
    let json = std::fs::read_to_string(src.join("BoxTextured.gltf")).expect("BoxTextured.gltf");
    let json = json.replacen(
        r#""baseColorTexture""#,
        r#""baseColorFactor":[1,1,1,1]},"extensions":{"KHR_materials_transmission":{"transmissionFactor":1,"transmissionTexture":{"index":0}}},"unused":{"x""#,
        1,
    );
    let json = json.replacen(r#""asset""#, r#""extensionsUsed":["KHR_materials_transmission"],"asset""#, 1);
    std::fs::write(dir.join("t.gltf"), json).expect("write");
    let s = Scene::load(dir.join("t.gltf")).expect("loads");
    let m = &s.materials[0];
    assert!(m.base_color_texture.is_none() && m.transmission_texture.is_some(), "{m:?}");
    let image = &s.images[0];
    assert!(image.width > 1 && image.height > 1, "{}×{}", image.width, image.height);
}
