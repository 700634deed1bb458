//! [`Film`]: per-pixel `f64` sums and sample counts, so that accumulation does not drift.

use glam::{DVec3, Vec3};

/// An accumulation buffer: for each pixel the `f64` sum of its accepted samples and their count.
///
/// The estimate of a pixel is `sum / count`, formed only when read ([`Film::pixel`]). Summing in
/// `f64` keeps the relative rounding error of `n` additions below `n·2⁻⁵³` (≈ 10⁻¹⁰ after 10⁶
/// samples); the running mean `(N·prev + new)/(N + 1)` in `f32` that the thesis used drifted
/// visibly after ~2000 frames, because every frame re-rounded the mean
/// (furnace-cpu's `tests/film.rs::million_frames_do_not_drift`).
///
/// Samples with a non-finite channel are rejected: not added, not counted, but tallied in
/// [`Film::rejected`].
///
/// Pixels are stored row-major, row 0 at the top, like the camera's film coordinates.
///
/// A film made by [`Film::with_aovs`] also sums, for every accepted sample, the first-hit
/// [`AovSample`] of its camera ray ([`AovSum`] per pixel): the albedo, shading normal and depth
/// guides a denoiser takes and compositors read, averaged over exactly the samples of the image.
#[derive(Debug, Clone, PartialEq)]
pub struct Film {
    width: u32,
    height: u32,
    sum: Vec<DVec3>,
    count: Vec<u64>,
    rejected: u64,
    aov: Option<Vec<AovSum>>,
    adaptive: Option<AdaptiveState>,
}

/// The part of a film that adaptive sampling needs ([`crate::AdaptiveSampling`]): per pixel the
/// `f64` sum of its samples' squared luminances, and whether it has converged.
#[derive(Debug, Clone, PartialEq)]
struct AdaptiveState {
    lum_sq: Vec<f64>,
    converged: Vec<bool>,
}

/// What the camera ray of one sample found first: the guides of a denoiser and the auxiliary
/// outputs (AOVs) of a render.
///
/// * `albedo`: the material's base colour at the hit (the diffuse colour of a dielectric, the
///   normal-incidence reflectance of a metal, as Open Image Denoise asks); 1 for a ray that
///   escapes and for the emitting side of an emitter (their colour is their light, like Cycles'
///   denoising albedo of the background; an emitter's base colour is often black, and a 0 guide
///   made Open Image Denoise smear the light's edges: measured on `cbox_area`);
/// * `normal`: the world-space shading normal at the hit (facing the ray); 0 for a ray that
///   escapes (Open Image Denoise's "no surface");
/// * `depth`: the distance along the (unit) camera ray to the hit; `None` for a ray that escapes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AovSample {
    /// Base colour at the hit, or 1 for a miss.
    pub albedo: Vec3,
    /// World-space shading normal at the hit, or 0 for a miss.
    pub normal: Vec3,
    /// Distance to the hit along the camera ray; `None` for a miss.
    pub depth: Option<f32>,
}

impl AovSample {
    /// A camera ray that hit nothing.
    pub const MISS: AovSample = AovSample { albedo: Vec3::ONE, normal: Vec3::ZERO, depth: None };
}

/// One pixel's sums of the [`AovSample`]s of its accepted samples, in `f64` like the colour
/// sums. `#[repr(C)]`, 64 bytes: the layout of the GPU film's AOV buffer (two `vec4<f64>`:
/// albedo and depth, normal and hits).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[repr(C)]
pub struct AovSum {
    /// Sum of the albedos.
    pub albedo: [f64; 3],
    /// Sum of the depths of the samples that hit a surface.
    pub depth: f64,
    /// Sum of the shading normals.
    pub normal: [f64; 3],
    /// How many of the samples hit a surface.
    pub hits: f64,
}

/// The means of one pixel's AOVs ([`Film::aov`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AovMean {
    /// Mean albedo over the pixel's samples.
    pub albedo: DVec3,
    /// Mean shading normal over the pixel's samples (not renormalised: shorter at silhouettes
    /// and where normals disagree, 0 where nothing was hit).
    pub normal: DVec3,
    /// Mean depth over the samples that hit a surface; `+∞` if none did (or the pixel has no
    /// samples).
    pub depth: f64,
    /// The fraction of the pixel's samples that hit a surface (0 without samples).
    pub coverage: f64,
}

