//! Texture formats beyond PNG and JPEG (`tests/data/scenes/gltf-transform-textures/`, one 40 × 40
//! picture in several KTX2 encodings, a WebP and an AVIF): each decodes to the expected size and
//! colours; the colour space follows the slot that uses the image; an image that cannot be used
//! is a warning (an error when loading strictly); corrupt payloads are errors, never panics.

use furnace_scene::{Image, LoadOptions, Scene, SceneError};
use std::path::PathBuf;

const STRICT: LoadOptions = LoadOptions { strict: true, variant: None, animation: None, time: None };

fn file(name: &str) -> PathBuf {
    furnace_tests::data::scene("gltf-transform-textures").join(name)
}

fn load(name: &str) -> Scene {
    Scene::load_with(file(name), &STRICT).unwrap_or_else(|e| panic!("{e}"))
}

fn warnings(scene: &Scene) -> String {
    scene.warnings.iter().map(ToString::to_string).collect::<Vec<_>>().join("\n")
}

/// The image the base colour of material 0 samples.
fn base_color(scene: &Scene) -> &Image {
    let r = scene.materials[0].base_color_texture.expect("a base colour texture");
    &scene.images[scene.textures[r.texture as usize].image as usize]
}

/// The R8G8B8A8_SRGB picture, stored as the file has it.
fn reference() -> Image {
    base_color(&load("ktx2_rgba8.gltf")).clone()
}

/// The most common texel (the picture's flat background).
fn background(img: &Image) -> [u8; 4] {
    let mut counts = std::collections::HashMap::new();
    for t in &img.texels {
        *counts.entry(*t).or_insert(0) += 1;
    }
    counts.into_iter().max_by_key(|&(t, n)| (n, t)).unwrap().0
}

/// How many texels lie within `tol` of `colour` in every channel.
fn near(img: &Image, colour: [u8; 4], tol: u8) -> usize {
    img.texels.iter().filter(|t| (0..4).all(|c| t[c].abs_diff(colour[c]) <= tol)).count()
}

/// Each 2d_*.ktx2 is a 40 × 40 flat colour with a white label naming its encoding: the flat
/// colour decodes to the picture's (exactly for the uncompressed encodings, within the codec's
/// error `tol` for the others), most texels have it (within `spread`: blocks that share the
/// label's pixels are coded with compromise colours), and the label is there.
fn check_picture(name: &str, colour: [u8; 4], tol: u8, spread: u8) -> Image {
    let s = load(name);
    assert_eq!(warnings(&s), "", "{name}");
    let img = base_color(&s).clone();
    assert_eq!((img.width, img.height), (40, 40), "{name}");
    let bg = background(&img);
    assert!(
        (0..4).all(|c| bg[c].abs_diff(colour[c]) <= tol),
        "{name}: background {bg:?}, expected {colour:?} ± {tol}"
    );
    // The label covers less than a third of the picture.
    let flat = near(&img, colour, spread);
    assert!(flat > 1600 * 2 / 3, "{name}: {flat} texels of the background colour");
    // The label: texels much brighter than the background (white, or near it after
    // compression).
    let sum = |t: &[u8; 4]| u32::from(t[0]) + u32::from(t[1]) + u32::from(t[2]);
    let label = img.texels.iter().filter(|t| sum(t) > sum(&colour) + 150).count();
    assert!(label >= 20, "{name}: {label} label texels");
    img
}

/// Uncompressed KTX2: R8G8B8A8 and R8G8B8 (sRGB transfer) are stored exactly as the file has
/// them, for the sRGB base-colour slot; the linear R16G16B16A16 and R32G32B32A32 SFLOAT encodings
/// of the same green are sRGB-encoded for that slot and give it back: ±1 for the half floats'
/// 11-bit mantissa and the 8-bit rounding, both below one 8-bit step.
#[test]
fn uncompressed_ktx2_decodes_exactly() {
    let green = [77, 175, 74, 255];
    check_picture("ktx2_rgba8.gltf", green, 0, 0);
    check_picture("ktx2_rgb8.gltf", green, 0, 0);
    check_picture("ktx2_rgba16_linear.gltf", green, 1, 1);
    check_picture("ktx2_rgba32_linear.gltf", green, 1, 1);
}

