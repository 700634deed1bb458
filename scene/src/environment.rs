//! Environment maps: radiance at infinity from a latitude-longitude HDR image
//! ([`EnvironmentMap`]), placed in the world by an [`Environment`] light (intensity, rotation
//! about +Y, whether the camera sees it), and its importance sampling ([`EnvironmentSampler`]).
//!
//! The direction → texel rule is the references' (`../shared/references/README.md`, "Environment
//! map"): `u = atan2(d.x, −d.z)/2π` (0 = −Z, ¼ = +X), `v = acos(d.y)/π` (0 = +Y), a bilinear
//! lookup **texel-centred** in both axes, columns wrapping, rows clamped to the edge.
//!
//! Sampling follows the map's cells (texel `(i, j)` covers `u ∈ [i, i+1]/W`, `v ∈ [j, j+1]/H`):
//! a [`Distribution2D`] over cells weighted by the average of the bilinear lookup's luminance
//! over the cell times the average of `sin θ` over its row, so that every direction whose
//! radiance is not zero has a positive pdf; a direction's solid-angle pdf is the cell's density
//! on the square divided by the Jacobian `2π² sin θ`. With MIS compensation (Karlík et al.
//! 2019) the weights are the luminance **minus its mean** over the sphere, clamped at 0: the
//! environment's dim part is left to BSDF sampling, which MIS combines with it; only valid under
//! MIS (a light-only estimator would miss the dim part).

use crate::luminance;
use furnace_sampling::Distribution2D;
use glam::{Vec2, Vec3};
use std::f64::consts::PI as PI64;
use std::path::Path;
use std::sync::Arc;

/// Why an environment map could not be read.
#[derive(Debug, thiserror::Error)]
pub enum EnvironmentError {
    /// The file could not be read.
    #[error("{file}: cannot read the environment map: {source}")]
    Io {
        /// The map's file.
        file: String,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The file is not an image `image` can decode (`.hdr`, `.exr`, …) or is corrupt.
    #[error("{file}: cannot decode the environment map: {message}")]
    Decode {
        /// The map's file.
        file: String,
        /// The decoder's message.
        message: String,
    },
    /// A texel is NaN or infinite: the map is broken, and guessing a value would bias every
    /// image lit by it.
    #[error(
        "{file}: texel ({x}, {y}) (column, row from the top) has {channel} = {value}: an environment map \
         must hold finite radiance ({count} such texels)"
    )]
    NonFinite {
        /// The map's file.
        file: String,
        /// Column of the first such texel.
        x: u32,
        /// Row of the first such texel (0 at the top).
        y: u32,
        /// `R`, `G` or `B`.
        channel: char,
        /// Its value.
        value: f32,
        /// How many texels are not finite.
        count: usize,
    },
    /// The map has no texels, or more than the renderer indexes.
    #[error("{file}: an environment map of {width} × {height} texels: {message}")]
    Size {
        /// The map's file.
        file: String,
        /// Its width.
        width: u32,
        /// Its height.
        height: u32,
        /// What is wrong.
        message: &'static str,
    },
}

/// Most texels a map may have: 2²⁸ (a 23 170² map; 16384 × 8192 is 2²⁷), so that the GPU's
/// `u32` word indices into its texels and CDFs (4 words per texel) cannot overflow.
pub const MAX_ENVIRONMENT_TEXELS: u64 = 1 << 28;

/// The most texels a map's file may claim per byte of its length: 4096. The best compression
/// of the formats read stays well below it (OpenEXR's deflate at most 1032:1 on 6-byte half RGB
/// texels, about 170 texels a byte, PIZ's run-length codes on constant data about a thousand;
/// Radiance RLE at most 127 texels per 8 bytes), so only a header that lies about the size (or
/// a truncated file) is refused, before its texels are allocated: a 441-byte EXR claiming
/// 4 × 5·10⁷ texels would otherwise cost gigabytes.
const MAX_TEXELS_PER_BYTE: u64 = 4096;

