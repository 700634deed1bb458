//! [`AliasTable`]: sampling one of `n` items with probability proportional to a weight, in
//! constant time (Walker 1977, built by Vose's method, 1991).

/// One bin of an [`AliasTable`]: the bin's own item is taken when the coin is below
/// `threshold`, its `alias` otherwise. `#[repr(C)]`, 8 bytes: GPU buffers can hold bins as
/// they are.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct AliasBin {
    /// Probability of keeping the bin's own item, in `[0, 1]`.
    pub threshold: f32,
    /// The item taken otherwise.
    pub alias: u32,
}

/// A discrete distribution over items `0 … n−1` with probabilities `wᵢ / Σw`, sampled in
/// constant time from two numbers: 32 bits that pick a bin uniformly and a coin in `[0, 1)`.
///
/// The bin is `⌊bits · n / 2³²⌋`, so bins are equally likely to `n / 2³²` relative (2·10⁻⁵
/// for 10⁵ items); the coin against the `f32` threshold adds `2⁻²⁴`. A caller that divides
/// by `wᵢ / Σw` is therefore unbiased to those orders.
///
/// ```
/// use furnace_sampling::AliasTable;
/// let table = AliasTable::new(&[1.0, 3.0]).unwrap();
/// assert!((table.probability(1) - 0.75).abs() < 1e-12);
/// // Bin 0 of 2 keeps item 0 with probability 0.5, else takes item 1.
/// assert_eq!(table.sample(0, 0.25), 0);
/// assert_eq!(table.sample(0, 0.75), 1);
/// assert_eq!(table.sample(u32::MAX, 0.0), 1);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct AliasTable {
    bins: Vec<AliasBin>,
    probabilities: Vec<f64>,
}

impl AliasTable {
    /// The table of `weights` (non-finite and negative weights count as 0). `None` when no
    /// weight is positive (nothing to sample) or there are more than `u32::MAX` items.
    pub fn new(weights: &[f64]) -> Option<Self> {
        let n = weights.len();
        if n == 0 || n > u32::MAX as usize {
            return None;
        }
        let clean: Vec<f64> =
            weights.iter().map(|&w| if w.is_finite() && w > 0.0 { w } else { 0.0 }).collect();
        let total: f64 = clean.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let probabilities: Vec<f64> = clean.iter().map(|w| w / total).collect();
        // Vose: scaled probabilities n·pᵢ; pair each bin below 1 with one above.
        let mut scaled: Vec<f64> = probabilities.iter().map(|p| p * n as f64).collect();
        let mut bins: Vec<AliasBin> = (0..n).map(|i| AliasBin { threshold: 1.0, alias: i as u32 }).collect();
        let (mut small, mut large): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| scaled[i] < 1.0);
        while let (Some(&s), Some(&l)) = (small.last(), large.last()) {
            small.pop();
            bins[s] = AliasBin { threshold: scaled[s] as f32, alias: l as u32 };
            scaled[l] -= 1.0 - scaled[s];
            if scaled[l] < 1.0 {
                large.pop();
                small.push(l);
            }
        }
        // What remains is 1 up to rounding: those bins keep their own item.
        Some(Self { bins, probabilities })
    }

    /// Number of items.
    pub fn len(&self) -> usize {
        self.bins.len()
    }

    /// Always false: a table has at least one item.
    pub fn is_empty(&self) -> bool {
        self.bins.is_empty()
    }

    /// The bins, for a GPU buffer (bin `i` belongs to item `i`).
    pub fn bins(&self) -> &[AliasBin] {
        &self.bins
    }

    /// The probability of item `i`, `wᵢ / Σw` (0 out of range).
    pub fn probability(&self, i: usize) -> f64 {
        self.probabilities.get(i).copied().unwrap_or(0.0)
    }

    /// The item for the bin-choosing `bits` (uniform 0.32 fixed point) and the `coin` in
    /// `[0, 1)`.
    pub fn sample(&self, bits: u32, coin: f32) -> usize {
        let bin = ((u64::from(bits) * self.bins.len() as u64) >> 32) as usize;
        let b = self.bins[bin];
        if coin < b.threshold { bin } else { b.alias as usize }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every bin's mass goes to its own item and its alias: summing `threshold` and
    /// `1 − threshold` per item recovers `n·pᵢ` to float rounding.
    #[test]
    fn bins_hold_the_probabilities() {
        let weights: Vec<f64> = (0..97).map(|i| f64::from((i * 37) % 11) + 0.01 * f64::from(i)).collect();
        let t = AliasTable::new(&weights).unwrap();
        let n = weights.len() as f64;
        let mut mass = vec![0.0f64; weights.len()];
        for (i, b) in t.bins().iter().enumerate() {
            mass[i] += f64::from(b.threshold);
            mass[b.alias as usize] += 1.0 - f64::from(b.threshold);
        }
        for (i, m) in mass.iter().enumerate() {
            // Tolerance: the f32 thresholds (6e-8 each, a few bins per item).
            assert!((m / n - t.probability(i)).abs() < 1e-8, "item {i}: {} vs {}", m / n, t.probability(i));
        }
    }

    #[test]
    fn zero_negative_and_nan_weights_are_never_sampled() {
        assert!(AliasTable::new(&[]).is_none());
        assert!(AliasTable::new(&[0.0, -1.0, f64::NAN]).is_none());
        let t = AliasTable::new(&[0.0, 2.0, -1.0, f64::NAN, f64::INFINITY]).unwrap();
        for k in 0..4096u32 {
            let bits = k.wrapping_mul(0x9e37_79b9);
            let coin = (k % 61) as f32 / 61.0;
            assert_eq!(t.sample(bits, coin), 1);
        }
    }
}
