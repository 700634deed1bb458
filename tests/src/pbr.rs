//! The glTF PBR material references (`tests/data/references/pbr/`): spheres and sheets whose
//! single-scattering radiance was integrated by quadrature from the Khronos specification texts,
//! and the per-object score of a render against them — the oracle's own comparison
//! (`make_pbr_refs.py compare`), ported.
//!
//! * [`regions`]: each object's interior in an image of any size, from the glTF file itself:
//!   the centre (`extras.sphere.center` / `extras.sheet.center` of its node) and the radius
//!   (`radius` / `half_size`) projected through the scene's camera; a pixel is interior when
//!   its centre lies within [`INTERIOR`] of the projected radius (a disc for spheres, a square
//!   for sheets): no silhouette pixels.
//! * [`score`]: per object, the per-channel ratio of the candidate's interior mean to the
//!   reference's, its standard error from two renders with different seeds, and per-pixel
//!   `z = (c − r)/√(σ²_c + e_r²)`, with `σ²_c` the variance of the two renders' mean
//!   (`(a − b)²/4`) averaged over 3 × 3 pixels (one render pair gives one degree of freedom
//!   per pixel) and `e_r` the reference's error estimate.
//! * [`downsample`]: a reference and its error image averaged over `f × f` blocks, so that a
//!   render at a fraction of the size can be scored.

use crate::cbox::Image;
use glam::{DVec2, DVec3};
use std::path::Path;

/// A pixel is interior when its centre is within this fraction of the projected radius (the
/// oracle's `margin`).
pub const INTERIOR: f64 = 0.85;

/// How an object's interior is bounded in the image.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shape {
    /// A sphere: a disc of the projected radius.
    Disc,
    /// A flat square facing the camera: a square of the projected half size.
    Square,
}

/// One object of a reference scene, in the pixel coordinates of an image of a given size.
#[derive(Debug, Clone, PartialEq)]
pub struct Region {
    /// The node's name (e.g. `gold_r0.1`).
    pub name: String,
    /// The projected centre (pixels from the top-left corner).
    pub centre: DVec2,
    /// The projected radius or half size (pixels).
    pub radius: f64,
    /// Disc or square.
    pub shape: Shape,
}

impl Region {
    /// Whether pixel `(x, y)` (its centre at `x + 0.5, y + 0.5`) is interior.
    pub fn contains(&self, x: usize, y: usize) -> bool {
        let d = DVec2::new(x as f64 + 0.5, y as f64 + 0.5) - self.centre;
        let r = INTERIOR * self.radius;
        match self.shape {
            Shape::Disc => d.length_squared() < r * r,
            Shape::Square => d.x.abs() < r && d.y.abs() < r,
        }
    }
}

fn vec3(v: &serde_json::Value) -> Option<DVec3> {
    let a = v.as_array()?;
    Some(DVec3::new(a.first()?.as_f64()?, a.get(1)?.as_f64()?, a.get(2)?.as_f64()?))
}