impl AovSum {
    /// Adds one sample's AOVs.
    #[inline]
    pub fn add(&mut self, s: &AovSample) {
        for c in 0..3 {
            self.albedo[c] += f64::from(s.albedo[c]);
            self.normal[c] += f64::from(s.normal[c]);
        }
        if let Some(d) = s.depth {
            self.depth += f64::from(d);
            self.hits += 1.0;
        }
    }

    /// Adds another pixel's sums (disjoint samples).
    pub fn add_sum(&mut self, o: &AovSum) {
        for c in 0..3 {
            self.albedo[c] += o.albedo[c];
            self.normal[c] += o.normal[c];
        }
        self.depth += o.depth;
        self.hits += o.hits;
    }

    /// The means over `count` samples.
    pub fn mean(&self, count: u64) -> AovMean {
        if count == 0 {
            return AovMean { albedo: DVec3::ZERO, normal: DVec3::ZERO, depth: f64::INFINITY, coverage: 0.0 };
        }
        let n = count as f64;
        AovMean {
            albedo: DVec3::from_array(self.albedo) / n,
            normal: DVec3::from_array(self.normal) / n,
            depth: if self.hits > 0.0 { self.depth / self.hits } else { f64::INFINITY },
            coverage: self.hits / n,
        }
    }

    /// The eight sums in layout order: albedo RGB, depth, normal XYZ, hits.
    pub fn to_array(&self) -> [f64; 8] {
        let [r, g, b] = self.albedo;
        let [x, y, z] = self.normal;
        [r, g, b, self.depth, x, y, z, self.hits]
    }

    /// From [`AovSum::to_array`]'s order.
    pub fn from_array(a: [f64; 8]) -> Self {
        AovSum { albedo: [a[0], a[1], a[2]], depth: a[3], normal: [a[4], a[5], a[6]], hits: a[7] }
    }
}

