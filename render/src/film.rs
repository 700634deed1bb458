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
#[derive(Debug, Clone, PartialEq)]
pub struct Film {
    width: u32,
    height: u32,
    sum: Vec<DVec3>,
    count: Vec<u64>,
    rejected: u64,
}

impl Film {
    /// An empty (all-zero) film of `width × height` pixels.
    pub fn new(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Self { width, height, sum: vec![DVec3::ZERO; n], count: vec![0; n], rejected: 0 }
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
        Ok(Self { width, height, sum: sums, count: counts, rejected })
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

    /// Resets every pixel and the rejection count to zero.
    pub fn clear(&mut self) {
        self.sum.fill(DVec3::ZERO);
        self.count.fill(0);
        self.rejected = 0;
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
        self.sum
            .chunks_mut(w)
            .zip(self.count.chunks_mut(w))
            .map(|(sum, count)| FilmRow { sum, count })
            .collect()
    }

    /// Adds `n` to the count of rejected samples (samples that [`FilmRow::add_sample`] refused).
    pub fn add_rejected(&mut self, n: u64) {
        self.rejected += n;
    }

    /// Adds `other`'s sums, counts and rejections into this film, pixel by pixel: the film of
    /// two disjoint sets of samples.
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
}

impl FilmRow<'_> {
    /// Adds a sample to pixel `x` of the row; `false` if it was rejected as non-finite.
    ///
    /// # Panics
    /// If `x` is outside the row.
    #[inline]
    pub fn add_sample(&mut self, x: usize, value: Vec3) -> bool {
        accumulate(&mut self.sum[x], &mut self.count[x], value)
    }
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
    fn from_parts_checks_sizes() {
        let e = Film::from_parts(2, 2, vec![DVec3::ZERO; 4], vec![0; 3], 0).unwrap_err();
        assert_eq!(e.to_string(), "a 2×2 film needs 4 pixel sums and counts, got 4 sums and 3 counts");
        assert!(Film::from_parts(2, 2, vec![DVec3::ZERO; 3], vec![0; 4], 0).is_err());
    }
}
