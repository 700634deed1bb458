//! [`Distribution2D`]: a piecewise-constant density on the unit square, sampled by inverting
//! its marginal and conditional CDFs (pbrt-v4's `PiecewiseConstant2D`).
//!
//! The CDFs are built in `f64` and stored in `f32`; sampling and [`Distribution2D::pdf`] read
//! only the stored `f32` values, so the density the pdf reports is the one sampling realises
//! (each cell's probability is the difference of two stored CDF values), and a GPU twin reading
//! the same tables makes the same choices. A cell whose probability rounds below the CDF's
//! `f32` step (6·10⁻⁸ of its row near the row's end) has probability 0 and is never sampled.

use glam::Vec2;

/// The largest `f32` below 1: sampled positions inside a cell stay below its upper edge.
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// A piecewise-constant 2-D density over `width × height` cells of the unit square, each cell's
/// density proportional to its weight.
#[derive(Debug, Clone, PartialEq)]
pub struct Distribution2D {
    width: u32,
    height: u32,
    /// Per row `j`, its conditional CDF at the end of each cell: `conditional[j·W + i]` =
    /// P(column ≤ i | row j); the row's last entry is exactly 1.
    conditional: Vec<f32>,
    /// The marginal CDF over rows at the end of each row; the last entry is exactly 1.
    marginal: Vec<f32>,
}

/// The first index whose CDF value exceeds `u`: the cell a uniform `u` falls in (`u < 1` and the
/// last value is 1, so the index is in range; cells of zero width are skipped).
#[inline]
fn find(cdf: &[f32], u: f32) -> usize {
    cdf.partition_point(|&c| c <= u).min(cdf.len() - 1)
}

/// The CDF value at the start of cell `i`.
#[inline]
fn start(cdf: &[f32], i: usize) -> f32 {
    if i == 0 { 0.0 } else { cdf[i - 1] }
}

impl Distribution2D {
    /// The distribution of `weights` (row-major, `width × height`, row 0 at `v = 0`). `None` when
    /// the size is zero or does not match, or no weight is positive and finite; negative, NaN
    /// and infinite weights count as 0.
    pub fn new(width: u32, height: u32, weights: &[f64]) -> Option<Self> {
        let (w, h) = (width as usize, height as usize);
        if w == 0 || h == 0 || weights.len() != w.checked_mul(h)? {
            return None;
        }
        let clean = |x: f64| if x.is_finite() && x > 0.0 { x } else { 0.0 };
        let mut conditional = Vec::with_capacity(w * h);
        let mut row_sums = Vec::with_capacity(h);
        for row in weights.chunks_exact(w) {
            let sum: f64 = row.iter().map(|&x| clean(x)).sum();
            row_sums.push(sum);
            let mut acc = 0.0;
            for (i, &x) in row.iter().enumerate() {
                acc += clean(x);
                // A row of zeros (never chosen) gets a uniform CDF, so that it is well formed.
                let c = if sum > 0.0 { acc / sum } else { (i + 1) as f64 / w as f64 };
                conditional.push(c as f32);
            }
            *conditional.last_mut()? = 1.0;
        }
        let total: f64 = row_sums.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let mut marginal = Vec::with_capacity(h);
        let mut acc = 0.0;
        for s in row_sums {
            acc += s;
            marginal.push((acc / total) as f32);
        }
        *marginal.last_mut()? = 1.0;
        Some(Self { width, height, conditional, marginal })
    }

    /// Cells per row.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Rows.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The conditional CDFs, row after row (`width` values each, the end of each cell).
    pub fn conditional_cdf(&self) -> &[f32] {
        &self.conditional
    }

    /// The marginal CDF over rows (`height` values, the end of each row).
    pub fn marginal_cdf(&self) -> &[f32] {
        &self.marginal
    }