/// A latitude-longitude HDR image of radiance: `width` columns × `height` rows, row 0 at the top
/// (+Y), linear RGB in W/(m²·sr).
#[derive(Clone, PartialEq)]
pub struct EnvironmentMap {
    width: u32,
    height: u32,
    texels: Vec<Vec3>,
    source: String,
}

impl std::fmt::Debug for EnvironmentMap {
    /// The size only: the content hash reads this and the texels themselves, and, as a scene's
    /// name, where a map came from is not its content (the same file by another path is the
    /// same light).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "EnvironmentMap({}×{})", self.width, self.height)
    }
}

impl EnvironmentMap {
    /// A map of `width × height` texels (row-major, row 0 at the top) read from `source` (a file
    /// name, for messages). Negative texels (the undershoot of resampling filters) are clamped
    /// to 0 and counted in the returned warning; NaN and infinite ones are an error naming the
    /// first.
    ///
    /// # Errors
    /// [`EnvironmentError::Size`] for an empty map or one of more than
    /// [`MAX_ENVIRONMENT_TEXELS`], [`EnvironmentError::NonFinite`].
    pub fn new(
        width: u32,
        height: u32,
        mut texels: Vec<Vec3>,
        source: impl Into<String>,
    ) -> Result<(Self, Option<String>), EnvironmentError> {
        let source = source.into();
        let n = u64::from(width) * u64::from(height);
        let size_error = |message| EnvironmentError::Size { file: source.clone(), width, height, message };
        if n == 0 {
            return Err(size_error("it has no texels"));
        }
        if n > MAX_ENVIRONMENT_TEXELS {
            return Err(size_error("more than 2²⁸ texels"));
        }
        if texels.len() as u64 != n {
            return Err(size_error("the texel count does not match the size"));
        }
        let bad = texels.iter().filter(|t| !t.is_finite()).count();
        if let Some(k) = texels.iter().position(|t| !t.is_finite()) {
            let t = texels[k];
            let c = (0..3).find(|&c| !t[c].is_finite()).unwrap_or(0);
            return Err(EnvironmentError::NonFinite {
                file: source,
                x: (k % width as usize) as u32,
                y: (k / width as usize) as u32,
                channel: ['R', 'G', 'B'][c],
                value: t[c],
                count: bad,
            });
        }
        let mut warning = None;
        let negative = texels.iter().filter(|t| t.min_element() < 0.0).count();
        if let Some(k) = texels.iter().position(|t| t.min_element() < 0.0) {
            warning = Some(format!(
                "{source}: {negative} texels have negative components (the first at ({}, {}): {:?}): clamped to 0",
                k % width as usize,
                k / width as usize,
                texels[k].to_array()
            ));
            for t in &mut texels {
                *t = t.max(Vec3::ZERO);
            }
        }
        if width != 2 * height {
            let note = format!(
                "{source}: {width} × {height} texels is not 2:1; read as latitude-longitude anyway \
                 (each texel covers 360°/{width} × 180°/{height})"
            );
            warning = Some(warning.map_or(note.clone(), |w| format!("{w}; {note}")));
        }
        Ok((Self { width, height, texels, source }, warning))
    }

    /// Reads an `.hdr` (Radiance RGBE) or `.exr` (OpenEXR; its R, G, B channels) file, or any
    /// other format `image` decodes (an 8-bit image is read as linear values in [0, 1]). Only a
    /// regular file is opened (a FIFO or a device is an error, not a wait), and the size its
    /// header states is checked against [`MAX_ENVIRONMENT_TEXELS`] before any texel is
    /// allocated.
    ///
    /// # Errors
    /// [`EnvironmentError::Io`] for a missing or unreadable file, [`EnvironmentError::Decode`]
    /// for a corrupt one, and those of [`EnvironmentMap::new`].
    pub fn load(path: impl AsRef<Path>) -> Result<(Self, Option<String>), EnvironmentError> {
        let path = path.as_ref();
        let file = path.display().to_string();
        let io = |source| EnvironmentError::Io { file: file.clone(), source };
        let (handle, len) = crate::file::open_regular(path).map_err(io)?;
        let mut reader = image::ImageReader::new(std::io::BufReader::new(handle));
        if let Ok(format) = image::ImageFormat::from_path(path) {
            reader.set_format(format);
        }
        Self::decode(reader.with_guessed_format().map_err(io)?, len, file)
    }