/// The objects of a reference scene, projected into a `width × height` image through the
/// scene's camera (the node of `scenes[0]` with a perspective camera, placed by its translation
/// and rotation).
///
/// # Errors
/// The file cannot be read or parsed, or a node, camera or object record is missing or
/// malformed; the message names the file and the glTF path.
pub fn regions(gltf: &Path, width: u32, height: u32) -> Result<Vec<Region>, String> {
    let file = gltf.display();
    let text = std::fs::read_to_string(gltf).map_err(|e| format!("{file}: {e}"))?;
    let j: serde_json::Value = serde_json::from_str(&text).map_err(|e| format!("{file}: {e}"))?;
    let nodes =
        j["scenes"][0]["nodes"].as_array().ok_or_else(|| format!("{file}: scenes[0].nodes: missing"))?;
    let mut camera = None;
    let mut objects = Vec::new();
    for (k, index) in nodes.iter().enumerate() {
        let i = index.as_u64().ok_or_else(|| format!("{file}: scenes[0].nodes[{k}]: not an index"))?;
        let node = &j["nodes"][i as usize];
        let translation = match &node["translation"] {
            serde_json::Value::Null => DVec3::ZERO,
            t => vec3(t).ok_or_else(|| format!("{file}: nodes[{i}].translation: malformed"))?,
        };
        if let Some(c) = node["camera"].as_u64() {
            let q = match node["rotation"].as_array() {
                None => glam::DQuat::IDENTITY,
                Some(q) => {
                    let v: Vec<f64> = q.iter().filter_map(serde_json::Value::as_f64).collect();
                    if v.len() != 4 {
                        return Err(format!("{file}: nodes[{i}].rotation: malformed"));
                    }
                    glam::DQuat::from_xyzw(v[0], v[1], v[2], v[3]).normalize()
                }
            };
            let yfov = j["cameras"][c as usize]["perspective"]["yfov"]
                .as_f64()
                .ok_or_else(|| format!("{file}: cameras[{c}].perspective.yfov: missing"))?;
            camera = Some((translation, q, yfov));
        }
        let extras = &node["extras"];
        let (record, shape, size) = if extras["sphere"].is_object() {
            ("sphere", Shape::Disc, "radius")
        } else if extras["sheet"].is_object() {
            ("sheet", Shape::Square, "half_size")
        } else {
            continue;
        };
        let g = &extras[record];
        let centre = vec3(&g["center"])
            .ok_or_else(|| format!("{file}: nodes[{i}].extras.{record}.center: malformed"))?;
        let radius =
            g[size].as_f64().ok_or_else(|| format!("{file}: nodes[{i}].extras.{record}.{size}: missing"))?;
        let name = node["name"].as_str().unwrap_or_default().to_owned();
        objects.push((name, centre, radius, shape));
    }
    let (origin, rotation, yfov) = camera.ok_or_else(|| format!("{file}: scenes[0]: no camera node"))?;
    let (w, h) = (f64::from(width), f64::from(height));
    let t = (yfov / 2.0).tan();
    // glTF pinhole, film x to the right and y down (the oracle's `Scene.project`).
    let project = |p: DVec3| {
        let q = rotation.inverse() * (p - origin);
        DVec2::new(((q.x / -q.z) / (t * w / h) + 1.0) * w / 2.0, (1.0 - (q.y / -q.z) / t) * h / 2.0)
    };
    Ok(objects
        .into_iter()
        .map(|(name, centre, radius, shape)| {
            let c = project(centre);
            let edge = project(centre + DVec3::X * radius);
            Region { name, centre: c, radius: (edge.x - c.x).abs(), shape }
        })
        .collect())
}

/// A reference image and its per-pixel error estimate averaged over `factor × factor` blocks.
///
/// The image's pixels are box-filtered means (one pixel wide), so a block's mean is exactly the
/// reference of the pixel of the image `factor` times smaller. The error estimates are of
/// quadrature errors, which need not be independent between neighbouring pixels: a block's error
/// is the **mean** of its pixels' (what the mean's error is when they all err alike), not the
/// `√(Σe²)/f²` of independent errors, `f` times smaller.
///
/// # Panics
/// If `factor` does not divide both sizes, or the two images differ in size.
pub fn downsample(reference: &Image, error: &Image, factor: usize) -> (Image, Image) {
    assert_eq!((reference.width, reference.height), (error.width, error.height), "reference and error sizes");
    let (w, h) = (reference.width / factor, reference.height / factor);
    assert_eq!(
        (w * factor, h * factor),
        (reference.width, reference.height),
        "size not divisible by {factor}"
    );
    let block = |image: &Image| {
        let mut out = vec![DVec3::ZERO; w * h];
        for y in 0..image.height {
            for x in 0..image.width {
                out[(y / factor) * w + x / factor] += image.pixels[y * image.width + x];
            }
        }
        let n = (factor * factor) as f64;
        Image { width: w, height: h, pixels: out.into_iter().map(|s| s / n).collect() }
    };
    (block(reference), block(error))
}

/// How one object of a render compares with the reference.
#[derive(Debug, Clone)]
pub struct ObjectScore {
    /// The object's node name.
    pub name: String,
    /// Interior pixels.
    pub pixels: usize,
    /// Per-channel ratio of the interior means, candidate (mean of the two renders) /
    /// reference.
    pub ratio: DVec3,
    /// Standard error of `ratio` from the two renders' spread (the reference's error is far
    /// smaller).
    pub ratio_sigma: DVec3,
    /// Mean and (population) standard deviation of z over the interior pixels and channels.
    pub z_mean: f64,
    /// (see `z_mean`)
    pub z_std: f64,
    /// The fraction of interior pixel-channels whose two renders differ by more than the
    /// reference's error estimate there: how much of the candidate's noise is resolved at the
    /// reference's precision (see the module `pbr_references` of the tests for what it decides).
    pub resolved: f64,
    /// `√(mean of σ²_c/(σ²_c + e_r²))` over the interior pixel-channels (σ²_c and e_r as z
    /// takes them): the z std of an unbiased candidate if the reference were exact and its error
    /// estimate only conservative. An unbiased render's z std lies between this and 1 (times
    /// the Student factor of few degrees of freedom).
    pub noise_share: f64,
}

