//! Normal maps (glTF `normalTexture` with `scale`, tangents from the file or generated): a
//! Lambert plane whose constant normal map tilts the shading normal by a known angle must
//! shade as `albedo/π · E · max(0, n′·l)` with the tilted normal `n′`, instead of the flat
//! `cos θ_sun`.
//!
//! The scene (written in memory, `furnace_tests::gltf`): a 2 m × 2 m floor at y = 0 facing +Y, with
//! `u` increasing along +x and `v` along +z; a sun 60° from the zenith; a black sky; 1 bounce
//! (direct light only), seen from straight above by an orthographic camera. The normal map is
//! one constant texel, so every pixel has the same value, free of noise: `eval` of a Lambert
//! BRDF is deterministic. The expected tilted normal is computed from the texel as stored
//! (8-bit, linear): `m = (2·rgb/255 − 1)·(scale, scale, 1)` in the frame (T, B, N), with
//!
//! * T = the direction of increasing `u` (+x here), N = +Y;
//! * B = `w · N × T` for a file tangent `(T, w)` (glTF 2.0, meshes: "bitangent vectors MUST be
//!   computed by taking the cross product of the normal and tangent XYZ vectors and multiplying
//!   it against the W component");
//! * B = "up" in the texture image, i.e. the direction of *decreasing* `v` (−z here), for
//!   generated tangents: glTF 2.0, `normalTexture`: "+X is right and +Y is up".

use furnace_tests::gltf;

use furnace_cpu::CpuRenderer;
use furnace_render::RenderSettings;
use furnace_sampling::SamplerKind;
use glam::{DVec3, Vec3, Vec4};
use gltf::{MaterialDesc, Quad, SceneDesc, TopCamera};
use std::f32::consts::PI;

const ALBEDO: f32 = 0.5;
const IRRADIANCE: f32 = 3.0;
const SIZE: u32 = 8;

/// The texel storing the tangent-space normal `m` (unit, z > 0).
fn encode(m: Vec3) -> [u8; 4] {
    let q = |x: f32| ((x * 0.5 + 0.5) * 255.0).round().clamp(0.0, 255.0) as u8;
    [q(m.x), q(m.y), q(m.z), 255]
}

/// The tangent-space normal a texel decodes to, before normalisation, with `scale`.
fn decode(texel: [u8; 4], scale: f32) -> Vec3 {
    let c = |b: u8| 2.0 * f32::from(b) / 255.0 - 1.0;
    Vec3::new(c(texel[0]) * scale, c(texel[1]) * scale, c(texel[2]))
}

/// A normal map case: the texel's normal, the scale, the file's tangent (`None`: generated).
#[derive(Debug, Clone, Copy)]
struct Case {
    name: &'static str,
    normal: Option<Vec3>,
    scale: f32,
    tangent: Option<Vec4>,
    /// Direction the light comes from (unit, towards the sun).
    to_sun: Vec3,
}

impl Case {
    /// The shading normal the glTF conventions give (module docs).
    fn expected_normal(&self) -> Vec3 {
        let Some(m) = self.normal else { return Vec3::Y };
        let m = decode(encode(m), self.scale);
        let (t, b) = match self.tangent {
            Some(t) => (t.truncate(), t.w * Vec3::Y.cross(t.truncate())),
            // Generated: T along +u = +x, B = up in the image = −v = −z.
            None => (Vec3::X, Vec3::NEG_Z),
        };
        (m.x * t + m.y * b + m.z * Vec3::Y).normalize()
    }

    fn expected_radiance(&self) -> f64 {
        f64::from(ALBEDO / PI * IRRADIANCE * self.expected_normal().dot(self.to_sun).max(0.0))
    }

    /// The rendered value of the image (all pixels, which must agree).
    fn render(&self) -> DVec3 {
        let texel = self.normal.map(encode);
        let floor = Quad {
            x: [-1.0, 1.0],
            z: [-1.0, 1.0],
            y: 0.0,
            tangent: self.tangent,
            material: MaterialDesc {
                albedo: Vec3::splat(ALBEDO),
                normal_png: texel.map(|t| (gltf::png(2, 2, |_, _| t), self.scale)),
                ..MaterialDesc::default()
            },
        };
        let desc = SceneDesc {
            quads: vec![floor],
            cameras: vec![TopCamera { position: Vec3::new(0.0, 1.0, 0.0), half_size: 0.5 }],
            sun: Some((-self.to_sun, Vec3::splat(IRRADIANCE))),
            sky: Vec3::ZERO,
        };
        let scene = desc.load(self.name);
        let settings = RenderSettings {
            width: SIZE,
            height: SIZE,
            bounces: 1,
            sampler: SamplerKind::Random,
            seed: 9,
            ..Default::default()
        };
        let renderer = CpuRenderer::with_default_camera(scene, settings).expect("a progressive sampler");
        let mut film = renderer.new_film();
        renderer.render_into(&mut film, 0, 4).expect("render");
        assert_eq!(film.rejected(), 0);
        let first = film.pixel(0, 0);
        for y in 0..SIZE {
            for x in 0..SIZE {
                // The plane, its normal map and the sun are uniform: every pixel is the same up
                // to f32 rounding.
                let d = (film.pixel(x, y) - first).abs().max_element();
                assert!(
                    d <= 1e-6 * first.max_element().max(1e-3),
                    "{}: pixel ({x}, {y}) differs by {d}",
                    self.name
                );
            }
        }
        first
    }
}

