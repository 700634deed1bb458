//! Stratification: the properties that make each sampler converge faster than random.
//!
//! * PMJ02 and Owen-Sobol: every power-of-two prefix of up to 1024 points has **exactly one**
//!   point in every elementary interval `2^a × 2^b` (a + b = log2 n), for several pixels,
//!   seeds and dimension pairs.
//! * CMJ: exactly one sample per cell, fine row and fine column of its grid (square N). For
//!   non-square N (an m × n grid with m·n > N, as Kensler handles it) every fine row
//!   (y = (s + jy)/N) holds exactly one sample, every fine column and every cell at most one.
//!
//! These are exact combinatorial properties: no tolerance.

use furnace_sampling::{Cmj, OwenSobol, Pmj02, Sampler};

/// Returns a description of the first elementary interval that does not hold exactly one point.
fn elementary_interval_violation(points: &[[u32; 2]]) -> Option<String> {
    let n = points.len();
    assert!(n.is_power_of_two());
    let m = n.trailing_zeros();
    for a in 0..=m {
        let b = m - a;
        let mut count = vec![0u32; n];
        for p in points {
            // a = 0 means one column: a shift by 32 is not defined, so special-case it.
            let col = if a == 0 { 0 } else { p[0] >> (32 - a) };
            let row = if b == 0 { 0 } else { p[1] >> (32 - b) };
            count[((row << a) | col) as usize] += 1;
        }
        if let Some(cell) = count.iter().position(|&c| c != 1) {
            return Some(format!(
                "prefix {n}: interval shape {}x{} cell {} holds {} points",
                1u32 << a,
                1u32 << b,
                cell,
                count[cell]
            ));
        }
    }
    None
}

fn check_progressive(name: &str, sampler: &dyn Sampler, dims: &[u32]) {
    for pixel in [0u32, 1, 77, 123_456, u32::MAX] {
        for &dim in dims {
            let points: Vec<[u32; 2]> = (0..1024).map(|i| sampler.bits_2d(pixel, i, dim)).collect();
            for m in 0..=10 {
                let prefix = &points[..1 << m];
                if let Some(v) = elementary_interval_violation(prefix) {
                    panic!("{name}: pixel {pixel}, dims ({dim},{}): {v}", dim + 1);
                }
            }
        }
    }
}

#[test]
fn pmj02_every_power_of_two_prefix_is_a_0m2_net() {
    for seed in [0, 1, 0xC0FFEE] {
        check_progressive("pmj02", &Pmj02::new(seed), &[0, 2, 4, 10]);
    }
}

#[test]
fn owen_sobol_every_power_of_two_prefix_is_a_0m2_net() {
    // Dimensions (4k, 4k+1) of each group are Sobol's first two dimensions, a (0,2)-sequence;
    // (4k+2, 4k+3) are not (Sobol dimensions 2 and 3 have t > 0), so they are not asserted.
    for seed in [0, 1, 0xC0FFEE] {
        check_progressive("sobol", &OwenSobol::new(seed), &[0, 4, 8]);
    }
}

#[test]
fn pmj02_blocks_beyond_the_first_prefix_are_nets_too() {
    // Aligned blocks [k·2^m, (k+1)·2^m) of a (0,2)-sequence are (0,m,2)-nets: this is what
    // keeps a render converging when it resumes at a sample index that is not zero.
    let s = Pmj02::new(9);
    for dim in [0, 2] {
        let points: Vec<[u32; 2]> = (0..4096).map(|i| s.bits_2d(5, i, dim)).collect();
        for m in [4usize, 6, 8] {
            for block in points.chunks(1 << m) {
                if let Some(v) = elementary_interval_violation(block) {
                    panic!("pmj02 dims ({dim},{}): block of {}: {v}", dim + 1, 1 << m);
                }
            }
        }
    }
}

#[test]
fn cmj_one_sample_per_cell_row_and_column() {
    for n_total in [1u32, 4, 9, 16, 64, 100, 256, 1024, 7, 10, 50, 1000] {
        let m = (n_total as f64).sqrt().floor() as u32;
        let n = n_total.div_ceil(m);
        let square = m * n == n_total;
        for seed in [0, 3] {
            let s = Cmj::new(n_total, seed).unwrap();
            for pixel in [0, 9, 4242] {
                for dim in [0, 2, 6] {
                    let mut cell = vec![0u32; (m * n) as usize];
                    let mut fine_col = vec![0u32; (m * n) as usize];
                    let mut fine_row = vec![0u32; n_total as usize];
                    for i in 0..n_total {
                        let [x, y] = s.bits_2d(pixel, i, dim);
                        // Exact integer strata: floor(x · K) = (x · K) >> 32.
                        let strat = |v: u32, k: u32| ((v as u64 * k as u64) >> 32) as usize;
                        // The cell's row is the group of m consecutive fine rows that the
                        // paper's y = (s + jy)/N assigns to grid row s div m; for square N it
                        // is exactly floor(y·n).
                        let row = strat(y, n_total) / m as usize;
                        if square {
                            assert_eq!(row, strat(y, n));
                        }
                        cell[row * m as usize + strat(x, m)] += 1;
                        fine_col[strat(x, m * n)] += 1;
                        fine_row[strat(y, n_total)] += 1;
                    }
                    let ctx = format!("cmj N={n_total} ({m}x{n}) seed {seed} pixel {pixel} dim {dim}");
                    assert!(fine_row.iter().all(|&c| c == 1), "{ctx}: rows {fine_row:?}");
                    if square {
                        assert!(cell.iter().all(|&c| c == 1), "{ctx}: cells {cell:?}");
                        assert!(fine_col.iter().all(|&c| c == 1), "{ctx}: columns {fine_col:?}");
                    } else {
                        assert!(cell.iter().all(|&c| c <= 1), "{ctx}: cells {cell:?}");
                        assert!(fine_col.iter().all(|&c| c <= 1), "{ctx}: columns {fine_col:?}");
                    }
                }
            }
        }
    }
}
