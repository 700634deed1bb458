//! The Mitsuba references of the built-in Cornell box (`tests/data/references/cbox/`),
//! per-pixel estimates with their standard error from any [`Integrator`], and the z statistics
//! that compare the two. Used by `tests/mitsuba.rs`, `tests/backends.rs` and the budget and
//! sampler-study examples.

use furnace_render::{Film, Integrator};
use glam::DVec3;
use std::path::Path;

/// An RGB image, row-major, row 0 at the top.
#[derive(Debug, Clone)]
pub struct Image {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Pixels, row-major.
    pub pixels: Vec<DVec3>,
}

impl Image {
    /// Reads the RGB channels of an EXR file.
    pub fn read_exr(path: &Path) -> Self {
        let image = exr::prelude::read_first_rgba_layer_from_file(
            path,
            |resolution, _| (resolution.width(), resolution.height(), vec![DVec3::ZERO; resolution.area()]),
            |(w, _, pixels), position, (r, g, b, _a): (f32, f32, f32, f32)| {
                pixels[position.y() * *w + position.x()] = DVec3::new(r.into(), g.into(), b.into());
            },
        )
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let (width, height, pixels) = image.layer_data.channel_data.pixels;
        Self { width, height, pixels }
    }

    /// Writes the image as an RGB `f32` EXR.
    pub fn write_exr(&self, path: &Path) {
        exr::prelude::write_rgb_file(path, self.width, self.height, |x, y| {
            let v = self.pixels[y * self.width + x].as_vec3();
            (v.x, v.y, v.z)
        })
        .unwrap_or_else(|e| panic!("writing {}: {e}", path.display()));
    }

    /// Per-channel mean over all pixels.
    pub fn mean(&self) -> DVec3 {
        self.pixels.iter().sum::<DVec3>() / self.pixels.len() as f64
    }
}

/// A Mitsuba reference: the image and each pixel's standard error of the mean.
#[derive(Debug, Clone)]
pub struct Reference {
    /// The reference's file stem (and downsampling).
    pub name: String,
    /// The image.
    pub mean: Image,
    /// Each pixel's standard error of the mean.
    pub stderr: Image,
}

impl Reference {
    /// `tests/data/references/cbox/{stem}.exr` and `{stem}_stderr.exr`.
    pub fn load(stem: &str) -> Self {
        Self::load_in("cbox", stem)
    }

    /// `tests/data/references/{folder}/{stem}.exr` and `{stem}_stderr.exr`.
    pub fn load_in(folder: &str, stem: &str) -> Self {
        let mean = Image::read_exr(&crate::data::reference(&format!("{folder}/{stem}.exr")));
        let stderr = Image::read_exr(&crate::data::reference(&format!("{folder}/{stem}_stderr.exr")));
        assert_eq!((mean.width, mean.height), (stderr.width, stderr.height), "{stem}: sizes");
        Self { name: stem.to_owned(), mean, stderr }
    }

    /// The noise floor of an MSE measured against this reference: `mean(se_ref²)` over pixels
    /// and channels (the expected squared error of a perfect candidate).
    pub fn mse_floor(&self) -> f64 {
        self.stderr.pixels.iter().map(|s| s.length_squared() / 3.0).sum::<f64>()
            / self.stderr.pixels.len() as f64
    }
}

/// Running mean and variance (Welford) of a pixel's samples grouped in batches of `batch`
/// consecutive samples: the standard error of the mean comes from the spread of the batch
/// means (`batch = 1`: of the samples themselves). Welford keeps a constant pixel's variance
/// exactly 0.
#[derive(Debug, Clone, Copy)]
pub struct BatchEstimator {
    batch: u32,
    in_batch: u32,
    batch_sum: DVec3,
    batches: u32,
    mean: DVec3,
    m2: DVec3,
}

