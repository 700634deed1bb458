//! Split renders: ranges of global sample indices, and the bookkeeping of merging films that
//! hold disjoint ranges of one render.
//!
//! A furnace sampler is addressable — the value of dimension `d` of sample `i` of pixel `p`
//! depends only on `(p, i, d, seed)` (and N for a fixed-N sampler) — and a [`crate::Film`] is a
//! per-pixel `f64` sum. So samples `A..B` of an N-sample render can be traced anywhere, and the
//! films of parts holding disjoint ranges that cover `0..N` add up to the film of one run: the
//! same estimator, equal to the single run's sums to the rounding of the `f64` additions (the
//! sums are associated differently; see [`merge_bound`]).
//!
//! This module is the arithmetic of ranges: parsing and printing `A..B` ([`SampleRange`]), and
//! the union, overlaps and gaps of the ranges of a set of parts ([`Coverage`]).

use std::fmt;
use std::str::FromStr;

/// A half-open range of global sample indices `start..end` (`start < end`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct SampleRange {
    /// The first sample index.
    pub start: u32,
    /// One past the last sample index.
    pub end: u32,
}

/// Why a text is not a [`SampleRange`] or a list of them.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("'{text}' is not a sample range A..B (0 ≤ A < B, whole numbers): {reason}")]
pub struct RangeParseError {
    /// The text given.
    pub text: String,
    /// What is wrong with it.
    pub reason: &'static str,
}

impl SampleRange {
    /// `start..end`, or `None` unless `start < end`.
    pub fn new(start: u32, end: u32) -> Option<Self> {
        (start < end).then_some(Self { start, end })
    }

    /// How many sample indices it holds.
    pub fn len(&self) -> u32 {
        self.end - self.start
    }

    /// Never empty (`start < end`); for clippy's `len_without_is_empty`.
    pub fn is_empty(&self) -> bool {
        self.start >= self.end
    }

    /// Part `k` of `parts` equal parts of `0..total` (the first `total % parts` one sample
    /// longer): what array task `k` of `parts` renders. `None` if `k ≥ parts` or the part would
    /// be empty (`total < parts`).
    pub fn part(total: u32, parts: u32, k: u32) -> Option<Self> {
        if k >= parts {
            return None;
        }
        let at = |k: u32| (u64::from(total) * u64::from(k) / u64::from(parts)) as u32;
        Self::new(at(k), at(k + 1))
    }

    /// Whether the two ranges share an index.
    pub fn overlaps(&self, other: &SampleRange) -> bool {
        self.start < other.end && other.start < self.end
    }
}

impl fmt::Display for SampleRange {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}..{}", self.start, self.end)
    }
}

impl FromStr for SampleRange {
    type Err = RangeParseError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let err = |reason| RangeParseError { text: s.to_string(), reason };
        let (a, b) = s.trim().split_once("..").ok_or_else(|| err("no '..'"))?;
        let parse =
            |v: &str| v.trim().parse::<u32>().map_err(|_| err("A and B must be whole numbers below 2³²"));
        let (start, end) = (parse(a)?, parse(b)?);
        Self::new(start, end).ok_or_else(|| err("A must be less than B"))
    }
}

/// A list of ranges, printed and parsed as `A..B,C..D`.
pub fn format_ranges(ranges: &[SampleRange]) -> String {
    ranges.iter().map(ToString::to_string).collect::<Vec<_>>().join(",")
}

/// Parses [`format_ranges`]' output (at least one range).
///
/// # Errors
/// The first range that does not parse.
pub fn parse_ranges(s: &str) -> Result<Vec<SampleRange>, RangeParseError> {
    s.split(',').map(str::parse).collect()
}

/// The ranges held by a set of parts, each range tagged with the index of the part that holds
/// it: their union, where they overlap, and what they miss of `0..total`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Coverage {
    /// The union, as sorted disjoint ranges, adjacent ranges joined.
    pub union: Vec<SampleRange>,
    /// Every pair of parts that hold a common index: `(part, part, the common range)`, each pair
    /// once, the lower part first.
    pub overlaps: Vec<(usize, usize, SampleRange)>,
    /// The ranges of `0..total` that no part holds, sorted.
    pub missing: Vec<SampleRange>,
}

impl Coverage {
    /// The coverage of `held` (`(part, range)` pairs; a part may hold several ranges) against
    /// `0..total`.
    pub fn of(held: &[(usize, SampleRange)], total: u32) -> Self {
        let mut sorted = held.to_vec();
        sorted.sort_by_key(|&(part, r)| (r, part));
        let mut overlaps = Vec::new();
        for (i, (pa, a)) in sorted.iter().enumerate() {
            for (pb, b) in &sorted[i + 1..] {
                if b.start >= a.end {
                    break;
                }
                let common = SampleRange { start: a.start.max(b.start), end: a.end.min(b.end) };
                overlaps.push(((*pa).min(*pb), (*pa).max(*pb), common));
            }
        }
        overlaps.sort();
        let mut union: Vec<SampleRange> = Vec::new();
        for &(_, r) in &sorted {
            match union.last_mut() {
                Some(last) if r.start <= last.end => last.end = last.end.max(r.end),
                _ => union.push(r),
            }
        }
        let mut missing = Vec::new();
        let mut at = 0u32;
        for r in &union {
            if let Some(gap) = SampleRange::new(at, r.start.min(total)) {
                missing.push(gap);
            }
            at = at.max(r.end);
        }
        if let Some(gap) = SampleRange::new(at, total) {
            missing.push(gap);
        }
        Self { union, overlaps, missing }
    }

