//! Textures: 8-bit RGBA images, glTF samplers (wrap modes), KHR_texture_transform, and a bilinear
//! lookup that decodes sRGB to linear *before* filtering (filtering encoded values would darken
//! edges).

use crate::VertexAttributes;
use glam::{Mat3, Vec2, Vec3, Vec4};
use std::sync::OnceLock;

/// The most texels a texture may have along each side: 16384, the largest 2D texture most GPUs
/// take, so 2²⁸ texels (1 GiB of RGBA8) at most. The loader refuses a larger image from its
/// header, before decoding it.
pub const MAX_TEXTURE_SIZE: u32 = 16384;

/// An image decoded to 8-bit RGBA, row 0 at the top (glTF's UV (0, 0) is the top-left corner).
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    /// Width in texels (≥ 1).
    pub width: u32,
    /// Height in texels (≥ 1).
    pub height: u32,
    /// `width × height` texels, row-major, as stored in the file (sRGB or linear: the slot that
    /// uses the image decides, see [`ColorSpace`]).
    pub texels: Vec<[u8; 4]>,
}

/// How a sampler repeats the image outside `[0, 1]`, glTF's `wrapS`/`wrapT`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum WrapMode {
    /// `REPEAT` (10497), glTF's default.
    #[default]
    Repeat,
    /// `CLAMP_TO_EDGE` (33071).
    ClampToEdge,
    /// `MIRRORED_REPEAT` (33648).
    MirroredRepeat,
}

impl WrapMode {
    /// Maps texel index `i` (any integer) into `0..n`.
    fn apply(self, i: i64, n: u32) -> usize {
        let n = i64::from(n.max(1));
        let j = match self {
            Self::Repeat => i.rem_euclid(n),
            Self::ClampToEdge => i.clamp(0, n - 1),
            Self::MirroredRepeat => {
                let m = i.rem_euclid(2 * n);
                if m < n { m } else { 2 * n - 1 - m }
            }
        };
        j as usize
    }
}

/// A glTF texture: an image and how to wrap it. Filtering is always bilinear (glTF's filters
/// are hints; a path tracer's pixel integration removes most aliasing anyway).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Texture {
    /// Index into [`crate::Scene::images`].
    pub image: u32,
    /// Horizontal wrap mode (`wrapS`).
    pub wrap_s: WrapMode,
    /// Vertical wrap mode (`wrapT`).
    pub wrap_t: WrapMode,
}

/// How a texture slot's 8-bit values encode colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ColorSpace {
    /// sRGB transfer function on RGB (base colour, emissive, specular colour); alpha is linear.
    Srgb,
    /// Plain values / 255 (metallic-roughness, normal, occlusion).
    Linear,
}

/// KHR_texture_transform: `uv' = T · R · S · uv` with `R` (rows) `[[cos r, sin r], [−sin r, cos r]]`:
/// "counter-clockwise" in glTF's V-down UV space, as Babylon.js, three.js, Blender and the
/// TextureTransformTest sample agree (the extension's GLSL listing reads the other way when taken
/// as column-major; see KhronosGroup/glTF issue #1563).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TextureTransform {
    /// Translation `(tx, ty)`.
    pub offset: Vec2,
    /// Rotation `r` in radians (counter-clockwise in UV space).
    pub rotation: f32,
    /// Scale `(sx, sy)`.
    pub scale: Vec2,
}

impl TextureTransform {
    /// The 3×3 matrix `T · R · S`, as the extension's specification writes it.
    pub fn matrix(&self) -> Mat3 {
        let (s, c) = self.rotation.sin_cos();
        let t = Mat3::from_cols(Vec3::X, Vec3::Y, Vec3::new(self.offset.x, self.offset.y, 1.0));
        // Column-major: column 0 = (cos, −sin), column 1 = (sin, cos).
        let r = Mat3::from_cols(Vec3::new(c, -s, 0.0), Vec3::new(s, c, 0.0), Vec3::Z);
        let sc = Mat3::from_diagonal(Vec3::new(self.scale.x, self.scale.y, 1.0));
        t * r * sc
    }