/// Block-compressed KTX2 (texture2ddecoder) and Basis Universal (Binomial's transcoder). BC1's
/// endpoints are RGB565: a flat colour is within half a 5-bit step (255 / 31 / 2 ≈ 4 codes) of
/// the source; BC7 and ASTC 4×4 at their block rates reproduce a flat colour within 2 codes
/// (4 in the blocks that also hold the label). The
/// Basis pictures (gold) have no uncompressed twin: UASTC (near-lossless on a flat colour,
/// ±2) and ETC1S decodes agree within ETC1S's error, whose base colours are 5-bit per channel
/// (8 codes); its endpoint codebook is shared between blocks, so the blocks beside the label take
/// colours up to 20 codes off (seen in its decode: the label's surroundings are blotchy).
#[test]
fn compressed_ktx2_and_basis_universal_decode() {
    let orange = [255, 127, 0, 255];
    check_picture("ktx2_bc1.gltf", orange, 4, 4);
    check_picture("ktx2_bc7.gltf", orange, 2, 4);
    check_picture("ktx2_astc4x4.gltf", [55, 126, 184, 255], 2, 4);
    let uastc = check_picture("basisu_uastc.gltf", [185, 151, 0, 255], 2, 4);
    let etc1s = check_picture("basisu_etc1s.gltf", background(&uastc), 8, 20);
    assert_ne!(etc1s, uastc, "two encodings, two decodes");
}

/// The slot decides the colour space, whatever the file says: the sRGB R8G8B8A8 image as a
/// metallic-roughness texture keeps its bytes, with a warning that its transfer function says
/// sRGB; the linear float image there is stored as plain values (not sRGB-encoded), so that the
/// linear slot reads back the file's values.
#[test]
fn the_slot_decides_the_colour_space() {
    let dir = furnace_tests::data::output_dir("scene/textures");
    for (gltf, image) in
        [("ktx2_rgba8.gltf", "2d_rgba8.ktx2"), ("ktx2_rgba32_linear.gltf", "2d_rgba32_linear.ktx2")]
    {
        std::fs::copy(file(image), dir.join(image)).unwrap();
        let json = std::fs::read_to_string(file(gltf))
            .unwrap()
            .replace("baseColorTexture", "metallicRoughnessTexture");
        std::fs::write(dir.join(gltf), json).unwrap();
    }
    let s = Scene::load_with(dir.join("ktx2_rgba8.gltf"), &STRICT).unwrap();
    let w = warnings(&s);
    assert!(w.contains("images[0]") && w.contains("marked sRGB") && w.contains("read as linear"), "{w}");
    assert_eq!(&s.images[0], &reference());

    let s = Scene::load_with(dir.join("ktx2_rgba32_linear.gltf"), &STRICT).unwrap();
    assert_eq!(warnings(&s), "");
    let linear = background(&s.images[0]);
    // The green's linear value: sRGB-decoded 77, 175, 74 (0.0742, 0.4287, 0.0685), × 255 and
    // rounded: 19, 109, 17 (± 1, the 8-bit rounding of the file's floats).
    let expected = [77u8, 175, 74].map(|v| furnace_scene::srgb_to_linear(f32::from(v) / 255.0) * 255.0);
    for c in 0..3 {
        assert!((f32::from(linear[c]) - expected[c]).abs() <= 1.0, "{linear:?} against {expected:?}");
    }
}

/// WebP through EXT_texture_webp: a 256 × 256 photograph whose top is a pale sky and whose
/// middle rows are dark.
#[test]
fn webp_decodes() {
    let s = load("webp.gltf");
    assert_eq!(warnings(&s), "");
    let img = base_color(&s);
    assert_eq!((img.width, img.height), (256, 256));
    let mean_row = |y: usize| {
        let row = &img.texels[y * 256..(y + 1) * 256];
        row.iter().map(|t| u32::from(t[0]) + u32::from(t[1]) + u32::from(t[2])).sum::<u32>() / (3 * 256)
    };
    assert!(mean_row(10) > 150, "sky {}", mean_row(10));
    assert!(mean_row(150) < 80, "dark band {}", mean_row(150));
}