impl Film {
    /// An empty (all-zero) film of `width × height` pixels.
    pub fn new(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            sum: vec![DVec3::ZERO; n],
            count: vec![0; n],
            rejected: 0,
            aov: None,
            adaptive: None,
        }
    }

    /// Bytes per pixel of a film made by [`Film::for_settings`]: the sums and count (32), the
    /// AOV sums (64 more), the adaptive state (9 more).
    pub fn bytes_per_pixel(settings: &crate::RenderSettings) -> u64 {
        let base = (size_of::<DVec3>() + size_of::<u64>()) as u64;
        let aov = if settings.aovs { size_of::<AovSum>() as u64 } else { 0 };
        let adaptive =
            if settings.adaptive.is_some() { (size_of::<f64>() + size_of::<bool>()) as u64 } else { 0 };
        base + aov + adaptive
    }

    /// An empty film of the settings' size with the parts they need: AOV sums
    /// ([`crate::RenderSettings::aovs`]), squared luminances and convergence marks
    /// ([`crate::RenderSettings::adaptive`]).
    pub fn for_settings(settings: &crate::RenderSettings) -> Self {
        let (w, h) = (settings.width, settings.height);
        let film = if settings.aovs { Self::with_aovs(w, h) } else { Self::new(w, h) };
        if settings.adaptive.is_some() { film.with_adaptive() } else { film }
    }

    /// The film with (zeroed) adaptive-sampling state: squared luminances and convergence marks
    /// (9 more bytes per pixel). The film must not have samples yet (their squares are unknown).
    ///
    /// # Panics
    /// If the film has samples.
    pub fn with_adaptive(mut self) -> Self {
        assert!(self.count.iter().all(|&c| c == 0), "adaptive state for a film with samples");
        let n = self.sum.len();
        self.adaptive = Some(AdaptiveState { lum_sq: vec![0.0; n], converged: vec![false; n] });
        self
    }

    /// The film with this adaptive-sampling state (restoring a saved film, bit for bit).
    ///
    /// # Errors
    /// [`FilmSizeError`] if either does not hold `width × height` pixels.
    pub fn with_adaptive_state(
        mut self,
        lum_sq: Vec<f64>,
        converged: Vec<bool>,
    ) -> Result<Self, FilmSizeError> {
        if lum_sq.len() != self.sum.len() || converged.len() != self.sum.len() {
            return Err(FilmSizeError {
                width: self.width,
                height: self.height,
                sums: lum_sq.len(),
                counts: converged.len(),
            });
        }
        self.adaptive = Some(AdaptiveState { lum_sq, converged });
        Ok(self)
    }

    /// Whether the film has adaptive-sampling state.
    pub fn has_adaptive(&self) -> bool {
        self.adaptive.is_some()
    }

    /// Every pixel's sum of squared sample luminances; `None` without adaptive state.
    pub fn lum_sq_sums(&self) -> Option<&[f64]> {
        self.adaptive.as_ref().map(|a| a.lum_sq.as_slice())
    }

    /// Every pixel's convergence mark; `None` without adaptive state.
    pub fn converged(&self) -> Option<&[bool]> {
        self.adaptive.as_ref().map(|a| a.converged.as_slice())
    }

    /// How many pixels have converged; `None` without adaptive state.
    pub fn converged_count(&self) -> Option<u64> {
        self.converged().map(|c| c.iter().filter(|&&c| c).count() as u64)
    }

    /// Whether pixel `i` (row-major) still takes samples: always, without adaptive state.
    #[inline]
    pub fn is_active(&self, i: usize) -> bool {
        self.adaptive.as_ref().is_none_or(|a| !a.converged[i])
    }

    /// Replaces the convergence marks (without adaptive state: nothing). A render shared among
    /// devices tests the sum of their films and gives each film the same marks.
    ///
    /// # Errors
    /// [`FilmSizeError`] unless `marks` holds one mark per pixel.
    pub fn set_converged(&mut self, marks: &[bool]) -> Result<(), FilmSizeError> {
        let Some(a) = &mut self.adaptive else { return Ok(()) };
        if marks.len() != a.converged.len() {
            return Err(FilmSizeError {
                width: self.width,
                height: self.height,
                sums: self.sum.len(),
                counts: marks.len(),
            });
        }
        a.converged.copy_from_slice(marks);
        Ok(())
    }

    /// Tests every pixel not yet converged against `rule` (call it when the film holds the
    /// samples below an index where [`crate::AdaptiveSampling::tests_at`]) and marks those below
    /// the threshold; returns how many pixels have converged (0 without adaptive state).
    pub fn test_convergence(&mut self, rule: &crate::AdaptiveSampling) -> u64 {
        let Some(a) = &mut self.adaptive else { return 0 };
        let mut n = 0;
        for i in 0..self.sum.len() {
            if !a.converged[i] && rule.converged(self.sum[i], a.lum_sq[i], self.count[i]) {
                a.converged[i] = true;
            }
            n += u64::from(a.converged[i]);
        }
        n
    }

    /// An empty film that also sums each sample's [`AovSample`] (64 more bytes per pixel).
    pub fn with_aovs(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Self { aov: Some(vec![AovSum::default(); n]), ..Self::new(width, height) }
    }

    /// An empty film of this one's size, with AOVs if it has them.
    pub fn empty_like(&self) -> Self {
        if self.has_aovs() {
            Self::with_aovs(self.width, self.height)
        } else {
            Self::new(self.width, self.height)
        }
    }

    /// Whether the film sums AOVs.
    pub fn has_aovs(&self) -> bool {
        self.aov.is_some()
    }

    /// Every pixel's AOV sums, row-major; `None` for a film without AOVs.
    pub fn aov_sums(&self) -> Option<&[AovSum]> {
        self.aov.as_deref()
    }

    /// The film with these AOV sums (restoring a saved film: taken bit for bit).
    ///
    /// # Errors
    /// [`FilmSizeError`] if `sums` does not hold `width × height` pixels.
    pub fn with_aov_sums(mut self, sums: Vec<AovSum>) -> Result<Self, FilmSizeError> {
        if sums.len() != self.sum.len() {
            return Err(FilmSizeError {
                width: self.width,
                height: self.height,
                sums: sums.len(),
                counts: self.count.len(),
            });
        }
        self.aov = Some(sums);
        Ok(self)
    }

    /// The means of pixel `i`'s AOVs (row-major index); `None` for a film without AOVs.
    ///
    /// # Panics
    /// If `i` is not below `width × height`.
    pub fn aov(&self, i: usize) -> Option<AovMean> {
        self.aov.as_ref().map(|a| a[i].mean(self.count[i]))
    }

    /// The AOV images as `f32`, row-major (for writers and denoisers): albedo and normal RGB
    /// triples, depth; `None` for a film without AOVs.
    pub fn aov_images(&self) -> Option<AovImages> {
        self.aov.as_ref()?;
        let n = self.sum.len();
        let mut out = AovImages {
            albedo: Vec::with_capacity(n),
            normal: Vec::with_capacity(n),
            depth: Vec::with_capacity(n),
        };
        for i in 0..n {
            let m = self.aov(i)?;
            out.albedo.push(m.albedo.as_vec3());
            out.normal.push(m.normal.as_vec3());
            out.depth.push(m.depth as f32);
        }
        Some(out)
    }

    /// A film from its parts, as [`Film::sums`], [`Film::counts`] and [`Film::rejected`]
    /// return them: restores a saved film exactly, so that rendering can continue
    /// bit-identically (the sums are taken as they are, bit for bit).
    ///
    /// # Errors
    /// [`FilmSizeError`] if `sums` or `counts` do not hold `width × height` pixels.
    pub fn from_parts(
        width: u32,
        height: u32,
        sums: Vec<DVec3>,
        counts: Vec<u64>,
        rejected: u64,
    ) -> Result<Self, FilmSizeError> {
        let pixels = width as usize * height as usize;
        if sums.len() != pixels || counts.len() != pixels {
            return Err(FilmSizeError { width, height, sums: sums.len(), counts: counts.len() });
        }
        Ok(Self { width, height, sum: sums, count: counts, rejected, aov: None, adaptive: None })
    }

    /// Every pixel's `f64` sum of accepted samples, row-major, row 0 at the top.
    pub fn sums(&self) -> &[DVec3] {
        &self.sum
    }

    /// Every pixel's count of accepted samples, row-major, row 0 at the top.
    pub fn counts(&self) -> &[u64] {
        &self.count
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Adds one sample to pixel `(x, y)`; returns `false` (and counts a rejection) if a channel is
    /// NaN or infinite.
    ///
    /// # Panics
    /// If `(x, y)` is outside the film.
    pub fn add_sample(&mut self, x: u32, y: u32, value: Vec3) -> bool {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) outside a {}×{} film",
            self.width,
            self.height
        );
        let i = y as usize * self.width as usize + x as usize;
        let accepted = accumulate(&mut self.sum[i], &mut self.count[i], value);
        self.rejected += u64::from(!accepted);
        if accepted && let Some(a) = &mut self.adaptive {
            a.lum_sq[i] += lum_sq(value);
        }
        accepted
    }

    /// [`Film::add_sample`] with the sample's AOVs, summed (into a film with AOVs) when the
    /// sample is accepted.
    ///
    /// # Panics
    /// If `(x, y)` is outside the film.
    pub fn add_sample_with_aovs(&mut self, x: u32, y: u32, value: Vec3, aov: &AovSample) -> bool {
        let accepted = self.add_sample(x, y, value);
        if accepted && let Some(a) = &mut self.aov {
            a[y as usize * self.width as usize + x as usize].add(aov);
        }
        accepted
    }

    /// The mean of pixel `(x, y)`'s accepted samples (0 without samples).
    ///
    /// # Panics
    /// If `(x, y)` is outside the film.
    pub fn pixel(&self, x: u32, y: u32) -> DVec3 {
        self.mean(self.index(x, y))
    }

    /// The mean of the accepted samples of pixel `i` in row-major order (0 without samples):
    /// [`Film::pixel`] by index.
    ///
    /// # Panics
    /// If `i` is not below `width × height`.
    pub fn mean(&self, i: usize) -> DVec3 {
        if self.count[i] == 0 { DVec3::ZERO } else { self.sum[i] / self.count[i] as f64 }
    }

    /// How many samples pixel `(x, y)` has accepted.
    ///
    /// # Panics
    /// If `(x, y)` is outside the film.
    pub fn sample_count(&self, x: u32, y: u32) -> u64 {
        self.count[self.index(x, y)]
    }

    /// Samples rejected as non-finite since the film was created or cleared.
    pub fn rejected(&self) -> u64 {
        self.rejected
    }

    /// Every pixel's mean as interleaved linear RGB `f32`, row-major, row 0 at the top
    /// (`3·width·height` values): what an image writer takes.
    pub fn to_rgb_f32(&self) -> Vec<f32> {
        (0..self.height)
            .flat_map(|y| (0..self.width).map(move |x| (x, y)))
            .flat_map(|(x, y)| self.pixel(x, y).as_vec3().to_array())
            .collect()
    }

    /// Resets every pixel (and its AOVs) and the rejection count to zero.
    pub fn clear(&mut self) {
        self.sum.fill(DVec3::ZERO);
        self.count.fill(0);
        self.rejected = 0;
        if let Some(a) = &mut self.aov {
            a.fill(AovSum::default());
        }
        if let Some(a) = &mut self.adaptive {
            a.lum_sq.fill(0.0);
            a.converged.fill(false);
        }
    }

    fn index(&self, x: u32, y: u32) -> usize {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) outside a {}×{} film",
            self.width,
            self.height
        );
        y as usize * self.width as usize + x as usize
    }

    /// The film as mutable rows (row 0 first), for rendering rows in parallel: each row adds its
    /// samples with [`FilmRow::add_sample`], and the caller adds the rows' rejections with
    /// [`Film::add_rejected`] afterwards.
    pub fn rows_mut(&mut self) -> Vec<FilmRow<'_>> {
        let w = self.width.max(1) as usize;
        let rows = self.sum.len().div_ceil(w);
        let mut aov = self.aov.as_mut().map(|a| a.chunks_mut(w));
        let (mut lum_sq, mut converged) = match &mut self.adaptive {
            Some(a) => (Some(a.lum_sq.chunks_mut(w)), Some(a.converged.chunks(w))),
            None => (None, None),
        };
        let mut out = Vec::with_capacity(rows);
        for (sum, count) in self.sum.chunks_mut(w).zip(self.count.chunks_mut(w)) {
            out.push(FilmRow {
                sum,
                count,
                aov: aov.as_mut().and_then(Iterator::next),
                lum_sq: lum_sq.as_mut().and_then(Iterator::next),
                converged: converged.as_mut().and_then(Iterator::next),
            });
        }
        out
    }

    /// Adds `n` to the count of rejected samples (samples that [`FilmRow::add_sample`] refused).
    pub fn add_rejected(&mut self, n: u64) {
        self.rejected += n;
    }

    /// Adds `other`'s sums, counts and rejections into this film, pixel by pixel: the film of
    /// two disjoint sets of samples. AOV sums and squared luminances are added when both films
    /// have them (a film given one without keeps its own as they were: call it only with alike
    /// films); convergence marks stay this film's.
    ///
    /// # Errors
    /// [`FilmSizeError`] if `other` is not of this film's size.
    pub fn add_film(&mut self, other: &Film) -> Result<(), FilmSizeError> {
        if (other.width, other.height) != (self.width, self.height) {
            return Err(FilmSizeError {
                width: self.width,
                height: self.height,
                sums: other.sum.len(),
                counts: other.count.len(),
            });
        }
        for (a, b) in self.sum.iter_mut().zip(&other.sum) {
            *a += *b;
        }
        for (a, b) in self.count.iter_mut().zip(&other.count) {
            *a += b;
        }
        self.rejected += other.rejected;
        if let (Some(a), Some(b)) = (&mut self.aov, &other.aov) {
            for (a, b) in a.iter_mut().zip(b) {
                a.add_sum(b);
            }
        }
        if let (Some(a), Some(b)) = (&mut self.adaptive, &other.adaptive) {
            for (a, b) in a.lum_sq.iter_mut().zip(&b.lum_sq) {
                *a += b;
            }
        }
        Ok(())
    }
}