    /// Applies the transform to `uv`.
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        (self.matrix() * uv.extend(1.0)).truncate()
    }
}

/// A material's use of a texture: which texture, in which colour space, with which transform.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TextureRef {
    /// Index into [`crate::Scene::textures`].
    pub texture: u32,
    /// The UV set (`texCoord`, possibly overridden by KHR_texture_transform), below
    /// [`crate::MAX_UV_SETS`] (the loader reads a higher one as set 0, with a warning).
    pub tex_coord: u32,
    /// How the slot encodes colour.
    pub color_space: ColorSpace,
    /// KHR_texture_transform, when present.
    pub transform: Option<TextureTransform>,
}

/// The sRGB → linear table for 8-bit values (IEC 61966-2-1).
fn srgb_table() -> &'static [f32; 256] {
    static TABLE: OnceLock<[f32; 256]> = OnceLock::new();
    TABLE.get_or_init(|| {
        let mut t = [0.0; 256];
        for (i, v) in t.iter_mut().enumerate() {
            *v = srgb_to_linear(i as f32 / 255.0);
        }
        t
    })
}

/// The exact sRGB electro-optical transfer function (IEC 61966-2-1): furnace-post's, the one
/// implementation (textures are decoded with it, images encoded with its inverse).
pub use furnace_post::srgb_to_linear;

impl Image {
    /// Texel `(x, y)` decoded to linear RGBA (alpha is always linear).
    fn texel(&self, x: usize, y: usize, space: ColorSpace) -> Vec4 {
        let i = y * self.width as usize + x;
        let Some(&[r, g, b, a]) = self.texels.get(i) else {
            return Vec4::ZERO;
        };
        let alpha = f32::from(a) / 255.0;
        match space {
            ColorSpace::Srgb => {
                let t = srgb_table();
                Vec4::new(t[r as usize], t[g as usize], t[b as usize], alpha)
            }
            ColorSpace::Linear => {
                Vec4::new(f32::from(r) / 255.0, f32::from(g) / 255.0, f32::from(b) / 255.0, alpha)
            }
        }
    }

    /// Bilinear lookup at `uv` (texel centres at `(i + ½)/width`), wrapping with `wrap_s` /
    /// `wrap_t`, decoding `space` to linear before filtering. Returns linear RGBA. A NaN or
    /// infinite `uv` gives texel (0, 0) rather than a panic.
    pub fn sample_bilinear(&self, uv: Vec2, wrap_s: WrapMode, wrap_t: WrapMode, space: ColorSpace) -> Vec4 {
        let uv = if uv.is_finite() { uv } else { Vec2::ZERO };
        let x = uv.x as f64 * f64::from(self.width) - 0.5;
        let y = uv.y as f64 * f64::from(self.height) - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
        // Clamp before converting so that huge UVs stay in i64 range.
        let (x0, y0) = (x0.clamp(-1e15, 1e15) as i64, y0.clamp(-1e15, 1e15) as i64);
        let xa = wrap_s.apply(x0, self.width);
        let xb = wrap_s.apply(x0 + 1, self.width);
        let ya = wrap_t.apply(y0, self.height);
        let yb = wrap_t.apply(y0 + 1, self.height);
        let top = self.texel(xa, ya, space).lerp(self.texel(xb, ya, space), fx);
        let bottom = self.texel(xa, yb, space).lerp(self.texel(xb, yb, space), fx);
        top.lerp(bottom, fy)
    }
}

impl TextureRef {
    /// Samples this slot at a shading point: at its UV set of `at` (see
    /// [`TextureRef::sample_bilinear`]).
    pub fn sample(&self, at: &VertexAttributes, textures: &[Texture], images: &[Image]) -> Vec4 {
        let uv = at.uv.get(self.tex_coord as usize).copied().unwrap_or(at.uv[0]);
        self.sample_bilinear(uv, textures, images)
    }

