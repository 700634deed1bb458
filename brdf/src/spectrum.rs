//! KHR_materials_dispersion: the index of refraction per wavelength, and the wavelength a
//! path is traced at once it meets a dispersive solid.
//!
//! furnace transports RGB. A dispersive interface bends each wavelength its own way, so a path
//! that meets one is traced from there on at one wavelength λ, drawn once per path
//! ([`sample_wavelength`]), and its throughput is multiplied by an RGB weight `c(λ)/p(λ)`: the
//! colour a unit of light at λ adds to the image, over the density λ was drawn with. Everything
//! after the event (surfaces, emitters, the sky) keeps its RGB values; only the dispersive
//! interfaces read λ ([`dispersed_ior`]).
//!
//! **Why a continuous wavelength and not three RGB indices.** Tracing the red, green and blue
//! channels each at its own index (the extension's non-normative real-time method) splits a
//! white line seen through a prism into three coloured copies with gaps between them: banding,
//! not a spectrum. Drawing λ from a continuous density costs the same one index per path and
//! gives the continuous rainbow; its colour noise is lower too (per channel variance 1.44–1.69
//! of a unit mean against 2 for choosing one of three channels; `docs/materials.md`).
//!
//! **The colour of a wavelength.** `c(λ)` is the CIE 1931 2° colour matching functions under
//! illuminant D65 (the white of linear sRGB / Rec. 709), taken to linear Rec. 709, in 80 bins of
//! 5 nm over 380–780 nm. Spectral colours lie outside the Rec. 709 gamut (their RGB has a
//! negative channel); the negative parts are clipped to 0 and each channel normalised to
//! integrate to 1 over the bins. So the weights of all wavelengths sum to white exactly, and a
//! dispersive solid that does not separate the wavelengths (a window, a slab in a uniform sky)
//! stays white in expectation; a separated band shows the hue of the gamut's edge nearest to the
//! spectral colour, which is also what a display shows. `p(λ)` is proportional to
//! `c_r + c_g + c_b`, so every weight lies in `[0, 3]` and the three sum to 3.
//!
//! The tables are the CIE's: the 1931 standard observer (CIE 018:2019, ISO/CIE 11664-1) and
//! the relative spectral power of D65 (ISO/CIE 11664-2), both at 5 nm.

use crate::Rgb;

/// The shortest wavelength drawn, nm.
pub const LAMBDA_MIN: f32 = 380.0;
/// The longest wavelength drawn, nm.
pub const LAMBDA_MAX: f32 = 780.0;
/// The width of one bin, nm.
pub const BIN_WIDTH: f32 = 5.0;
/// Bins of the wavelength distribution.
pub const BINS: usize = 80;