/// EXT_texture_avif required: refused, naming the texture, the image and the extension. Only
/// used: its fallback `source` is decoded, with a warning naming the AVIF image.
#[test]
fn avif_is_refused_when_required_and_falls_back_when_used() {
    let e = Scene::load(file("avif_required.gltf")).unwrap_err();
    assert!(matches!(e, SceneError::UnsupportedExtension { .. }), "{e}");
    let e = e.to_string();
    assert!(
        e.contains("textures[0].extensions.EXT_texture_avif") && e.contains("images[0] 'test.avif'"),
        "{e}"
    );
    let s = load("avif_fallback.gltf");
    let w = warnings(&s);
    assert!(w.contains("textures[0].extensions.EXT_texture_avif") && w.contains("images[1]"), "{w}");
    assert_eq!(base_color(&s), &reference());
}

/// A missing image file: a warning naming the file, `images[0]` and the reason, and the
/// material without its texture (its factors alone); with `strict`, an error.
#[test]
fn a_missing_texture_is_a_warning_unless_strict() {
    let s = Scene::load(file("missing_texture.gltf")).unwrap();
    let w = warnings(&s);
    assert!(w.contains("images[0]") && w.contains("no-such-texture.png") && w.contains("left out"), "{w}");
    assert_eq!(s.materials[0].base_color_texture, None);
    let e = Scene::load_with(file("missing_texture.gltf"), &STRICT).unwrap_err();
    assert!(matches!(e, SceneError::Io { .. }), "{e}");
    assert!(e.to_string().contains("images[0]") && e.to_string().contains("no-such-texture.png"), "{e}");
}

/// A small deterministic generator (xorshift64*), for the corruptions.
struct Rng(u64);

impl Rng {
    fn below(&mut self, n: usize) -> usize {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 33) as usize % n.max(1)
    }
}

/// A glTF of the textured quad `gltf` with its image embedded as a data URI of `bytes`.
fn with_embedded_image(gltf: &str, uri: &str, bytes: &[u8]) -> String {
    gltf.replace(
        &format!("\"uri\": \"{uri}\""),
        &format!("\"uri\": \"data:image/x;base64,{}\"", base64::encode(bytes)),
    )
}

/// Truncated and bit-flipped payloads of every encoding (a fixed seed, 150 of each): loading
/// strictly gives the scene or an image error naming `images[0]` and the format's extension
/// path where there is one, never a panic; loading leniently always gives the scene.
#[test]
fn corrupt_payloads_are_errors_not_panics() {
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    for (gltf, uri) in [
        ("basisu_etc1s.gltf", "2d_etc1s.ktx2"),
        ("basisu_uastc.gltf", "2d_uastc.ktx2"),
        ("ktx2_rgba8.gltf", "2d_rgba8.ktx2"),
        ("ktx2_rgb8.gltf", "2d_rgb8.ktx2"),
        ("ktx2_rgba16_linear.gltf", "2d_rgba16_linear.ktx2"),
        ("ktx2_rgba32_linear.gltf", "2d_rgba32_linear.ktx2"),
        ("ktx2_bc1.gltf", "2d_bc1.ktx2"),
        ("ktx2_bc7.gltf", "2d_bc7.ktx2"),
        ("ktx2_astc4x4.gltf", "2d_astc4x4.ktx2"),
        ("webp.gltf", "test-lossy.webp"),
    ] {
        let json = std::fs::read_to_string(file(gltf)).unwrap();
        let payload = std::fs::read(file(uri)).unwrap();
        for i in 0..150 {
            let mut bytes = payload.clone();
            if i % 2 == 0 {
                bytes.truncate(rng.below(bytes.len()));
            }
            for _ in 0..1 + rng.below(8) {
                let at = rng.below(bytes.len());
                if let Some(b) = bytes.get_mut(at) {
                    *b ^= 1 << rng.below(8);
                }
            }
            let mutant = with_embedded_image(&json, uri, &bytes);
            match Scene::from_slice_with(mutant.as_bytes(), gltf, &STRICT) {
                Ok(_) => {}
                Err(SceneError::Image { path, .. }) => assert_eq!(path, "images[0]"),
                Err(e) => panic!("{gltf} mutant {i}: {e}"),
            }
            assert!(Scene::from_slice(mutant.as_bytes(), gltf).is_ok(), "{gltf} mutant {i}");
        }
    }
}