    /// [`EnvironmentMap::load`] of a file's bytes already in memory; `name` names it in
    /// messages (its extension is not consulted: the format is recognised from the bytes).
    ///
    /// # Errors
    /// As [`EnvironmentMap::load`].
    pub fn from_bytes(bytes: &[u8], name: &str) -> Result<(Self, Option<String>), EnvironmentError> {
        let reader = image::ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|source| EnvironmentError::Io { file: name.to_string(), source })?;
        Self::decode(reader, bytes.len() as u64, name.to_string())
    }

    /// Decodes through `reader` (a file of `len` bytes) with the limits that keep a lying
    /// header from allocating: the size is read from the header and refused above
    /// [`MAX_ENVIRONMENT_TEXELS`] or above [`MAX_TEXELS_PER_BYTE`] × `len`, and the decoder may
    /// allocate at most [`MAX_ENVIRONMENT_TEXELS`] RGBA f32 texels.
    fn decode<R: std::io::BufRead + std::io::Seek>(
        mut reader: image::ImageReader<R>,
        len: u64,
        file: String,
    ) -> Result<(Self, Option<String>), EnvironmentError> {
        let decode =
            |e: image::ImageError| EnvironmentError::Decode { file: file.clone(), message: e.to_string() };
        let mut limits = image::Limits::default();
        // 16 bytes a texel: RGBA f32, the widest form a decoder produces (EXR with alpha).
        limits.max_alloc = Some(MAX_ENVIRONMENT_TEXELS * 16);
        reader.limits(limits);
        let decoder = reader.into_decoder().map_err(decode)?;
        let (width, height) = image::ImageDecoder::dimensions(&decoder);
        if u64::from(width) * u64::from(height) > MAX_ENVIRONMENT_TEXELS {
            return Err(EnvironmentError::Size { file, width, height, message: "more than 2²⁸ texels" });
        }
        if u64::from(width) * u64::from(height) > len.saturating_mul(MAX_TEXELS_PER_BYTE) {
            return Err(EnvironmentError::Size {
                file,
                width,
                height,
                message: "more texels than a file of this size can hold (the header lies or the file is truncated)",
            });
        }
        let image = image::DynamicImage::from_decoder(decoder).map_err(decode)?.into_rgb32f();
        let (width, height) = image.dimensions();
        let texels = image.pixels().map(|p| Vec3::from(p.0)).collect();
        Self::new(width, height, texels, file)
    }

    /// The built-in neutral light for scenes without one of their own (`--env studio`): a soft
    /// studio of 512 × 256 texels, computed here. A grey gradient (ground 0.3, horizon 0.5,
    /// zenith 1.0 W/(m²·sr)) and three soft-edged rectangular panels: a key of radiance 6 above
    /// the front left (azimuth 45° from +Z towards −X, elevation 40°, 40° × 30°), a fill of 2 on
    /// the right (azimuth 100° from +Z towards +X, elevation 15°, 50° × 40°) and a rim of 4 behind
    /// and above (from −Z, elevation 55°, 60° × 20°). Neutral white: it shows materials' own
    /// colours; the panels give glossy surfaces highlights to show their shape. Each texel is
    /// the mean of 4 × 4 points in its cell.
    pub fn studio() -> Self {
        let (width, height) = (512u32, 256u32);
        let mut texels = Vec::with_capacity((width * height) as usize);
        for j in 0..height {
            for i in 0..width {
                let mut sum = Vec3::ZERO;
                for k in 0..16 {
                    let uv = Vec2::new(
                        (i as f32 + ((k % 4) as f32 + 0.5) / 4.0) / width as f32,
                        (j as f32 + ((k / 4) as f32 + 0.5) / 4.0) / height as f32,
                    );
                    sum += Vec3::splat(studio_radiance(uv_to_direction(uv)));
                }
                texels.push(sum / 16.0);
            }
        }
        Self { width, height, texels, source: "<built-in studio>".into() }
    }

    /// A map of one constant radiance (1 × 1 texel).
    pub fn constant(radiance: Vec3) -> Self {
        Self { width: 1, height: 1, texels: vec![radiance.max(Vec3::ZERO)], source: "<constant>".into() }
    }

    /// Columns.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Rows.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The texels, row-major, row 0 at the top.
    pub fn texels(&self) -> &[Vec3] {
        &self.texels
    }

    /// Where it came from: a file name or `<built-in studio>`.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// Bytes of texels (12 per texel).
    pub fn bytes(&self) -> usize {
        self.texels.len() * size_of::<Vec3>()
    }

    /// Texel (column `i`, row `j`), the column wrapping and the row clamped.
    #[inline]
    fn texel(&self, i: i64, j: i64) -> Vec3 {
        let i = i.rem_euclid(i64::from(self.width)) as usize;
        let j = j.clamp(0, i64::from(self.height) - 1) as usize;
        self.texels[j * self.width as usize + i]
    }

    /// The radiance at `(u, v)` of the unit square: the bilinear, texel-centred lookup.
    pub fn lookup_uv(&self, uv: Vec2) -> Vec3 {
        let x = uv.x * self.width as f32 - 0.5;
        let y = uv.y * self.height as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (i0, j0) = (x0 as i64, y0 as i64);
        let top = (1.0 - fx) * self.texel(i0, j0) + fx * self.texel(i0 + 1, j0);
        let bottom = (1.0 - fx) * self.texel(i0, j0 + 1) + fx * self.texel(i0 + 1, j0 + 1);
        (1.0 - fy) * top + fy * bottom
    }

    /// The radiance seen along unit direction `d` of the map's frame.
    pub fn lookup(&self, d: Vec3) -> Vec3 {
        self.lookup_uv(direction_to_uv(d))
    }

    /// The sampling weight of each cell, row-major: the cell's mean luminance (the bilinear
    /// lookup averaged over the cell, exactly: the texels filtered by `[1 6 1]/8` in each axis,
    /// wrapping in u, clamped in v) × the mean of `sin θ` over its row. With `compensated`, the
    /// mean luminance over the sphere is subtracted first (clamped at 0); if nothing is left (a
    /// constant map) the plain weights are returned.
    pub fn sampling_weights(&self, compensated: bool) -> Vec<f64> {
        let (w, h) = (i64::from(self.width), i64::from(self.height));
        let k = [1.0 / 8.0, 6.0 / 8.0, 1.0 / 8.0];
        // Row j of the horizontal pass (per row, columns wrapping); the vertical pass reads three
        // of them at a time, so only the output holds a value per cell (an 8192 × 4096 map:
        // 256 MiB of f64 and three rows, not three full arrays).
        let horizontal = |j: i64| -> Vec<f64> {
            let j = j.clamp(0, h - 1);
            let lum = |i: i64| f64::from(luminance(self.texel(i, j)));
            (0..w).map(|i| k[0] * lum(i - 1) + k[1] * lum(i) + k[2] * lum(i + 1)).collect()
        };
        let mut out = Vec::with_capacity((w * h) as usize);
        let (mut above, mut here) = (horizontal(-1), horizontal(0));
        for j in 0..h {
            let below = horizontal(j + 1);
            out.extend((0..w as usize).map(|i| k[0] * above[i] + k[1] * here[i] + k[2] * below[i]));
            (above, here) = (here, below);
        }
        let sines: Vec<f64> = (0..h)
            .map(|j| {
                let (t0, t1) = (PI64 * j as f64 / h as f64, PI64 * (j + 1) as f64 / h as f64);
                (t0.cos() - t1.cos()) / (t1 - t0)
            })
            .collect();
        let row_of = |c: usize| c / w as usize;
        let mut offset = 0.0;
        if compensated {
            // The mean over the sphere: cells weighted by their solid angle (∝ the row's sin θ);
            // a map with nothing above its mean (a constant one) keeps the plain weights.
            let (num, den) = out
                .iter()
                .enumerate()
                .fold((0.0, 0.0), |(n, d), (c, &l)| (n + l * sines[row_of(c)], d + sines[row_of(c)]));
            let mean = num / den;
            if out.iter().any(|&l| l - mean > 0.0) {
                offset = mean;
            }
        }
        for (c, l) in out.iter_mut().enumerate() {
            *l = (*l - offset).max(0.0) * sines[row_of(c)];
        }
        out
    }
}