/// `x̄, ȳ, z̄` of the CIE 1931 2° observer and the relative power of D65 at 380, 385, …, 780 nm.
#[rustfmt::skip]
const CIE: [[f64; 4]; BINS + 1] = [
    [0.001368, 3.9e-05, 0.006450001, 49.9755],
    [0.002236, 6.4e-05, 0.01054999, 52.3118],
    [0.004243, 0.00012, 0.02005001, 54.6482],
    [0.00765, 0.000217, 0.03621, 68.7015],
    [0.01431, 0.000396, 0.06785001, 82.7549],
    [0.02319, 0.00064, 0.1102, 87.1204],
    [0.04351, 0.00121, 0.2074, 91.486],
    [0.07763, 0.00218, 0.3713, 92.4589],
    [0.13438, 0.004, 0.6456, 93.4318],
    [0.21477, 0.0073, 1.0390501, 90.057],
    [0.2839, 0.0116, 1.3856, 86.6823],
    [0.3285, 0.01684, 1.62296, 95.7736],
    [0.34828, 0.023, 1.74706, 104.865],
    [0.34806, 0.0298, 1.7826, 110.936],
    [0.3362, 0.038, 1.77211, 117.008],
    [0.3187, 0.048, 1.7441, 117.41],
    [0.2908, 0.06, 1.6692, 117.812],
    [0.2511, 0.0739, 1.5281, 116.336],
    [0.19536, 0.09098, 1.28764, 114.861],
    [0.1421, 0.1126, 1.0419, 115.392],
    [0.09564, 0.13902, 0.8129501, 115.923],
    [0.05795001, 0.1693, 0.6162, 112.367],
    [0.03201, 0.20802, 0.46518, 108.811],
    [0.0147, 0.2586, 0.3533, 109.082],
    [0.0049, 0.323, 0.272, 109.354],
    [0.0024, 0.4073, 0.2123, 108.578],
    [0.0093, 0.503, 0.1582, 107.802],
    [0.0291, 0.6082, 0.1117, 106.296],
    [0.06327, 0.71, 0.07824999, 104.79],
    [0.1096, 0.7932, 0.05725001, 106.239],
    [0.1655, 0.862, 0.04216, 107.689],
    [0.2257499, 0.9148501, 0.02984, 106.047],
    [0.2904, 0.954, 0.0203, 104.405],
    [0.3597, 0.9803, 0.0134, 104.225],
    [0.4334499, 0.9949501, 0.008749999, 104.046],
    [0.5120501, 1.0, 0.005749999, 102.023],
    [0.5945, 0.995, 0.0039, 100.0],
    [0.6784, 0.9786, 0.002749999, 98.1671],
    [0.7621, 0.952, 0.0021, 96.3342],
    [0.8425, 0.9154, 0.0018, 96.0611],
    [0.9163, 0.87, 0.001650001, 95.788],
    [0.9786, 0.8163, 0.0014, 92.2368],
    [1.0263, 0.757, 0.0011, 88.6856],
    [1.0567, 0.6949, 0.001, 89.3459],
    [1.0622, 0.631, 0.0008, 90.0062],
    [1.0456, 0.5668, 0.0006, 89.8026],
    [1.0026, 0.503, 0.00034, 89.5991],
    [0.9384, 0.4412, 0.00024, 88.6489],
    [0.8544499, 0.381, 0.00019, 87.6987],
    [0.7514, 0.321, 0.0001, 85.4936],
    [0.6424, 0.265, 4.999999e-05, 83.2886],
    [0.5419, 0.217, 3e-05, 83.4939],
    [0.4479, 0.175, 2e-05, 83.6992],
    [0.3608, 0.1382, 1e-05, 81.863],
    [0.2835, 0.107, 0.0, 80.0268],
    [0.2187, 0.0816, 0.0, 80.1207],
    [0.1649, 0.061, 0.0, 80.2146],
    [0.1212, 0.04458, 0.0, 81.2462],
    [0.0874, 0.032, 0.0, 82.2778],
    [0.0636, 0.0232, 0.0, 80.281],
    [0.04677, 0.017, 0.0, 78.2842],
    [0.0329, 0.01192, 0.0, 74.0027],
    [0.0227, 0.00821, 0.0, 69.7213],
    [0.01584, 0.005723, 0.0, 70.6652],
    [0.01135916, 0.004102, 0.0, 71.6091],
    [0.008110916, 0.002929, 0.0, 72.979],
    [0.005790346, 0.002091, 0.0, 74.349],
    [0.004109457, 0.001484, 0.0, 67.9765],
    [0.002899327, 0.001047, 0.0, 61.604],
    [0.00204919, 0.00074, 0.0, 65.7448],
    [0.001439971, 0.00052, 0.0, 69.8856],
    [0.0009999493, 0.0003611, 0.0, 72.4863],
    [0.0006900786, 0.0002492, 0.0, 75.087],
    [0.0004760213, 0.0001719, 0.0, 69.3398],
    [0.0003323011, 0.00012, 0.0, 63.5927],
    [0.0002348261, 8.48e-05, 0.0, 55.0054],
    [0.0001661505, 6e-05, 0.0, 46.4182],
    [0.000117413, 4.24e-05, 0.0, 56.6118],
    [8.307527e-05, 3e-05, 0.0, 66.8054],
    [5.870652e-05, 2.12e-05, 0.0, 65.0941],
    [4.150994e-05, 1.499e-05, 0.0, 63.3828],
];