/// [`Film::from_parts`] was given sums or counts for a different number of pixels.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FilmSizeError {
    /// The width given.
    pub width: u32,
    /// The height given.
    pub height: u32,
    /// How many sums were given.
    pub sums: usize,
    /// How many counts were given.
    pub counts: usize,
}

impl std::fmt::Display for FilmSizeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let n = self.width as usize * self.height as usize;
        write!(
            f,
            "a {}×{} film needs {n} pixel sums and counts, got {} sums and {} counts",
            self.width, self.height, self.sums, self.counts
        )
    }
}

impl std::error::Error for FilmSizeError {}

/// One row of a [`Film`], borrowed mutably by one rendering task ([`Film::rows_mut`]).
#[derive(Debug)]
pub struct FilmRow<'a> {
    sum: &'a mut [DVec3],
    count: &'a mut [u64],
    aov: Option<&'a mut [AovSum]>,
    lum_sq: Option<&'a mut [f64]>,
    converged: Option<&'a [bool]>,
}

/// A film's AOVs as `f32` images, row-major from the top ([`Film::aov_images`]).
#[derive(Debug, Clone, PartialEq)]
pub struct AovImages {
    /// Mean albedo.
    pub albedo: Vec<Vec3>,
    /// Mean shading normal (world space, not renormalised).
    pub normal: Vec<Vec3>,
    /// Mean depth of the samples that hit; `+∞` where none did.
    pub depth: Vec<f32>,
}

