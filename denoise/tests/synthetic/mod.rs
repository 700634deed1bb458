//! A synthetic render with a known clean image, its guides, and Monte-Carlo-like noise of known
//! size, shared by the tests (`tests/oidn.rs`) and the benchmark (`examples/bench.rs`).
//!
//! The clean image is `albedo × lighting × shade`, with a smooth HDR lighting gradient
//! (0.4 … 3.4) over three vertical bands:
//!
//! | columns          | albedo             | normal            | shade |
//! |------------------|--------------------|-------------------|-------|
//! | `x < w/2`        | light (0.8 0.7 0.6)| +z                | 1     |
//! | `w/2 ≤ x < 3w/4` | dark (0.15 0.2 0.3)| +z                | 1     |
//! | `x ≥ 3w/4`       | dark               | tilted (0.8 0 0.6)| 0.4   |
//!
//! so there is an **albedo edge** at `w/2` (contrast ≈ 4:1, which the albedo guide shows) and a
//! **crease** at `3w/4` (same albedo, the light drops to 40 %, which only the normal guide
//! shows).
#![allow(dead_code)]

use glam::Vec3;

/// splitmix64 (Steele, Lea, Flood 2014): a tiny seeded generator, plenty for test noise.
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in (0, 1]: never 0, so `ln` is finite.
    pub fn unit(&mut self) -> f64 {
        ((self.next_u64() >> 11) + 1) as f64 / (1u64 << 53) as f64
    }

    /// Standard normal (Box–Muller).
    pub fn normal(&mut self) -> f64 {
        let (u, v) = (self.unit(), self.unit());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

/// The scene: clean colour and guides.
pub struct Scene {
    pub width: u32,
    pub height: u32,
    pub clean: Vec<Vec3>,
    pub albedo: Vec<Vec3>,
    pub normal: Vec<Vec3>,
}

pub const LIGHT_ALBEDO: Vec3 = Vec3::new(0.8, 0.7, 0.6);
pub const DARK_ALBEDO: Vec3 = Vec3::new(0.15, 0.2, 0.3);

impl Scene {
    pub fn new(width: u32, height: u32) -> Scene {
        let (w, h) = (width as usize, height as usize);
        let mut scene = Scene { width, height, clean: Vec::new(), albedo: Vec::new(), normal: Vec::new() };
        for y in 0..h {
            for x in 0..w {
                let (u, v) = ((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
                let lighting = 0.4 + 3.0 * u * (0.5 + 0.5 * v);
                let (albedo, normal, shade) = if x < w / 2 {
                    (LIGHT_ALBEDO, Vec3::Z, 1.0)
                } else if x < 3 * w / 4 {
                    (DARK_ALBEDO, Vec3::Z, 1.0)
                } else {
                    (DARK_ALBEDO, Vec3::new(0.8, 0.0, 0.6), 0.4)
                };
                scene.clean.push(albedo * lighting * shade);
                scene.albedo.push(albedo);
                scene.normal.push(normal);
            }
        }
        scene
    }

    /// The column of the albedo edge (its first dark pixel) and of the crease.
    pub fn edges(&self) -> [usize; 2] {
        let w = self.width as usize;
        [w / 2, 3 * w / 4]
    }

    /// Each pixel times a mean of `k` independent unit exponentials — what a pixel estimate
    /// from `k` samples of an exponentially distributed integrand looks like: unbiased,
    /// non-negative, skewed (fireflies), relative standard deviation exactly `1/√k`. The same
    /// factor for the three channels (a path carries all three).
    pub fn noisy(&self, k: u32, seed: u64) -> Vec<Vec3> {
        let mut rng = SplitMix64(seed);
        self.clean
            .iter()
            .map(|&c| {
                let sum: f64 = (0..k).map(|_| -rng.unit().ln()).sum();
                c * (sum / f64::from(k)) as f32
            })
            .collect()
    }
}

/// Adds Gaussian noise of standard deviation `sigma` to each channel of a guide, keeping
/// albedo in [0, 1] (`clamp01`) — a guide averaged over too few samples.
pub fn noisy_guide(guide: &[Vec3], sigma: f64, clamp01: bool, seed: u64) -> Vec<Vec3> {
    let mut rng = SplitMix64(seed);
    guide
        .iter()
        .map(|&g| {
            let n = Vec3::new(rng.normal() as f32, rng.normal() as f32, rng.normal() as f32);
            let g = g + n * sigma as f32;
            if clamp01 { g.clamp(Vec3::ZERO, Vec3::ONE) } else { g }
        })
        .collect()
}

/// Root-mean-square error over all channels, optionally only in columns `cols`.
pub fn rmse(width: u32, a: &[Vec3], b: &[Vec3], cols: Option<std::ops::Range<usize>>) -> f64 {
    let w = width as usize;
    let (mut sum, mut n) = (0.0f64, 0usize);
    for (i, (p, q)) in a.iter().zip(b).enumerate() {
        if cols.as_ref().is_some_and(|c| !c.contains(&(i % w))) {
            continue;
        }
        let d = *p - *q;
        sum += f64::from(d.dot(d));
        n += 3;
    }
    (sum / n as f64).sqrt()
}

/// How much of the clean image's step across the edge at column `e` (between columns `e - 1`
/// and `e`, in luminance, summed over all rows) `image` keeps: 1 for a sharp edge, 1/2 for an
/// edge blurred by a 2-pixel box filter, 1/3 for a 3-pixel one.
pub fn step_kept(width: u32, clean: &[Vec3], image: &[Vec3], e: usize) -> f64 {
    let w = width as usize;
    let lum = |p: Vec3| f64::from(p.x + p.y + p.z) / 3.0;
    let (mut kept, mut step) = (0.0, 0.0);
    for row in 0..clean.len() / w {
        let (l, r) = (row * w + e - 1, row * w + e);
        kept += lum(image[l]) - lum(image[r]);
        step += lum(clean[l]) - lum(clean[r]);
    }
    kept / step
}

/// `image` blurred horizontally by an `n`-pixel box filter (edges clamped): a strawman that the
/// edge tests must reject.
pub fn box_blur(width: u32, image: &[Vec3], n: usize) -> Vec<Vec3> {
    let w = width as usize;
    (0..image.len())
        .map(|i| {
            let (x, row) = (i % w, i - i % w);
            let sum: Vec3 = (0..n).map(|k| image[row + (x + k).saturating_sub(n / 2).min(w - 1)]).sum();
            sum / n as f32
        })
        .collect()
}