/// XYZ to linear Rec. 709 (sRGB primaries, D65 white; IEC 61966-2-1).
const XYZ_TO_REC709: [[f64; 3]; 3] = [
    [3.2404542, -1.5371385, -0.4985314],
    [-0.9692660, 1.8760108, 0.0415560],
    [0.0556434, -0.2040259, 1.0572252],
];

/// The wavelength distribution: the probability of each bin and the RGB weight `c/p` of a
/// wavelength drawn in it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WavelengthTable {
    /// `cdf[b]`: the probability of the bins before `b`; `cdf[0] = 0`, `cdf[BINS] = 1`.
    pub cdf: [f32; BINS + 1],
    /// `c(λ)/p(λ)` per channel for a wavelength in bin `b` (constant over the bin).
    pub weight: [[f32; 3]; BINS],
}

/// The wavelength distribution (computed at compile time from the CIE tables).
pub const TABLE: WavelengthTable = table();

/// `c_k` per bin, clipped at 0 and normalised per channel to sum to 1; the trapezoid rule over
/// each bin's two 5 nm samples.
const fn colours() -> [[f64; 3]; BINS] {
    let mut c = [[0.0; 3]; BINS];
    let mut sum = [0.0; 3];
    let mut b = 0;
    while b < BINS {
        let mut xyz = [0.0; 3];
        let mut j = 0;
        while j < 3 {
            xyz[j] = 0.5 * (CIE[b][j] * CIE[b][3] + CIE[b + 1][j] * CIE[b + 1][3]);
            j += 1;
        }
        let mut k = 0;
        while k < 3 {
            let v =
                XYZ_TO_REC709[k][0] * xyz[0] + XYZ_TO_REC709[k][1] * xyz[1] + XYZ_TO_REC709[k][2] * xyz[2];
            c[b][k] = if v > 0.0 { v } else { 0.0 };
            sum[k] += c[b][k];
            k += 1;
        }
        b += 1;
    }
    let mut b = 0;
    while b < BINS {
        let mut k = 0;
        while k < 3 {
            c[b][k] /= sum[k];
            k += 1;
        }
        b += 1;
    }
    c
}

const fn table() -> WavelengthTable {
    let c = colours();
    let mut cdf = [0.0f32; BINS + 1];
    let mut weight = [[0.0f32; 3]; BINS];
    let mut acc = 0.0f64;
    let mut b = 0;
    while b < BINS {
        // p = (c_r + c_g + c_b)/3: the channels each sum to 1.
        let p = (c[b][0] + c[b][1] + c[b][2]) / 3.0;
        let mut k = 0;
        while k < 3 {
            weight[b][k] = if p > 0.0 { (c[b][k] / p) as f32 } else { 0.0 };
            k += 1;
        }
        acc += p;
        cdf[b + 1] = acc as f32;
        b += 1;
    }
    cdf[BINS] = 1.0;
    WavelengthTable { cdf, weight }
}

/// A wavelength drawn for a path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WavelengthSample {
    /// The wavelength, nm, in `[LAMBDA_MIN, LAMBDA_MAX)`.
    pub lambda: f32,
    /// `c(λ)/p(λ)` per channel: multiplies the path's throughput.
    pub weight: Rgb,
}