/// The unit-square position `(u, v)` of unit direction `d` (the references' rule).
#[inline]
pub fn direction_to_uv(d: Vec3) -> Vec2 {
    let mut u = d.x.atan2(-d.z) * (0.5 * std::f32::consts::FRAC_1_PI);
    u -= u.floor();
    let v = d.y.clamp(-1.0, 1.0).acos() * std::f32::consts::FRAC_1_PI;
    Vec2::new(u, v)
}

/// The unit direction of unit-square position `(u, v)`: `(sin φ sin θ, cos θ, −cos φ sin θ)`,
/// `φ = 2πu`, `θ = πv`.
#[inline]
pub fn uv_to_direction(uv: Vec2) -> Vec3 {
    let phi = 2.0 * std::f32::consts::PI * uv.x;
    let theta = std::f32::consts::PI * uv.y;
    let (sp, cp) = phi.sin_cos();
    let (st, ct) = theta.sin_cos();
    Vec3::new(sp * st, ct, -cp * st)
}

/// Smooth step from 0 at `a` to 1 at `b`.
fn smoothstep(a: f32, b: f32, x: f32) -> f32 {
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// The studio's radiance along `d` ([`EnvironmentMap::studio`]).
fn studio_radiance(d: Vec3) -> f32 {
    let ground = 0.3;
    let horizon = 0.5;
    let zenith = 1.0;
    let sky = horizon + (zenith - horizon) * smoothstep(0.0, 1.0, d.y);
    let mut l = ground + (sky - ground) * smoothstep(-0.05, 0.05, d.y);
    // A soft-edged rectangular panel centred at (azimuth, elevation) in degrees (azimuth from
    // +Z, positive towards +X), `w × h` degrees, of radiance `k`.
    let panel = |azimuth: f32, elevation: f32, w: f32, h: f32, k: f32| {
        let az = d.x.atan2(d.z).to_degrees();
        let el = d.y.clamp(-1.0, 1.0).asin().to_degrees();
        let mut da = (az - azimuth).abs() % 360.0;
        da = da.min(360.0 - da);
        let de = (el - elevation).abs();
        let edge = 4.0;
        k * (1.0 - smoothstep(w / 2.0 - edge, w / 2.0, da)) * (1.0 - smoothstep(h / 2.0 - edge, h / 2.0, de))
    };
    l += panel(-45.0, 40.0, 40.0, 30.0, 6.0);
    l += panel(100.0, 15.0, 50.0, 40.0, 2.0);
    l += panel(180.0, 55.0, 60.0, 20.0, 4.0);
    l
}

/// Radiance at infinity from an [`EnvironmentMap`], scaled and turned about +Y: a ray leaving
/// the scene in world direction `d` sees `intensity × lookup(R⁻¹ d)`, `R` the rotation by
/// `rotation` radians about +Y, right-handed (+X turns towards −Z).
#[derive(Debug, Clone, PartialEq)]
pub struct Environment {
    /// The map (shared: scenes and renderers hold it without copying).
    pub map: Arc<EnvironmentMap>,
    /// Scale of the map's radiance.
    pub intensity: f32,
    /// Rotation about +Y in radians.
    pub rotation: f32,
    /// Whether camera rays that leave the scene see it (`false`: they see the constant sky
    /// instead, for product shots; it still lights the scene and is seen in reflections).
    pub visible: bool,
}

impl Environment {
    /// `map` at intensity 1, unrotated, visible.
    pub fn new(map: Arc<EnvironmentMap>) -> Self {
        Self { map, intensity: 1.0, rotation: 0.0, visible: true }
    }

    /// `(cos, sin)` of the rotation, formed in `f64` (both integrators use these two numbers).
    pub fn rotation_cos_sin(&self) -> (f32, f32) {
        let r = f64::from(self.rotation);
        (r.cos() as f32, r.sin() as f32)
    }

    /// The rotation as its cosine and sine ([`Environment::rotation_cos_sin`]), formed once for
    /// per-ray use.
    pub fn y_rotation(&self) -> YRotation {
        let (cos, sin) = self.rotation_cos_sin();
        YRotation { cos, sin }
    }

    /// World direction → the map's frame (`R⁻¹ d`).
    pub fn to_map(&self, d: Vec3) -> Vec3 {
        self.y_rotation().to_map(d)
    }

    /// The map's frame → world direction (`R m`).
    pub fn to_world(&self, m: Vec3) -> Vec3 {
        self.y_rotation().to_world(m)
    }

    /// The radiance seen along world direction `d`.
    pub fn radiance(&self, d: Vec3) -> Vec3 {
        self.radiance_with(self.y_rotation(), d)
    }

    /// [`Environment::radiance`] with its rotation formed once ([`Environment::y_rotation`]):
    /// the integrators' escaping rays call this.
    #[inline]
    pub fn radiance_with(&self, rotation: YRotation, d: Vec3) -> Vec3 {
        self.intensity * self.map.lookup(rotation.to_map(d))
    }

    /// Whether it sends no light (intensity 0 or every texel black): nothing to sample.
    pub fn is_black(&self) -> bool {
        !(self.intensity > 0.0) || self.map.texels.iter().all(|t| *t == Vec3::ZERO)
    }

    /// The importance sampler of this environment (`compensated`: MIS compensation); `None` when
    /// it is black ([`Environment::is_black`]: nothing to sample).
    pub fn sampler(&self, compensated: bool) -> Option<EnvironmentSampler> {
        if self.is_black() {
            return None;
        }
        let m = &self.map;
        Distribution2D::new(m.width, m.height, &m.sampling_weights(compensated))
            .map(|distribution| EnvironmentSampler { distribution, rotation: self.y_rotation() })
    }
}

/// A rotation about +Y by its cosine and sine, right-handed (+X turns towards −Z).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct YRotation {
    /// Cosine of the angle.
    pub cos: f32,
    /// Sine of the angle.
    pub sin: f32,
}