/// The sun 60° from the zenith, in the x–y plane on the +x side, or the z–y plane on the −z
/// side.
fn sun_from(direction: Vec3) -> Vec3 {
    let theta = 60f32.to_radians();
    (direction * theta.sin() + Vec3::Y * theta.cos()).normalize()
}

/// A normal tilted by `degrees` from +Z (tangent space) towards tangent-space `axis`.
fn tilted(axis: Vec3, degrees: f32) -> Vec3 {
    let a = degrees.to_radians();
    (axis * a.sin() + Vec3::Z * a.cos()).normalize()
}

/// Renders each case and compares with its expectation; on failure writes the table to
/// `target/test-output/furnace-cpu/<file>.md`.
fn check(file: &str, cases: &[Case]) {
    let mut table = String::from(
        "| case | rendered | expected (tilted normal) | flat `cos θ` would give | relative error |\n|---|---|---|---|---|\n",
    );
    let mut failed = Vec::new();
    let flat = f64::from(ALBEDO / PI * IRRADIANCE);
    for case in cases {
        let got = case.render();
        let expected = case.expected_radiance();
        let err = (got - DVec3::splat(expected)).abs().max_element() / expected.max(1e-3);
        table.push_str(&format!(
            "| {} | {:.5} | {expected:.5} (n′ = {:.4}) | {:.5} | {err:.1e} |\n",
            case.name,
            got.x,
            case.expected_normal(),
            flat * f64::from(case.to_sun.y),
        ));
        // Tolerance 2e-4 relative: the tangent is stored as snorm16 (2⁻¹⁵ ≈ 3e-5 per
        // component) and the normal octahedrally (~1e-5 rad); the cosine of a 60° angle moves
        // by ≤ √3 times that. A wrong frame, sign or scale moves it by ≥ 10% in these cases.
        if !(err < 2e-4) {
            failed.push(case.name);
        }
    }
    println!("{table}");
    if !failed.is_empty() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/test-output/furnace-cpu");
        std::fs::create_dir_all(&dir).expect("an output folder");
        let path = dir.join(format!("{file}.md"));
        std::fs::write(&path, &table).expect("writing the table");
        panic!("{failed:?} do not shade as their tilted normal; table in {}", path.display());
    }
}

/// Generated tangents, the red channel (tangent direction, no handedness involved): tilts
/// towards and away from the sun, with scale 1 and 0.5, and the flat plane without a map.
#[test]
fn normal_map_tilts_lambert_shading_along_the_tangent() {
    let sun = sun_from(Vec3::X);
    let case = |name, normal, scale| Case { name, normal, scale, tangent: None, to_sun: sun };
    check(
        "normal_map_tangent",
        &[
            case("no normal map (flat)", None, 1.0),
            case("flat texel (0.5, 0.5, 1)", Some(Vec3::Z), 1.0),
            case("30° towards the sun", Some(tilted(Vec3::X, 30.0)), 1.0),
            case("30° towards the sun, scale 0.5", Some(tilted(Vec3::X, 30.0)), 0.5),
            case("20° away from the sun", Some(tilted(Vec3::NEG_X, 20.0)), 1.0),
            case("45° away: past the terminator", Some(tilted(Vec3::NEG_X, 45.0)), 1.0),
        ],
    );
}

/// File tangents, the green channel: B = w·N×T, so the sign of `w` decides whether +green
/// tilts towards −z (w = 1) or +z (w = −1). The sun is on the −z side.
#[test]
fn normal_map_bitangent_follows_the_file_tangent_handedness() {
    let sun = sun_from(Vec3::NEG_Z);
    let green = Some(tilted(Vec3::Y, 25.0));
    let case = |name, w| Case {
        name,
        normal: green,
        scale: 1.0,
        tangent: Some(Vec4::new(1.0, 0.0, 0.0, w)),
        to_sun: sun,
    };
    check("normal_map_file_tangent", &[case("+green, w = +1", 1.0), case("+green, w = −1", -1.0)]);
}

/// Generated tangents, the green channel: +green is "up" in the texture image, i.e. towards
/// decreasing `v` (−z here), as a file tangent `(1, 0, 0, w = +1)` says for this plane — the
/// same render with and without the file's tangents.
///
/// Until 2026-11-22 `furnace_scene::generate_tangents` set the handedness so that B pointed along
/// *increasing* `v` (MikkTSpace fed glTF's UVs unflipped — KhronosGroup/glTF-Sample-Models#174,
/// "NormalTangentTest does not work with MikkTSpace (w sign is flipped)"): rendered 0.043 where
/// 0.390 is expected. This test found it.
#[test]
fn normal_map_green_is_up_in_the_image_with_generated_tangents() {
    let sun = sun_from(Vec3::NEG_Z);
    let green = Some(tilted(Vec3::Y, 25.0));
    let case = |name, tangent| Case { name, normal: green, scale: 1.0, tangent, to_sun: sun };
    check(
        "normal_map_generated_bitangent",
        &[
            case("+green, file tangent (1, 0, 0, +1)", Some(Vec4::new(1.0, 0.0, 0.0, 1.0))),
            case("+green, generated tangent", None),
        ],
    );
}