    /// Samples per pixel the union holds.
    pub fn samples(&self) -> u64 {
        self.union.iter().map(|r| u64::from(r.len())).sum()
    }
}

/// The largest difference that rounding can make between the `f64` sum of a pixel's `n`
/// samples summed in one order and the same samples summed in any other (one run's film
/// against a merge of parts), relative to the sum of their magnitudes `Σ|x|`: each of two
/// summations of `n` terms is within `γ(n−1)·Σ|x|` of the exact sum (Higham, *Accuracy and
/// Stability of Numerical Algorithms*, §4.2: any summation order, `γ(k) = k·u/(1 − k·u)`,
/// `u = 2⁻⁵³`), so they are within `2·γ(n−1)·Σ|x|` of each other. For radiance (never negative)
/// `Σ|x|` is the sum itself: after 10⁶ samples the bound is 2.2·10⁻¹⁰ of the pixel's value, far
/// below an `f32`'s half ulp (3·10⁻⁸), so the image's `f32` values almost always agree bit for
/// bit.
pub fn merge_bound(n: u64) -> f64 {
    let u = f64::EPSILON / 2.0;
    let k = n.saturating_sub(1) as f64;
    2.0 * k * u / (1.0 - k * u)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn r(a: u32, b: u32) -> SampleRange {
        SampleRange::new(a, b).unwrap()
    }

    #[test]
    fn ranges_parse_and_print() {
        assert_eq!("0..16".parse(), Ok(r(0, 16)));
        assert_eq!(" 3 .. 4 ".parse(), Ok(r(3, 4)));
        assert_eq!(r(5, 9).to_string(), "5..9");
        for bad in ["4..4", "5..2", "1-2", "..3", "a..b", "-1..2", "0..4294967296"] {
            assert!(bad.parse::<SampleRange>().is_err(), "{bad}");
        }
        let e = "7..3".parse::<SampleRange>().unwrap_err().to_string();
        assert_eq!(e, "'7..3' is not a sample range A..B (0 ≤ A < B, whole numbers): A must be less than B");
        let list = vec![r(0, 4), r(8, 16)];
        assert_eq!(format_ranges(&list), "0..4,8..16");
        assert_eq!(parse_ranges("0..4,8..16"), Ok(list));
        assert!(parse_ranges("").is_err());
    }

    #[test]
    fn parts_tile_the_render() {
        for (total, parts) in [(64, 4), (10, 3), (7, 7), (1_000_003, 16), (u32::MAX, 5)] {
            let ranges: Vec<_> = (0..parts).map(|k| SampleRange::part(total, parts, k).unwrap()).collect();
            assert_eq!(ranges[0].start, 0);
            assert_eq!(ranges.last().unwrap().end, total);
            for w in ranges.windows(2) {
                assert_eq!(w[0].end, w[1].start);
                assert!(w[1].len().abs_diff(w[0].len()) <= 1, "{total} {parts}: {w:?}");
            }
        }
        assert_eq!(SampleRange::part(3, 4, 0), None, "an empty part");
        assert_eq!(SampleRange::part(64, 4, 4), None);
    }

    #[test]
    fn coverage_finds_overlaps_and_gaps() {
        let c = Coverage::of(&[(0, r(0, 16)), (1, r(32, 48)), (2, r(16, 20))], 64);
        assert_eq!(c.union, [r(0, 20), r(32, 48)]);
        assert!(c.overlaps.is_empty());
        assert_eq!(c.missing, [r(20, 32), r(48, 64)]);
        assert_eq!(c.samples(), 36);

        let c = Coverage::of(&[(2, r(10, 30)), (0, r(0, 16)), (1, r(16, 64)), (3, r(40, 41))], 64);
        assert_eq!(c.overlaps, [(0, 2, r(10, 16)), (1, 2, r(16, 30)), (1, 3, r(40, 41))]);
        assert_eq!(c.union, [r(0, 64)]);
        assert!(c.missing.is_empty());

        // A part beyond the total (a progressive render's later samples) leaves no negative gap.
        let c = Coverage::of(&[(0, r(0, 8)), (1, r(70, 80))], 64);
        assert_eq!(c.missing, [r(8, 64)]);
        assert_eq!(Coverage::of(&[], 4).missing, [r(0, 4)]);
    }

    #[test]
    fn the_merge_bound_is_twice_gamma() {
        assert_eq!(merge_bound(0), 0.0);
        assert_eq!(merge_bound(1), 0.0);
        let b = merge_bound(1_000_000);
        assert!((b / 2.2e-10 - 1.0).abs() < 0.01, "{b}");
    }
}
