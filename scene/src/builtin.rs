//! Built-in scenes that need no file.

use crate::geometry::{Geometry, oct_encode};
use crate::material::Material;
use crate::{Camera, Scene, SceneError};
use glam::{Vec3, Vec4};

pub use crate::forest::forest;

/// The reference Cornell box (the scene of the Mitsuba references in the repository's
/// `tests/data/references/cbox/`; `assets/cbox-README.md` gives its conventions), embedded in
/// the binary: the CLI's default scene.
pub const CORNELL_BOX_GLB: &[u8] = include_bytes!("../assets/cbox.glb");

/// The reference Cornell box: 20,516 triangles, Lambert walls, a GGX metal sphere, sun, sky and
/// camera, exactly as the Mitsuba reference renders saw it.
pub fn cornell_box() -> Result<Scene, SceneError> {
    Scene::from_slice(CORNELL_BOX_GLB, "<built-in cbox>")
}

/// A white-furnace scene: a unit sphere at the origin (a UV sphere of `4·n·(n−1)` triangles, with
/// exact unit normals as shading normals) made of `material`, sky radiance 1, no sun, and a
/// camera on +Z at distance 4 looking at it with 45° field of view. With an energy-conserving,
/// non-absorbing material every pixel should converge to 1.
pub fn furnace_sphere(material: Material, n: u32) -> Scene {
    let mut g = Geometry::default();
    push_uv_sphere(&mut g, Vec3::ZERO, 1.0, n.max(3), 0);
    Scene {
        name: "<built-in furnace>".into(),
        geometry: g,
        instancing: Default::default(),
        materials: vec![material, Material::default()],
        textures: Vec::new(),
        images: Vec::new(),
        cameras: vec![Camera::look_at(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, Vec3::Y, crate::DEFAULT_YFOV)],
        lights: vec![crate::Light::Sky(crate::Sky { radiance: Vec3::ONE })],
        warnings: Vec::new(),
        dropped_triangles: 0,
        extensions: Vec::new(),
        variants: Vec::new(),
        animations: Vec::new(),
        posed_by: None,
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

/// A clear dielectric (KHR_materials_transmission 1, KHR_materials_ior `ior`, white) of GGX
/// `alpha` (0: smooth): the surface of a solid (KHR_materials_volume, absorbing `absorption`
/// per metre) when `volume`, else a thin-walled sheet.
pub fn glass(ior: f32, alpha: f32, volume: bool, absorption: Vec3) -> Material {
    Material {
        base_color_factor: Vec4::ONE,
        metallic_factor: 0.0,
        roughness_factor: alpha.max(0.0).sqrt(),
        double_sided: true,
        transmission_factor: 1.0,
        ior,
        volume,
        absorption: if volume { absorption } else { Vec3::ZERO },
        ..Material::default()
    }
}

/// Dimensions of [`sunlit_interior`]'s room in metres (x, y = up, z), centred on x and z with
/// the floor at y = 0.
pub const INTERIOR_ROOM: Vec3 = Vec3::new(12.0, 4.0, 10.0);

/// The window openings of [`sunlit_interior`] in the +x wall, as (z range, y range) in metres.
pub const INTERIOR_WINDOWS: [([f32; 2], [f32; 2]); 3] =
    [([-4.0, -2.5], [1.0, 3.0]), ([-1.0, 1.0], [1.0, 3.0]), ([2.5, 4.0], [1.0, 3.0])];

/// A procedural interior lit only by a sun through windows — the thesis's worst case (its Sun
/// Temple test): almost all light arrives after one or more diffuse bounces from the sunlit
/// patches on the floor, the sky is black, so variance is high and paths are long.
///
/// * A closed room of [`INTERIOR_ROOM`] (single-sided walls, double-sided materials) tessellated
///   into 0.5 m quads (about 3,200 triangles), with the three [`INTERIOR_WINDOWS`] left open in the +x wall.
/// * A grid of UV spheres ("furniture") standing on the floor, whose count and tessellation are
///   chosen so that the whole scene has about `target_triangles` triangles (within a few
///   percent from 10⁴ up to 10⁷; below ~3·10³ the room shell alone is larger). Materials cycle
///   through white, red and green Lambert and a rough metal (GGX α = 0.1).
/// * A sun of irradiance (1000, 950, 850) W/m² travelling along (−1, −0.7, 0.15) (normalised):
///   through the windows onto the floor; a camera in the −x half looking at the window wall.
///
/// The large benchmark scene (Sponza's geometry is not available). Deterministic.
pub fn sunlit_interior(target_triangles: u32) -> Scene {
    let mut g = Geometry::default();
    let half = INTERIOR_ROOM * Vec3::new(0.5, 1.0, 0.5);
    let cell = 0.5f32;
    // One wall: a grid of quads over the rectangle `origin + s·u + t·v`, s ∈ [0, su], t ∈ [0, sv],
    // facing `normal` (shading normal and winding both); `keep(s, t)` (centre of a cell, in metres along u and v) drops window cells.
    let mut wall =
        |origin: Vec3, u: Vec3, v: Vec3, normal: Vec3, material: u32, keep: &dyn Fn(f32, f32) -> bool| {
            let (su, sv) = (u.length(), v.length());
            let (nu, nv) = ((su / cell).round().max(1.0) as u32, (sv / cell).round().max(1.0) as u32);
            for j in 0..nv {
                for i in 0..nu {
                    let (s0, s1) = (i as f32 / nu as f32, (i + 1) as f32 / nu as f32);
                    let (t0, t1) = (j as f32 / nv as f32, (j + 1) as f32 / nv as f32);
                    if !keep((s0 + s1) * 0.5 * su, (t0 + t1) * 0.5 * sv) {
                        continue;
                    }
                    let base = g.positions.len() as u32;
                    for (s, t) in [(s0, t0), (s1, t0), (s1, t1), (s0, t1)] {
                        g.positions.push(origin + s * u + t * v);
                        g.normals.push(oct_encode(normal));
                    }
                    // Wound so that the front face (u × v) is the side `normal` faces.
                    if u.cross(v).dot(normal) > 0.0 {
                        g.triangles.push([base, base + 1, base + 2]);
                        g.triangles.push([base, base + 2, base + 3]);
                    } else {
                        g.triangles.push([base, base + 2, base + 1]);
                        g.triangles.push([base, base + 3, base + 2]);
                    }
                    g.triangle_materials.extend([material, material]);
                }
            }
        };
    let all = |_: f32, _: f32| true;
    let (x0, x1, y1, z0, z1) = (-half.x, half.x, half.y, -half.z, half.z);
    // Floor (y = 0, facing up), ceiling (facing down), walls facing inwards.
    wall(Vec3::new(x0, 0.0, z0), Vec3::X * INTERIOR_ROOM.x, Vec3::Z * INTERIOR_ROOM.z, Vec3::Y, 0, &all);
    wall(Vec3::new(x0, y1, z0), Vec3::X * INTERIOR_ROOM.x, Vec3::Z * INTERIOR_ROOM.z, -Vec3::Y, 0, &all);
    wall(Vec3::new(x0, 0.0, z0), Vec3::Z * INTERIOR_ROOM.z, Vec3::Y * y1, Vec3::X, 0, &all);
    wall(Vec3::new(x0, 0.0, z0), Vec3::X * INTERIOR_ROOM.x, Vec3::Y * y1, Vec3::Z, 1, &all);
    wall(Vec3::new(x0, 0.0, z1), Vec3::X * INTERIOR_ROOM.x, Vec3::Y * y1, -Vec3::Z, 2, &all);
    let outside_windows = |s: f32, t: f32| {
        let z = z0 + s;
        !INTERIOR_WINDOWS.iter().any(|([za, zb], [ya, yb])| z > *za && z < *zb && t > *ya && t < *yb)
    };
    wall(Vec3::new(x1, 0.0, z0), Vec3::Z * INTERIOR_ROOM.z, Vec3::Y * y1, -Vec3::X, 0, &outside_windows);

    // Furniture: a k × k grid of UV spheres (4·n·(n−1) triangles each) filling the rest.
    let shell = g.triangles.len() as u64;
    let remaining = (target_triangles as u64).saturating_sub(shell);
    if remaining > 0 {
        // About 2000 triangles per sphere, at most 100 × 100 spheres.
        let k = ((remaining as f64 / 2000.0).sqrt().ceil() as u32).clamp(1, 100);
        let per_sphere = remaining as f64 / (k * k) as f64;
        // 4n(n−1) = per_sphere  ⇒  n = (1 + √(1 + per_sphere))/2.
        let n = (((1.0 + (1.0 + per_sphere).sqrt()) / 2.0).round() as u32).max(3);
        let pitch = Vec3::new((INTERIOR_ROOM.x - 2.0) / k as f32, 0.0, (INTERIOR_ROOM.z - 2.0) / k as f32);
        let radius = 0.35 * pitch.x.min(pitch.z);
        for a in 0..k {
            for b in 0..k {
                let centre = Vec3::new(
                    x0 + 1.0 + (a as f32 + 0.5) * pitch.x,
                    radius,
                    z0 + 1.0 + (b as f32 + 0.5) * pitch.z,
                );
                push_uv_sphere(&mut g, centre, radius, n, 3 + (a + b) % 4);
            }
        }
    }

    let materials = vec![
        lambert(Vec3::splat(0.75)),
        lambert(Vec3::new(0.7, 0.15, 0.1)),
        lambert(Vec3::new(0.15, 0.6, 0.15)),
        lambert(Vec3::splat(0.75)),
        lambert(Vec3::new(0.7, 0.15, 0.1)),
        lambert(Vec3::new(0.15, 0.6, 0.15)),
        metal(0.1),
        Material::default(),
    ];
    let eye = Vec3::new(x0 + 0.5, 1.6, z1 - 0.5);
    Scene {
        name: format!("<built-in sunlit interior, {} triangles>", g.triangles.len()),
        geometry: g,
        instancing: Default::default(),
        materials,
        textures: Vec::new(),
        images: Vec::new(),
        cameras: vec![Camera::look_at(eye, Vec3::new(x1, 1.2, -1.0), Vec3::Y, 1.0)],
        lights: vec![crate::Light::Sun(crate::Sun::delta(
            Vec3::new(-1.0, -0.7, 0.15).normalize(),
            Vec3::new(1000.0, 950.0, 850.0),
        ))],
        warnings: Vec::new(),
        dropped_triangles: 0,
        extensions: Vec::new(),
        variants: Vec::new(),
        animations: Vec::new(),
        posed_by: None,
    }
}

/// Appends a UV sphere of `4·n·(n−1)` triangles (`n` rings, `2n` segments, poles as fans)
/// with exact normals.
fn push_uv_sphere(g: &mut Geometry, centre: Vec3, radius: f32, n: u32, material: u32) {
    let (rings, segs) = (n, 2 * n);
    let base = g.positions.len() as u32;
    for r in 0..=rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..=segs {
            let phi = 2.0 * std::f32::consts::PI * s as f32 / segs as f32;
            let dir = Vec3::new(theta.sin() * phi.cos(), theta.cos(), -theta.sin() * phi.sin());
            g.positions.push(centre + radius * dir);
            g.normals.push(oct_encode(dir));
        }
    }
    let idx = |r: u32, s: u32| base + r * (segs + 1) + s;
    for r in 0..rings {
        for s in 0..segs {
            let (a, b, c, d) = (idx(r, s), idx(r + 1, s), idx(r + 1, s + 1), idx(r, s + 1));
            if r != 0 {
                g.triangles.push([a, b, d]);
                g.triangle_materials.push(material);
            }
            if r != rings - 1 {
                g.triangles.push([b, c, d]);
                g.triangle_materials.push(material);
            }
        }
    }
}