impl BatchEstimator {
    /// An estimator of batches of `batch` samples (`batch > 0`).
    pub fn new(batch: u32) -> Self {
        assert!(batch > 0);
        Self { batch, in_batch: 0, batch_sum: DVec3::ZERO, batches: 0, mean: DVec3::ZERO, m2: DVec3::ZERO }
    }

    /// Adds one sample.
    pub fn push(&mut self, v: DVec3) {
        self.batch_sum += v;
        self.in_batch += 1;
        if self.in_batch == self.batch {
            let x = self.batch_sum / f64::from(self.batch);
            self.batch_sum = DVec3::ZERO;
            self.in_batch = 0;
            self.batches += 1;
            let delta = x - self.mean;
            self.mean += delta / f64::from(self.batches);
            self.m2 += delta * (x - self.mean);
        }
    }

    /// Number of complete batches.
    pub fn batches(&self) -> u32 {
        self.batches
    }

    /// `(mean, standard error of the mean)` over the complete batches (needs ≥ 2 of them and no
    /// partial batch).
    pub fn estimate(&self) -> (DVec3, DVec3) {
        assert!(
            self.batches >= 2 && self.in_batch == 0,
            "{} batches + {} samples",
            self.batches,
            self.in_batch
        );
        let n = f64::from(self.batches);
        (self.mean, (self.m2 / (n - 1.0) / n).map(f64::sqrt))
    }
}

/// A candidate image with per-pixel standard errors.
#[derive(Debug, Clone)]
pub struct Estimate {
    /// Each pixel's mean.
    pub mean: Image,
    /// Each pixel's standard error of the mean.
    pub stderr: Image,
}

/// Renders `passes` passes of `spp_per_pass` samples per pixel with `integrator` (pass `p`
/// takes sample indices `p·spp_per_pass ..`, onto the integrator's current film), and estimates
/// each pixel's mean and standard error from the spread of its pass means (Welford).
///
/// Each pass's contribution is the difference of the film's sums before and after it: exact,
/// the sums being f64 sums of f32 samples far from f64's precision.
///
/// # Panics
/// If a pass fails, or a sample was rejected as non-finite (it would bias the estimate without
/// showing).
pub fn render_passes(integrator: &mut dyn Integrator, passes: u32, spp_per_pass: u32) -> Estimate {
    let mut before = integrator.film().expect("reading the film");
    let (w, h) = (before.width() as usize, before.height() as usize);
    let mut estimators = vec![BatchEstimator::new(1); w * h];
    let first = before.counts().first().copied().unwrap_or(0) as u32;
    for pass in 0..passes {
        integrator.render_pass(first + pass * spp_per_pass, spp_per_pass).expect("a pass");
        let after: Film = integrator.film().expect("reading the film");
        assert_eq!(after.rejected(), before.rejected(), "pass {pass}: non-finite samples");
        for (i, e) in estimators.iter_mut().enumerate() {
            let n = f64::from(spp_per_pass);
            e.push(DVec3::from_array(std::array::from_fn(|c| {
                (after.sums()[i][c] - before.sums()[i][c]) / n
            })));
        }
        before = after;
    }
    let per_pixel: Vec<(DVec3, DVec3)> = estimators.iter().map(BatchEstimator::estimate).collect();
    let image = |f: fn(&(DVec3, DVec3)) -> DVec3| Image {
        width: w,
        height: h,
        pixels: per_pixel.iter().map(f).collect(),
    };
    Estimate { mean: image(|p| p.0), stderr: image(|p| p.1) }
}