/// Draws a wavelength from `u` in `[0, 1)`: a bin by the table's CDF (binary search), then
/// uniformly within it (the index varies continuously inside the bin).
#[inline]
pub fn sample_wavelength(u: f32) -> WavelengthSample {
    let cdf = &TABLE.cdf;
    let u = if u.is_finite() { u.clamp(0.0, crate::dielectric::ONE_BELOW) } else { 0.0 };
    // cdf[lo] ≤ u < cdf[hi].
    let (mut lo, mut hi) = (0usize, BINS);
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if cdf[mid] <= u {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let t = ((u - cdf[lo]) / (cdf[lo + 1] - cdf[lo])).clamp(0.0, crate::dielectric::ONE_BELOW);
    let t = if t.is_finite() { t } else { 0.0 };
    WavelengthSample {
        lambda: LAMBDA_MIN + BIN_WIDTH * (lo as f32 + t),
        weight: Rgb::from_array(TABLE.weight[lo]),
    }
}

/// The density of [`sample_wavelength`] at `lambda` nm (per nm; 0 outside the range).
pub fn wavelength_pdf(lambda: f32) -> f32 {
    if !(LAMBDA_MIN..LAMBDA_MAX).contains(&lambda) {
        return 0.0;
    }
    let b = (((lambda - LAMBDA_MIN) / BIN_WIDTH) as usize).min(BINS - 1);
    (TABLE.cdf[b + 1] - TABLE.cdf[b]) / BIN_WIDTH
}

/// The index at `lambda` nm of a material of index `ior` at 587.6 nm (the d line) and
/// KHR_materials_dispersion's `dispersion` = 20/V_d: Cauchy's two terms fitted to the Abbe
/// number, `max(n_d + (n_d − 1)/V_d·(523655/λ² − 1.5168), 1)`, as the extension writes it.
/// A NaN or non-positive `dispersion` leaves `ior`; the result is at least 1 and finite for
/// finite inputs (an infinite index is the dielectric's to clamp).
#[inline]
pub fn dispersed_ior(ior: f32, dispersion: f32, lambda: f32) -> f32 {
    if !(dispersion > 0.0) {
        return ior;
    }
    let n = ior + (ior - 1.0) * (dispersion / 20.0) * (523_655.0 / (lambda * lambda) - 1.5168);
    if n.is_nan() { ior } else { n.max(1.0) }
}

/// The table as WGSL `const` arrays (`SPECTRUM_CDF`, `SPECTRUM_WEIGHT`) and the bin constants,
/// for the GPU integrator's twin of [`sample_wavelength`]: the same `f32` values.
pub fn wgsl() -> String {
    let cdf: Vec<String> = TABLE.cdf.iter().map(|x| format!("{x:?}")).collect();
    let weight: Vec<String> =
        TABLE.weight.iter().map(|w| format!("vec3<f32>({:?}, {:?}, {:?})", w[0], w[1], w[2])).collect();
    format!(
        "const SPECTRUM_BINS: u32 = {BINS}u;\nconst SPECTRUM_LAMBDA_MIN: f32 = {LAMBDA_MIN:?};\n\
         const SPECTRUM_BIN_WIDTH: f32 = {BIN_WIDTH:?};\n\
         const SPECTRUM_CDF = array<f32, {}>({});\nconst SPECTRUM_WEIGHT = array<vec3<f32>, {BINS}>({});\n",
        BINS + 1,
        cdf.join(", "),
        weight.join(", "),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_weights_of_all_wavelengths_sum_to_white() {
        // Σ_b p_b·w_b = Σ_b c_b = 1 per channel; f32 weights and CDF differences round each
        // term by ~6e-8 relative, 80 terms: 1e-5 is far above that and far below any colour.
        let mut sum = Rgb::ZERO;
        for b in 0..BINS {
            sum += (TABLE.cdf[b + 1] - TABLE.cdf[b]) * Rgb::from_array(TABLE.weight[b]);
        }
        assert!((sum - Rgb::ONE).abs().max_element() < 1e-5, "{sum}");
    }

    #[test]
    fn weights_lie_in_zero_to_three_and_sum_to_three() {
        for (b, w) in TABLE.weight.iter().enumerate() {
            let w = Rgb::from_array(*w);
            assert!(w.min_element() >= 0.0 && w.max_element() <= 3.0 + 1e-5, "bin {b}: {w}");
            assert!((w.element_sum() - 3.0).abs() < 1e-5, "bin {b}: {w}");
        }
        assert!(TABLE.cdf.windows(2).all(|p| p[1] >= p[0]));
    }

    #[test]
    fn colour_noise_is_below_choosing_one_of_three_channels() {
        // The variance per channel of one path's weight (the mean is 1): Σ p·w² − 1. Tracing
        // one of three RGB channels at random has weights 3·e_k: variance 2 per channel.
        for k in 0..3 {
            let second: f32 =
                (0..BINS).map(|b| (TABLE.cdf[b + 1] - TABLE.cdf[b]) * TABLE.weight[b][k].powi(2)).sum();
            let variance = second - 1.0;
            assert!((1.3..1.8).contains(&variance), "channel {k}: {variance}");
        }
    }

    #[test]
    fn hues_run_from_blue_to_red() {
        let w = |l: f32| sample_wavelength_at(l).weight;
        assert!(w(450.0).z > w(450.0).x && w(450.0).z > w(450.0).y, "450 nm is blue");
        assert!(w(530.0).y > w(530.0).x && w(530.0).y > w(530.0).z, "530 nm is green");
        assert!(w(620.0).x > w(620.0).y && w(620.0).x > w(620.0).z, "620 nm is red");
    }

    /// The sample at the CDF value of `lambda`'s bin start.
    fn sample_wavelength_at(lambda: f32) -> WavelengthSample {
        let b = ((lambda - LAMBDA_MIN) / BIN_WIDTH) as usize;
        sample_wavelength(0.5 * (TABLE.cdf[b] + TABLE.cdf[b + 1]))
    }

    #[test]
    fn sampling_inverts_the_cdf() {
        for i in 0..4096 {
            let u = (i as f32 + 0.5) / 4096.0;
            let s = sample_wavelength(u);
            assert!((LAMBDA_MIN..LAMBDA_MAX).contains(&s.lambda), "{u} → {}", s.lambda);
            let b = ((s.lambda - LAMBDA_MIN) / BIN_WIDTH) as usize;
            assert!(TABLE.cdf[b] <= u + 1e-6 && u <= TABLE.cdf[b + 1] + 1e-6, "{u} → bin {b}");
            assert!(wavelength_pdf(s.lambda) > 0.0);
        }
        for u in [0.0, -1.0, 1.0, 2.0, f32::NAN, f32::INFINITY] {
            let s = sample_wavelength(u);
            assert!(s.lambda.is_finite() && s.weight.is_finite(), "{u}");
        }
        // The density integrates to 1.
        let total: f32 =
            (0..BINS).map(|b| wavelength_pdf(LAMBDA_MIN + BIN_WIDTH * (b as f32 + 0.5)) * BIN_WIDTH).sum();
        assert!((total - 1.0).abs() < 1e-5, "{total}");
    }

    #[test]
    fn the_index_follows_the_abbe_number() {
        // V_d = (n_d − 1)/(n_F − n_C) at the Fraunhofer d, F and C lines; the extension's
        // constants reproduce it to 0.03 % (523655/486.1² − 523655/656.3² = 1.0003).
        for (ior, dispersion) in [(1.5, 0.33), (2.42, 0.36), (1.33, 1.0), (1.76, 5.0)] {
            let n = |l: f32| dispersed_ior(ior, dispersion, l);
            let v = 20.0 / dispersion;
            assert!((n(587.56) - ior).abs() < 1e-4 * ior, "n_d");
            let abbe = (n(587.56) - 1.0) / (n(486.13) - n(656.27));
            assert!((abbe / v - 1.0).abs() < 1e-3, "{ior} {dispersion}: V {abbe} ≠ {v}");
            assert!(n(400.0) > n(500.0) && n(500.0) > n(700.0), "normal dispersion: blue bends more");
        }
        assert_eq!(dispersed_ior(1.5, 0.0, 400.0), 1.5);
        assert_eq!(dispersed_ior(1.5, f32::NAN, 400.0), 1.5);
        assert_eq!(dispersed_ior(1.0, 5.0, 400.0), 1.0, "an index of 1 has nothing to disperse");
        // An extreme Abbe number drives the red index below 1: clamped there.
        assert_eq!(dispersed_ior(1.5, 100.0, 779.0), 1.0);
        assert!(dispersed_ior(1.5, 1e30, 380.0).is_infinite() || dispersed_ior(1.5, 1e30, 380.0) > 1e20);
        assert_eq!(dispersed_ior(1.5, f32::INFINITY, 587.56 * 1.0001), 1.0);
    }
}