impl YRotation {
    /// No rotation.
    pub const IDENTITY: Self = Self { cos: 1.0, sin: 0.0 };

    /// World direction → the map's frame (`R⁻¹ d`).
    #[inline]
    pub fn to_map(self, d: Vec3) -> Vec3 {
        let (c, s) = (self.cos, self.sin);
        Vec3::new(c * d.x - s * d.z, d.y, s * d.x + c * d.z)
    }

    /// The map's frame → world direction (`R m`).
    #[inline]
    pub fn to_world(self, m: Vec3) -> Vec3 {
        let (c, s) = (self.cos, self.sin);
        Vec3::new(c * m.x + s * m.z, m.y, -s * m.x + c * m.z)
    }
}

/// A direction sampled from an environment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnvironmentSample {
    /// Unit world direction towards the environment.
    pub direction: Vec3,
    /// Its solid-angle pdf.
    pub pdf: f32,
    /// The radiance arriving from it ([`Environment::radiance`]).
    pub radiance: Vec3,
}

/// `2π²`: the Jacobian from the unit square to the sphere is `2π² sin θ`.
const TWO_PI_SQUARED: f32 = (2.0 * std::f64::consts::PI * std::f64::consts::PI) as f32;

/// Importance sampling of an [`Environment`] by the [`Distribution2D`] of its map's cells,
/// built by [`Environment::sampler`] for that environment (its rotation taken then, once).
#[derive(Debug, Clone, PartialEq)]
pub struct EnvironmentSampler {
    distribution: Distribution2D,
    rotation: YRotation,
}