/// The reference averaged over `factor × factor` blocks: each block's mean, and the standard
/// error of that mean `√(Σ se²)/factor²` (independent pixels).
///
/// # Panics
/// If `factor` does not divide the reference's size.
pub fn downsample(r: &Reference, factor: usize) -> Reference {
    let (w, h) = (r.mean.width / factor, r.mean.height / factor);
    assert_eq!((w * factor, h * factor), (r.mean.width, r.mean.height), "{}: size", r.name);
    let mut mean = vec![DVec3::ZERO; w * h];
    let mut var = vec![DVec3::ZERO; w * h];
    for y in 0..r.mean.height {
        for x in 0..r.mean.width {
            let (i, k) = ((y / factor) * w + x / factor, y * r.mean.width + x);
            mean[i] += r.mean.pixels[k];
            var[i] += r.stderr.pixels[k] * r.stderr.pixels[k];
        }
    }
    let n = (factor * factor) as f64;
    Reference {
        name: format!("{}_{w}x{h}", r.name),
        mean: Image { width: w, height: h, pixels: mean.iter().map(|m| *m / n).collect() },
        stderr: Image { width: w, height: h, pixels: var.iter().map(|v| v.map(f64::sqrt) / n).collect() },
    }
}

/// How a candidate compares with a reference.
#[derive(Debug, Clone)]
pub struct Comparison {
    /// Per-channel image means.
    pub ours: DVec3,
    /// Per-channel image means of the reference.
    pub reference: DVec3,
    /// Standard error of `ours / reference` per channel (both images' errors).
    pub ratio_se: DVec3,
    /// Per-pixel, per-channel `z = (ours − ref)/√(se_ours² + se_ref²)` over the values where
    /// the denominator is not 0: mean, standard deviation, fraction with |z| > 3, count.
    pub z_mean: f64,
    /// (see `z_mean`)
    pub z_std: f64,
    /// (see `z_mean`)
    pub z_over_3: f64,
    /// (see `z_mean`)
    pub z_count: usize,
    /// Largest |z| and its pixel.
    pub z_max: (f64, usize, usize),
    /// Root-mean-square error over pixels and channels, and relative MSE
    /// (`furnace_post::metrics`, ε = 1e-2).
    pub rmse: f64,
    /// (see `rmse`)
    pub rel_mse: f64,
    /// The z image (0 where undefined).
    pub z_image: Image,
}

impl Comparison {
    /// Per-channel ratio of the image means, ours / reference.
    pub fn ratio(&self) -> DVec3 {
        self.ours / self.reference
    }

    /// The table cells `ratio R, G, B (± se) | z mean | z std | |z| > 3 | max |z| | z values`
    /// (shared by the reference tests and their budget example).
    pub fn cells(&self) -> String {
        let r = self.ratio();
        format!(
            "{:.4}, {:.4}, {:.4} (± {:.4}) | {:+.3} | {:.3} | {:.4} | {:.1} at ({}, {}) | {}",
            r.x,
            r.y,
            r.z,
            self.ratio_se.max_element(),
            self.z_mean,
            self.z_std,
            self.z_over_3,
            self.z_max.0,
            self.z_max.1,
            self.z_max.2,
            self.z_count
        )
    }
}

/// Relative floor of the z-scores' denominators: the references are `f32` sums of 65 536
/// samples, so a pixel whose every sample has the same value (an emitter seen directly, filling
/// the pixel) has a "standard error" of float rounding (10⁻⁹ of 0.2) that the candidate's
/// exact value misses by 10⁻⁷ relative — a z of 100 that is no bias. 10⁻⁶ of the reference
/// value is far below any pixel's noise (≥ 10⁻⁴ here) and above that rounding. Pixels with no
/// error on either side (exactly 0) still have no z.
pub use furnace_post::metrics::Z_ROUNDING_FLOOR;

/// Compares `candidate` with `reference` pixel by pixel (same size).
pub fn compare(candidate: &Estimate, reference: &Reference) -> Comparison {
    compare_masked(candidate, reference, None)
}