impl FilmRow<'_> {
    /// Adds a sample to pixel `x` of the row; `false` if it was rejected as non-finite.
    ///
    /// # Panics
    /// If `x` is outside the row.
    #[inline]
    pub fn add_sample(&mut self, x: usize, value: Vec3) -> bool {
        let accepted = accumulate(&mut self.sum[x], &mut self.count[x], value);
        if accepted && let Some(l) = &mut self.lum_sq {
            l[x] += lum_sq(value);
        }
        accepted
    }

    /// Whether pixel `x` of the row still takes samples (not converged under adaptive sampling).
    #[inline]
    pub fn is_active(&self, x: usize) -> bool {
        self.converged.is_none_or(|c| !c[x])
    }

    /// [`FilmRow::add_sample`] with the sample's AOVs (summed if the film has AOVs and the
    /// sample is accepted).
    ///
    /// # Panics
    /// If `x` is outside the row.
    #[inline]
    pub fn add_sample_with_aovs(&mut self, x: usize, value: Vec3, aov: &AovSample) -> bool {
        let accepted = self.add_sample(x, value);
        if accepted && let Some(a) = &mut self.aov {
            a[x].add(aov);
        }
        accepted
    }

    /// Whether the row's film sums AOVs.
    pub fn has_aovs(&self) -> bool {
        self.aov.is_some()
    }
}