impl EnvironmentSampler {
    /// The distribution over the map's cells.
    pub fn distribution(&self) -> &Distribution2D {
        &self.distribution
    }

    /// A direction for uniform `u ∈ [0, 1)²`, or `None` at a pole (`sin θ = 0`, a set of
    /// measure zero).
    ///
    /// The pdf reported is the density the sampling realised: the sampled cell's over the
    /// Jacobian at the direction. [`EnvironmentSampler::pdf`] of the same direction is the same
    /// number except where the direction's round trip through `(u, v)` crosses a cell edge (f32
    /// rounding of the trigonometry: about 10⁻⁶ of the samples on the CPU, more with a GPU's
    /// approximate `atan2`/`acos`); the light sample's own estimate stays exact there, only its
    /// MIS weight against the BSDF ray is off on that set.
    pub fn sample(&self, env: &Environment, u: Vec2) -> Option<EnvironmentSample> {
        let (uv, _, pdf_uv) = self.distribution.sample(u);
        let m = uv_to_direction(uv);
        let sin_theta = (m.x * m.x + m.z * m.z).sqrt();
        if !(sin_theta > 0.0 && pdf_uv > 0.0) {
            return None;
        }
        Some(EnvironmentSample {
            direction: self.rotation.to_world(m),
            pdf: pdf_uv / (TWO_PI_SQUARED * sin_theta),
            radiance: env.intensity * env.map.lookup_uv(uv),
        })
    }