/// [`compare`], with the image-mean ratio (and its standard error) over the pixels where
/// `ratio_pixels` is true only (all of them for `None`); z covers every pixel.
pub fn compare_masked(
    candidate: &Estimate,
    reference: &Reference,
    ratio_pixels: Option<&[bool]>,
) -> Comparison {
    let (w, h) = (reference.mean.width, reference.mean.height);
    assert_eq!((candidate.mean.width, candidate.mean.height), (w, h), "candidate size");
    let mut zs = Vec::with_capacity(w * h * 3);
    let mut z_image = vec![DVec3::ZERO; w * h];
    let mut z_max = (0.0, 0, 0);
    let (mut var_ours, mut var_ref) = (DVec3::ZERO, DVec3::ZERO);
    let (mut sum_ours, mut sum_ref, mut p) = (DVec3::ZERO, DVec3::ZERO, 0.0);
    let mut errors = furnace_post::metrics::ErrorSum::default();
    for (i, z_pixel) in z_image.iter_mut().enumerate() {
        let (m, s) = (candidate.mean.pixels[i], candidate.stderr.pixels[i]);
        let (r, sr) = (reference.mean.pixels[i], reference.stderr.pixels[i]);
        if ratio_pixels.is_none_or(|mask| mask[i]) {
            var_ours += s * s;
            var_ref += sr * sr;
            sum_ours += m;
            sum_ref += r;
            p += 1.0;
        }
        let d = m - r;
        errors.add_rgb(m.to_array(), r.to_array());
        let floor = r * Z_ROUNDING_FLOOR;
        let variance = s * s + sr * sr;
        let denominator = variance.max(floor * floor).map(f64::sqrt);
        for c in 0..3 {
            // A value without noise on either side (the sky through a hole) has no z.
            if variance[c] > 0.0 {
                let z = d[c] / denominator[c];
                z_pixel[c] = z;
                zs.push(z);
                if z.abs() > z_max.0 {
                    z_max = (z.abs(), i % w, i / w);
                }
            }
        }
    }
    let (ours, refm) = (sum_ours / p, sum_ref / p);
    // Pixels' errors are independent: Var(image mean) = Σ se²/p².
    let ratio = ours / refm;
    let ratio_se = ratio * ((var_ours / (ours * ours) + var_ref / (refm * refm)) / (p * p)).map(f64::sqrt);
    let n = zs.len() as f64;
    let z_mean = zs.iter().sum::<f64>() / n;
    let z_std = (zs.iter().map(|z| (z - z_mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    let z_over_3 = zs.iter().filter(|z| z.abs() > 3.0).count() as f64 / n;
    Comparison {
        ours,
        reference: refm,
        ratio_se,
        z_mean,
        z_std,
        z_over_3,
        z_count: zs.len(),
        z_max,
        rmse: errors.rmse(),
        rel_mse: errors.rel_mse(),
        z_image: Image { width: w, height: h, pixels: z_image },
    }
}

/// Which pixels of a `size`² render of `scene` (its default camera) show **no** emitter
/// directly: a camera-ray-only render (0 bounces, 64 Owen-Sobol samples per pixel, CPU) is 0
/// there. `None` for a scene without emitters. Image-mean ratios over these pixels measure the
/// light the emitters cast: a pixel on an emitter's edge has the jitter noise of where its
/// samples land on the edge, the same for every light-sampling method, which dominates the
/// image mean's error when emitters are seen (many small ones, or one bright one).
pub fn pixels_without_visible_emitters(scene: &furnace_scene::Scene, size: u32) -> Option<Vec<bool>> {
    furnace_scene::Emitters::new(scene)?;
    let settings = furnace_render::RenderSettings {
        width: size,
        height: size,
        bounces: 0,
        sampler: furnace_sampling::SamplerKind::Sobol,
        ..Default::default()
    };
    let cpu = furnace_cpu::CpuRenderer::with_default_camera(scene.clone(), settings).expect("a CPU renderer");
    let mut film = cpu.new_film();
    cpu.render_into(&mut film, 0, 64).expect("a pass");
    Some((0..film.counts().len()).map(|i| film.mean(i) == DVec3::ZERO).collect())
}
