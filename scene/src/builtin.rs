//! Built-in scenes that need no file.

use crate::geometry::{Geometry, oct_encode};
use crate::material::Material;
use crate::{Camera, Scene, SceneError};
use glam::{Vec3, Vec4};

/// The reference Cornell box (`shared/references/cbox/cbox.glb`, see `assets/cbox-README.md`
/// for its conventions), embedded in the binary: the CLI's default scene.
pub const CORNELL_BOX_GLB: &[u8] = include_bytes!("../assets/cbox.glb");

/// The reference Cornell box: 20,516 triangles, Lambert walls, a GGX metal sphere, sun, sky and
/// camera, exactly as the Mitsuba reference renders saw it.
pub fn cornell_box() -> Result<Scene, SceneError> {
    Scene::from_slice(CORNELL_BOX_GLB, "<built-in cbox>")
}

/// A white-furnace scene: a unit sphere at the origin (a UV sphere of `2·n·n` triangles, with
/// exact unit normals as shading normals) made of `material`, sky radiance 1, no sun, and a
/// camera on +Z at distance 4 looking at it with 45° field of view. With an energy-conserving,
/// non-absorbing material every pixel should converge to 1.
pub fn furnace_sphere(material: Material, n: u32) -> Scene {
    let n = n.max(3);
    let mut g = Geometry::default();
    let (rings, segs) = (n, 2 * n);
    for r in 0..=rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..=segs {
            let phi = 2.0 * std::f32::consts::PI * s as f32 / segs as f32;
            let p = Vec3::new(theta.sin() * phi.cos(), theta.cos(), -theta.sin() * phi.sin());
            g.positions.push(p);
            g.normals.push(oct_encode(p));
        }
    }
    let idx = |r: u32, s: u32| r * (segs + 1) + s;
    for r in 0..rings {
        for s in 0..segs {
            let (a, b, c, d) = (idx(r, s), idx(r + 1, s), idx(r + 1, s + 1), idx(r, s + 1));
            if r != 0 {
                g.triangles.push([a, b, d]);
                g.triangle_materials.push(0);
            }
            if r != rings - 1 {
                g.triangles.push([b, c, d]);
                g.triangle_materials.push(0);
            }
        }
    }
    Scene {
        name: "<built-in furnace>".into(),
        geometry: g,
        materials: vec![material, Material::default()],
        textures: Vec::new(),
        images: Vec::new(),
        cameras: vec![Camera::look_at(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, Vec3::Y, crate::DEFAULT_YFOV)],
        sun: None,
        sky: Vec3::ONE,
        warnings: Vec::new(),
        dropped_triangles: 0,
    }
}

/// The Lambert material of albedo `albedo` the reference furnace scenes use: metallic 0 and
/// KHR_materials_specular `specularFactor` 0 (which removes glTF's dielectric layer).
pub fn lambert(albedo: Vec3) -> Material {
    Material {
        base_color_factor: albedo.extend(1.0),
        metallic_factor: 0.0,
        specular_factor: 0.0,
        double_sided: true,
        ..Material::default()
    }
}

/// A GGX metal with base colour 1 (F = 1) and GGX `alpha` (glTF roughness = √alpha).
pub fn metal(alpha: f32) -> Material {
    Material {
        base_color_factor: Vec4::ONE,
        metallic_factor: 1.0,
        roughness_factor: alpha.max(0.0).sqrt(),
        double_sided: true,
        ..Material::default()
    }
}