/// Per-pixel `z = (c − r)/√(σ²_c + e_r²)` of two renders `a`, `b` (different seeds): `c` their
/// mean, `σ²_c = (a − b)²/4` averaged over the 3 × 3 neighbourhood (edge pixels repeated), `e_r`
/// the reference's error estimate.
///
/// # Panics
/// If the images differ in size.
pub fn z_image(a: &Image, b: &Image, reference: &Image, error: &Image) -> Image {
    let (w, h) = (reference.width, reference.height);
    for i in [a, b, error] {
        assert_eq!((i.width, i.height), (w, h), "image sizes");
    }
    let var: Vec<DVec3> = a.pixels.iter().zip(&b.pixels).map(|(a, b)| (*a - *b) * (*a - *b) / 4.0).collect();
    let at = |x: isize, y: isize| {
        var[y.clamp(0, h as isize - 1) as usize * w + x.clamp(0, w as isize - 1) as usize]
    };
    let pixels = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as isize, (i / w) as isize);
            let mut v = DVec3::ZERO;
            for dy in -1..=1 {
                for dx in -1..=1 {
                    v += at(x + dx, y + dy);
                }
            }
            let e = error.pixels[i];
            // The oracle's 1e-30 keeps a pixel without noise or error (none inside an object) finite.
            ((a.pixels[i] + b.pixels[i]) / 2.0 - reference.pixels[i])
                / (v / 9.0 + e * e + DVec3::splat(1e-30)).map(f64::sqrt)
        })
        .collect();
    Image { width: w, height: h, pixels }
}

/// Scores two renders `a`, `b` of the same settings and different seeds against `reference`
/// and its `error` estimate, per region (all four images of one size, the regions projected at
/// that size): the oracle's `compare`.
///
/// # Panics
/// If the images differ in size or a region has no interior pixel.
pub fn score(a: &Image, b: &Image, reference: &Image, error: &Image, regions: &[Region]) -> Vec<ObjectScore> {
    let (w, h) = (reference.width, reference.height);
    for i in [a, b, error] {
        assert_eq!((i.width, i.height), (w, h), "image sizes");
    }
    let mean: Vec<DVec3> = a.pixels.iter().zip(&b.pixels).map(|(a, b)| (*a + *b) / 2.0).collect();
    let var: Vec<DVec3> = a.pixels.iter().zip(&b.pixels).map(|(a, b)| (*a - *b) * (*a - *b) / 4.0).collect();
    let z = z_image(a, b, reference, error).pixels;
    regions
        .iter()
        .map(|r| {
            let inside: Vec<usize> = (0..w * h).filter(|i| r.contains(i % w, i / w)).collect();
            assert!(!inside.is_empty(), "{}: no interior pixel", r.name);
            let n = inside.len() as f64;
            let sum = |f: &dyn Fn(usize) -> DVec3| inside.iter().map(|&i| f(i)).sum::<DVec3>();
            let reference_mean = sum(&|i| reference.pixels[i]) / n;
            let ratio = sum(&|i| mean[i]) / n / reference_mean;
            let ratio_sigma = sum(&|i| var[i]).map(f64::sqrt) / n / reference_mean;
            let zs: Vec<f64> = inside.iter().flat_map(|&i| z[i].to_array()).collect();
            let m = zs.len() as f64;
            let z_mean = zs.iter().sum::<f64>() / m;
            let z_std = (zs.iter().map(|z| (z - z_mean).powi(2)).sum::<f64>() / m).sqrt();
            let resolved = inside
                .iter()
                .flat_map(|&i| {
                    let d = (a.pixels[i] - b.pixels[i]).abs().to_array();
                    let e = error.pixels[i].to_array();
                    (0..3).map(move |c| d[c] > e[c])
                })
                .filter(|&r| r)
                .count() as f64
                / m;
            let pooled = |i: usize| {
                let (x, y) = ((i % w) as isize, (i / w) as isize);
                let mut v = DVec3::ZERO;
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        let (xx, yy) = ((x + dx).clamp(0, w as isize - 1), (y + dy).clamp(0, h as isize - 1));
                        v += var[yy as usize * w + xx as usize];
                    }
                }
                v / 9.0
            };
            let share = inside
                .iter()
                .flat_map(|&i| {
                    let (v, e) = (pooled(i), error.pixels[i]);
                    (v / (v + e * e + DVec3::splat(1e-30))).to_array()
                })
                .sum::<f64>()
                / m;
            ObjectScore {
                name: r.name.clone(),
                pixels: inside.len(),
                ratio,
                ratio_sigma,
                z_mean,
                z_std,
                resolved,
                noise_share: share.sqrt(),
            }
        })
        .collect()
}