/// A sample's squared luminance in `f64`, as the GPU film sums it (`f32` luminance).
#[inline]
fn lum_sq(value: Vec3) -> f64 {
    let l = f64::from(crate::luminance(value));
    l * l
}

#[inline]
fn accumulate(sum: &mut DVec3, count: &mut u64, value: Vec3) -> bool {
    if !value.is_finite() {
        return false;
    }
    *sum += value.as_dvec3();
    *count += 1;
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn from_parts_restores_a_film_exactly() {
        let mut film = Film::new(3, 2);
        film.add_sample(0, 0, Vec3::new(0.1, 0.2, 0.3));
        film.add_sample(2, 1, Vec3::new(1e-8, 3.0, 7.0));
        film.add_sample(2, 1, Vec3::new(f32::NAN, 0.0, 0.0));
        let back =
            Film::from_parts(3, 2, film.sums().to_vec(), film.counts().to_vec(), film.rejected()).unwrap();
        assert_eq!(back, film);
        // Continuing either gives the same film.
        let (mut a, mut b) = (film, back);
        a.add_sample(2, 1, Vec3::splat(0.7));
        b.add_sample(2, 1, Vec3::splat(0.7));
        assert_eq!(a, b);
    }

    #[test]
    fn add_film_sums_disjoint_samples() {
        let (mut a, mut b, mut both) = (Film::new(2, 1), Film::new(2, 1), Film::new(2, 1));
        for (film, v) in [(&mut a, 0.25), (&mut b, 4.0)] {
            film.add_sample(1, 0, Vec3::splat(v));
            film.add_sample(1, 0, Vec3::NAN);
        }
        both.add_sample(1, 0, Vec3::splat(0.25));
        both.add_sample(1, 0, Vec3::splat(4.0));
        both.add_rejected(2);
        a.add_film(&b).unwrap();
        assert_eq!(a, both);
        assert!(a.add_film(&Film::new(1, 2)).is_err());
    }

    #[test]
    fn rows_cover_the_film_in_order() {
        let mut film = Film::new(3, 2);
        for (y, mut row) in film.rows_mut().into_iter().enumerate() {
            assert!(row.add_sample(2, Vec3::splat(y as f32)));
        }
        assert_eq!(film.pixel(2, 1), DVec3::ONE);
        assert_eq!(film.sample_count(2, 0), 1);
        assert_eq!(film.sample_count(0, 0), 0);
    }

    #[test]
    fn aovs_follow_the_accepted_samples() {
        let mut film = Film::with_aovs(2, 1);
        let hit = AovSample { albedo: Vec3::new(0.5, 0.25, 1.0), normal: Vec3::Z, depth: Some(2.0) };
        assert!(film.add_sample_with_aovs(0, 0, Vec3::ONE, &hit));
        assert!(film.add_sample_with_aovs(0, 0, Vec3::ONE, &AovSample::MISS));
        // A rejected sample adds no AOVs either.
        assert!(!film.add_sample_with_aovs(0, 0, Vec3::NAN, &hit));
        let m = film.aov(0).unwrap();
        assert_eq!(m.albedo, DVec3::new(0.75, 0.625, 1.0));
        assert_eq!(m.normal, DVec3::new(0.0, 0.0, 0.5));
        assert_eq!((m.depth, m.coverage), (2.0, 0.5));
        // No samples: no surface seen.
        let empty = film.aov(1).unwrap();
        assert_eq!((empty.depth, empty.coverage, empty.albedo), (f64::INFINITY, 0.0, DVec3::ZERO));
        // Rows add the same sums as the film.
        let mut by_rows = Film::with_aovs(2, 1);
        for mut row in by_rows.rows_mut() {
            row.add_sample_with_aovs(0, Vec3::ONE, &hit);
            row.add_sample_with_aovs(0, Vec3::ONE, &AovSample::MISS);
        }
        assert_eq!(by_rows.aov_sums(), film.aov_sums());
        // Merging films of disjoint samples sums the AOVs; clearing zeroes them.
        let mut twice = film.clone();
        twice.add_film(&film).unwrap();
        assert_eq!(twice.aov_sums().unwrap()[0].hits, 2.0);
        twice.clear();
        assert_eq!(twice.aov_sums().unwrap()[0], AovSum::default());
        // A film without AOVs has none, and ignores them.
        let mut plain = Film::new(1, 1);
        assert!(plain.add_sample_with_aovs(0, 0, Vec3::ONE, &hit));
        assert!(plain.aov(0).is_none() && plain.aov_images().is_none());
    }

    #[test]
    fn from_parts_checks_sizes() {
        let e = Film::from_parts(2, 2, vec![DVec3::ZERO; 4], vec![0; 3], 0).unwrap_err();
        assert_eq!(e.to_string(), "a 2×2 film needs 4 pixel sums and counts, got 4 sums and 3 counts");
        assert!(Film::from_parts(2, 2, vec![DVec3::ZERO; 3], vec![0; 4], 0).is_err());
    }

    #[test]
    fn convergence_marks_are_replaced_whole_and_only_with_adaptive_state() {
        let mut film = Film::new(2, 1).with_adaptive();
        film.add_sample(0, 0, Vec3::ONE);
        film.set_converged(&[false, true]).unwrap();
        assert_eq!(film.converged(), Some(&[false, true][..]));
        assert!(!film.is_active(1) && film.is_active(0));
        assert_eq!(film.sample_count(0, 0), 1, "the sums stay");
        assert!(film.set_converged(&[true]).is_err(), "one mark per pixel");
        assert_eq!(film.converged(), Some(&[false, true][..]), "unchanged by a refused call");
        let mut plain = Film::new(2, 1);
        plain.set_converged(&[true, true]).unwrap();
        assert_eq!(plain.converged(), None, "no marks without adaptive state");
    }
}