    /// A point of the unit square for uniform `u ∈ [0, 1)²` (`u.y` chooses the row, `u.x` the
    /// cell in it; each is then remapped to the position inside the cell), its cell `(i, j)`,
    /// and its density (with respect to area on the unit square).
    pub fn sample(&self, u: Vec2) -> (Vec2, [u32; 2], f32) {
        let j = find(&self.marginal, u.y);
        let (m0, m1) = (start(&self.marginal, j), self.marginal[j]);
        let dv = ((u.y - m0) / (m1 - m0)).clamp(0.0, ONE_MINUS_EPSILON);
        let row = &self.conditional[j * self.width as usize..][..self.width as usize];
        let i = find(row, u.x);
        let (c0, c1) = (start(row, i), row[i]);
        let du = ((u.x - c0) / (c1 - c0)).clamp(0.0, ONE_MINUS_EPSILON);
        let p = Vec2::new((i as f32 + du) / self.width as f32, (j as f32 + dv) / self.height as f32);
        let pdf = (m1 - m0) * (c1 - c0) * (self.width as f32 * self.height as f32);
        (p, [i as u32, j as u32], pdf)
    }

    /// The density of cell `(i, j)` (0 outside the grid).
    pub fn cell_pdf(&self, i: u32, j: u32) -> f32 {
        if i >= self.width || j >= self.height {
            return 0.0;
        }
        let (i, j) = (i as usize, j as usize);
        let row = &self.conditional[j * self.width as usize..][..self.width as usize];
        let pm = self.marginal[j] - start(&self.marginal, j);
        let pc = row[i] - start(row, i);
        pm * pc * (self.width as f32 * self.height as f32)
    }

    /// The density at point `p` of the unit square, with respect to area (points on the upper
    /// or right edge belong to the last cell).
    pub fn pdf(&self, p: Vec2) -> f32 {
        let i = ((p.x * self.width as f32) as u32).min(self.width - 1);
        let j = ((p.y * self.height as f32) as u32).min(self.height - 1);
        self.cell_pdf(i, j)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sampling_realises_the_weights() {
        // 3 × 2 cells; a zero cell and a zero row of the second kind never sampled.
        let w = [1.0, 0.0, 3.0, 2.0, 2.0, 0.0];
        let d = Distribution2D::new(3, 2, &w).unwrap();
        assert_eq!(d.cell_pdf(1, 0), 0.0);
        // Densities: weight × cells / total = w · 6 / 8.
        for (k, &wk) in w.iter().enumerate() {
            let (i, j) = (k as u32 % 3, k as u32 / 3);
            assert!((d.cell_pdf(i, j) - wk as f32 * 0.75).abs() < 1e-6, "cell {i},{j}");
        }
        let mut counts = [0u32; 6];
        let n = 60_000;
        for s in 0..n {
            let u = Vec2::new(((s * 7919) % n) as f32 / n as f32, (s as f32 + 0.5) / n as f32);
            let (p, [i, j], pdf) = d.sample(u);
            assert!(p.x >= 0.0 && p.x < 1.0 && p.y >= 0.0 && p.y < 1.0);
            assert_eq!(pdf, d.pdf(p));
            assert_eq!(pdf, d.cell_pdf(i, j));
            counts[(j * 3 + i) as usize] += 1;
        }
        for (k, &wk) in w.iter().enumerate() {
            let expect = wk / 8.0;
            let got = f64::from(counts[k]) / f64::from(n);
            assert!((got - expect).abs() < 0.01, "cell {k}: {got} vs {expect}");
        }
    }

    #[test]
    fn degenerate_inputs() {
        assert!(Distribution2D::new(0, 1, &[]).is_none());
        assert!(Distribution2D::new(2, 1, &[1.0]).is_none());
        assert!(Distribution2D::new(2, 1, &[0.0, -1.0]).is_none());
        assert!(Distribution2D::new(2, 1, &[f64::NAN, f64::INFINITY]).is_none());
        let d = Distribution2D::new(1, 1, &[5.0]).unwrap();
        let (p, cell, pdf) = d.sample(Vec2::new(0.25, ONE_MINUS_EPSILON));
        assert_eq!((cell, pdf), ([0, 0], 1.0));
        assert!(p.y < 1.0 && (p.x - 0.25).abs() < 1e-7);
    }
}