    /// Samples this slot at `uv` (its UV set's, before KHR_texture_transform): applies the
    /// transform, the texture's wrap modes and the slot's colour space. Returns linear RGBA, or
    /// opaque white when the texture or image index is out of range (cannot happen for a scene
    /// built by this crate).
    pub fn sample_bilinear(&self, uv: Vec2, textures: &[Texture], images: &[Image]) -> Vec4 {
        let uv = match &self.transform {
            Some(t) => t.apply(uv),
            None => uv,
        };
        let Some(tex) = textures.get(self.texture as usize) else {
            return Vec4::ONE;
        };
        let Some(img) = images.get(tex.image as usize) else {
            return Vec4::ONE;
        };
        img.sample_bilinear(uv, tex.wrap_s, tex.wrap_t, self.color_space)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checker() -> Image {
        // 2×2: black, white / white, black.
        Image {
            width: 2,
            height: 2,
            texels: vec![[0, 0, 0, 255], [255, 255, 255, 255], [255, 255, 255, 255], [0, 0, 0, 255]],
        }
    }

    #[test]
    fn texel_centres_are_exact_and_midpoints_average() {
        let img = checker();
        let s =
            |u, v| img.sample_bilinear(Vec2::new(u, v), WrapMode::Repeat, WrapMode::Repeat, ColorSpace::Srgb);
        // Texel centres return the texel itself (within f32 rounding of the lerp weights).
        assert!((s(0.25, 0.25) - Vec4::new(0.0, 0.0, 0.0, 1.0)).abs().max_element() < 1e-6);
        assert!((s(0.75, 0.25) - Vec4::ONE).abs().max_element() < 1e-6);
        // The centre of the image mixes the four texels equally, in linear space: 0.5, not
        // the sRGB-encoded 0.5 (= 0.214 linear) a filter-then-decode lookup would give.
        assert!((s(0.5, 0.5).x - 0.5).abs() < 1e-6);
    }

    #[test]
    fn wrap_modes() {
        assert_eq!(WrapMode::Repeat.apply(-1, 4), 3);
        assert_eq!(WrapMode::Repeat.apply(5, 4), 1);
        assert_eq!(WrapMode::ClampToEdge.apply(-3, 4), 0);
        assert_eq!(WrapMode::ClampToEdge.apply(9, 4), 3);
        assert_eq!(WrapMode::MirroredRepeat.apply(4, 4), 3);
        assert_eq!(WrapMode::MirroredRepeat.apply(-1, 4), 0);
        assert_eq!(WrapMode::MirroredRepeat.apply(8, 4), 0);
    }

    #[test]
    fn srgb_decode_matches_the_standard() {
        // 0.5 encoded is 0.21404 linear (IEC 61966-2-1); tolerance is f32 powf rounding.
        assert!((srgb_to_linear(0.5) - 0.214_041_14).abs() < 1e-6);
        assert_eq!(srgb_table()[255], 1.0);
        assert_eq!(srgb_table()[0], 0.0);
    }

    #[test]
    fn texture_transform_follows_the_extension() {
        // The extension's example: rotate a quarter turn, then offset. (1, 0) ↦ R·(1,0) = (0, −1)
        // (column 0 of R is (cos, −sin)), + (0, 1) = (0, 0).
        let t = TextureTransform {
            offset: Vec2::new(0.0, 1.0),
            rotation: std::f32::consts::FRAC_PI_2,
            scale: Vec2::ONE,
        };
        // Tolerance: sin/cos of π/2 in f32 leave ~1e-7.
        assert!((t.apply(Vec2::new(1.0, 0.0)) - Vec2::new(0.0, 0.0)).abs().max_element() < 1e-6);
        let s = TextureTransform { offset: Vec2::ZERO, rotation: 0.0, scale: Vec2::new(2.0, 3.0) };
        assert_eq!(s.apply(Vec2::new(0.5, 0.5)), Vec2::new(1.0, 1.5));
    }

    #[test]
    fn non_finite_uv_does_not_panic() {
        let img = checker();
        for uv in [Vec2::NAN, Vec2::INFINITY, Vec2::splat(1e30), Vec2::splat(-1e30)] {
            let v = img.sample_bilinear(uv, WrapMode::MirroredRepeat, WrapMode::Repeat, ColorSpace::Linear);
            assert!(v.is_finite());
        }
    }
}