    /// The solid-angle pdf with which [`EnvironmentSampler::sample`] chooses world direction `d`.
    pub fn pdf(&self, d: Vec3) -> f32 {
        let m = self.rotation.to_map(d);
        let sin_theta = (m.x * m.x + m.z * m.z).sqrt();
        if !(sin_theta > 0.0) {
            return 0.0;
        }
        self.distribution.pdf(direction_to_uv(m)) / (TWO_PI_SQUARED * sin_theta)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map(w: u32, h: u32, f: impl Fn(u32, u32) -> Vec3) -> EnvironmentMap {
        let texels = (0..h).flat_map(|j| (0..w).map(move |i| (i, j))).map(|(i, j)| f(i, j)).collect();
        EnvironmentMap::new(w, h, texels, "test").unwrap().0
    }

    #[test]
    fn the_references_rule() {
        // Directions of the README: u 0 = −Z, 0.25 = +X, 0.5 = +Z, 0.75 = −X; v 0 = +Y.
        let uv = |d: Vec3| direction_to_uv(d.normalize());
        assert!((uv(Vec3::NEG_Z) - Vec2::new(0.0, 0.5)).length() < 1e-6);
        assert!((uv(Vec3::X) - Vec2::new(0.25, 0.5)).length() < 1e-6);
        assert!((uv(Vec3::Z) - Vec2::new(0.5, 0.5)).length() < 1e-6);
        assert!((uv(Vec3::NEG_X) - Vec2::new(0.75, 0.5)).length() < 1e-6);
        assert!(uv(Vec3::Y).y.abs() < 1e-6 && (uv(Vec3::NEG_Y).y - 1.0).abs() < 1e-6);
        for k in 0..100 {
            let uv0 = Vec2::new((k as f32 * 0.618_034).fract(), (k as f32 + 0.5) / 100.0);
            let back = direction_to_uv(uv_to_direction(uv0));
            let du = (back.x - uv0.x).abs();
            assert!(du.min(1.0 - du) < 1e-5 && (back.y - uv0.y).abs() < 1e-5, "{uv0} → {back}");
        }
        // Texel centres return the texel; between two centres the mean; the edge row clamps.
        let m = map(4, 2, |i, j| Vec3::splat((i + 10 * j) as f32));
        assert_eq!(m.lookup_uv(Vec2::new(0.375, 0.25)), Vec3::splat(1.0));
        assert_eq!(m.lookup_uv(Vec2::new(0.5, 0.25)), Vec3::splat(1.5));
        assert_eq!(m.lookup_uv(Vec2::new(0.375, 0.0)), Vec3::splat(1.0));
        assert_eq!(m.lookup_uv(Vec2::new(0.375, 0.5)), Vec3::splat(6.0));
        // Columns wrap: u = 0 is halfway between the last and the first column.
        assert_eq!(m.lookup_uv(Vec2::new(0.0, 0.25)), Vec3::splat(1.5));
    }

    #[test]
    fn weights_are_the_cell_means_of_the_lookup() {
        let m = map(5, 3, |i, j| Vec3::splat(((i * 7 + j * 3) % 5) as f32 + 0.1 * j as f32));
        let weights = m.sampling_weights(false);
        for j in 0..3u32 {
            let (t0, t1) = (PI64 * f64::from(j) / 3.0, PI64 * f64::from(j + 1) / 3.0);
            let sin_mean = (t0.cos() - t1.cos()) / (t1 - t0);
            for i in 0..5u32 {
                let n = 64;
                let mut sum = 0.0;
                for a in 0..n {
                    for b in 0..n {
                        let uv = Vec2::new(
                            (i as f32 + (a as f32 + 0.5) / n as f32) / 5.0,
                            (j as f32 + (b as f32 + 0.5) / n as f32) / 3.0,
                        );
                        sum += f64::from(luminance(m.lookup_uv(uv)));
                    }
                }
                let expect = sum / f64::from(n * n) * sin_mean;
                let got = weights[(j * 5 + i) as usize];
                assert!((got - expect).abs() < 1e-4 * expect.max(1.0), "cell {i},{j}: {got} vs {expect}");
            }
        }
    }

    #[test]
    fn compensation_subtracts_the_mean() {
        let m = map(4, 2, |i, _| Vec3::splat(if i == 0 { 3.0 } else { 1.0 }));
        let plain = m.sampling_weights(false);
        let comp = m.sampling_weights(true);
        assert!(plain.iter().all(|&w| w > 0.0));
        assert!(comp.iter().filter(|&&w| w > 0.0).count() < comp.len());
        // A constant map keeps its plain weights.
        let c = EnvironmentMap::constant(Vec3::ONE);
        assert_eq!(c.sampling_weights(true), c.sampling_weights(false));
    }

    #[test]
    fn bad_texels() {
        let e =
            EnvironmentMap::new(2, 1, vec![Vec3::ONE, Vec3::new(0.0, f32::NAN, 0.0)], "x.exr").unwrap_err();
        let s = e.to_string();
        assert!(s.contains("x.exr") && s.contains("(1, 0)") && s.contains("G = NaN"), "{s}");
        let (m, w) = EnvironmentMap::new(2, 1, vec![Vec3::ONE, Vec3::new(-1.0, 0.5, 0.0)], "y.hdr").unwrap();
        assert_eq!(m.texels()[1], Vec3::new(0.0, 0.5, 0.0));
        let w = w.unwrap();
        assert!(w.contains("y.hdr") && w.contains("(1, 0)") && w.contains("clamped"), "{w}");
        assert!(EnvironmentMap::new(0, 0, vec![], "z").is_err());
    }

    #[test]
    fn rotation_turns_plus_x_towards_minus_z() {
        let env = Environment {
            rotation: std::f32::consts::FRAC_PI_2,
            ..Environment::new(Arc::new(EnvironmentMap::studio()))
        };
        assert!((env.to_world(Vec3::X) - Vec3::NEG_Z).length() < 1e-6);
        assert!(
            (env.to_map(env.to_world(Vec3::new(0.3, 0.5, -0.2))) - Vec3::new(0.3, 0.5, -0.2)).length() < 1e-6
        );
    }
}
