//! Tone curves, sRGB transfer functions and quantisation against known values and independent
//! f64 reference implementations.

use furnace_post::{
    Tonemap, aces_filmic, exposure_scale, linear_to_srgb, pbr_neutral, quantize_unorm8, srgb_to_linear,
    srgb8_to_linear, to_srgb8,
};
use glam::Vec3;

/// Asserts |actual − expected| ≤ tol, printing all three.
#[track_caller]
fn assert_close(actual: f64, expected: f64, tol: f64) {
    let diff = (actual - expected).abs();
    assert!(diff <= tol, "expected {expected}, got {actual}, |diff| = {diff:e} > {tol:e}");
}

#[test]
fn exposure_is_two_to_the_ev() {
    assert_eq!(exposure_scale(0.0), 1.0); // EV 0: radiance unchanged
    assert_eq!(exposure_scale(1.0), 2.0);
    assert_eq!(exposure_scale(-10.0), 1.0 / 1024.0);
    assert_close(f64::from(exposure_scale(0.5)), 2f64.sqrt(), 1e-6);
}

#[test]
fn aces_known_points() {
    assert_eq!(aces_filmic(0.0), 0.0);
    // x = 0.18: numerator 0.18·(2.51·0.18 + 0.03) = 0.18·0.4818 = 0.086724;
    // denominator 0.18·(2.43·0.18 + 0.59) + 0.14 = 0.18·1.0274 + 0.14 = 0.324932;
    // 0.086724 / 0.324932 = 0.26689892… (f32 arithmetic: a few ulp, hence 1e-6).
    assert_close(f64::from(aces_filmic(0.18)), 0.086724 / 0.324932, 1e-6);
    // x = 1: 2.54 / 3.16 = 0.80379746…
    assert_close(f64::from(aces_filmic(1.0)), 2.54 / 3.16, 1e-6);
    // Unclamped the curve tends to 2.51/2.43 = 1.0329 > 1; it crosses 1 at the root of
    // 0.08x² − 0.56x − 0.14, x = (0.56 + √0.3584)/0.16 = 7.2417, and is clamped to 1 beyond.
    let root = (0.56 + 0.3584f64.sqrt()) / 0.16;
    assert_close(root, 7.241_656, 1e-5);
    assert!(aces_filmic(7.2) < 1.0 && aces_filmic(7.2) > 0.999);
    for x in [7.3, 8.0, 100.0, 1e20, f32::MAX, f32::INFINITY] {
        assert_eq!(aces_filmic(x), 1.0, "x = {x}");
    }
    // Defined off the domain: NaN and negatives → 0.
    assert_eq!(aces_filmic(f32::NAN), 0.0);
    assert_eq!(aces_filmic(-0.5), 0.0);
    assert_eq!(aces_filmic(f32::NEG_INFINITY), 0.0);
}

#[test]
fn aces_is_monotonic() {
    let mut prev = 0.0;
    for i in 0..=10_000 {
        let y = aces_filmic(i as f32 * 1e-3);
        assert!(y >= prev, "decreases at x = {}", i as f32 * 1e-3);
        prev = y;
    }
}

/// The Khronos PBR Neutral reference GLSL, transcribed independently in f64.
fn pbr_neutral_f64(c: [f64; 3]) -> [f64; 3] {
    let start_compression = 0.8 - 0.04;
    let desaturation = 0.15;
    let x = c[0].min(c[1].min(c[2]));
    let offset = if x < 0.08 { x - 6.25 * x * x } else { 0.04 };
    let mut c = c.map(|v| v - offset);
    let peak = c[0].max(c[1].max(c[2]));
    if peak < start_compression {
        return c;
    }
    let d = 1.0 - start_compression;
    let new_peak = 1.0 - d * d / (peak + d - start_compression);
    c = c.map(|v| v * new_peak / peak);
    let g = 1.0 - 1.0 / (desaturation * (peak - new_peak) + 1.0);
    c.map(|v| v * (1.0 - g) + new_peak * g)
}

#[test]
fn pbr_neutral_matches_reference() {
    // Grey below the compression start: identity after the toe (minus 0.04 for x ≥ 0.08).
    for g in [0.08f32, 0.2, 0.5, 0.79] {
        let y = pbr_neutral(Vec3::splat(g));
        assert_close(f64::from(y.x), f64::from(g) - 0.04, 1e-6);
    }
    let cases = [
        [0.0, 0.0, 0.0],
        [0.02, 0.02, 0.02],
        [0.05, 0.3, 0.6],
        [0.2, 0.5, 0.7],
        [0.1, 0.5, 0.81],
        [2.0, 1.0, 0.5],
        [10.0, 10.0, 10.0],
        [100.0, 0.5, 0.01],
    ];
    // f32 vs f64 over a dozen operations on values ≤ 1: within ~10 ulp, 1e-6.
    for c in cases {
        let want = pbr_neutral_f64(c);
        let got = pbr_neutral(Vec3::from_array(c.map(|v| v as f32)));
        for k in 0..3 {
            assert_close(f64::from(got[k]), want[k], 1e-6);
        }
    }
}

#[test]
fn tonemap_names_round_trip() {
    for t in Tonemap::ALL {
        assert_eq!(t.to_string().parse::<Tonemap>().unwrap(), t);
    }
    assert_eq!("ACES".parse::<Tonemap>().unwrap(), Tonemap::Aces);
    assert_eq!(" pbr-neutral ".parse::<Tonemap>().unwrap(), Tonemap::PbrNeutral);
    let err = "reinhard".parse::<Tonemap>().unwrap_err();
    assert!(err.to_string().contains("reinhard"), "{err}");
}

#[test]
fn non_finite_inputs_are_defined() {
    let nan = f32::NAN;
    let inf = f32::INFINITY;
    for t in Tonemap::ALL {
        assert_eq!(t.apply(Vec3::splat(nan)), Vec3::ZERO, "{t}: NaN → 0");
        assert_eq!(t.apply(Vec3::splat(inf)), Vec3::ONE, "{t}: +∞ → 1");
        assert_eq!(t.apply(Vec3::splat(-inf)), Vec3::ZERO, "{t}: −∞ → 0");
        let mixed = t.apply(Vec3::new(nan, inf, -1.0));
        assert!(mixed.is_finite() && mixed.cmpge(Vec3::ZERO).all() && mixed.cmple(Vec3::ONE).all());
        // Per-channel maps keep the channels apart; PBR Neutral desaturates a +∞ pixel to white.
        assert_eq!(mixed.y, 1.0, "{t}");
        let px = to_srgb8(&[Vec3::new(nan, inf, 0.0)], 0.0, t);
        assert_eq!(px[0][1], 255, "{t}");
        // Huge exposure overflows finite radiance to +∞: still defined.
        assert!(to_srgb8(&[Vec3::splat(1e30)], 100.0, t)[0] == [255; 3]);
        assert!(to_srgb8(&[Vec3::splat(1.0)], f32::NAN, t)[0] == [0; 3]);
    }
    assert_eq!(to_srgb8(&[Vec3::new(nan, inf, 0.0)], 0.0, Tonemap::Aces)[0], [0, 255, 0]);
}

#[test]
fn srgb_breakpoints() {
    // The breakpoint pair: 12.92 · 0.0031308 = 0.040449936 ≈ 0.04045.
    assert_close(f64::from(linear_to_srgb(0.003_130_8)), 0.040_45, 1e-6);
    assert_close(f64::from(srgb_to_linear(0.040_45)), 0.003_130_8, 1e-6);
    assert_eq!(linear_to_srgb(0.0), 0.0);
    assert_eq!(srgb_to_linear(0.0), 0.0);
    assert_close(f64::from(linear_to_srgb(1.0)), 1.0, 1e-6);
    assert_close(f64::from(srgb_to_linear(1.0)), 1.0, 1e-6);
    // Mid grey: 1.055 · 0.18^(1/2.4) − 0.055 = 0.46135612…
    assert_close(f64::from(linear_to_srgb(0.18)), 1.055 * 0.18f64.powf(1.0 / 2.4) - 0.055, 1e-6);
    // Just either side of the breakpoint, the branches agree to within the standard's ~6e-8
    // discontinuity (plus f32 rounding).
    let below = f64::from(linear_to_srgb(0.003_130_8));
    let above = f64::from(linear_to_srgb(f32::from_bits(0.003_130_8f32.to_bits() + 1)));
    assert_close(above, below, 1e-6);
}

#[test]
fn srgb_round_trip_within_1e6() {
    // f32 powf is accurate to ~1 ulp; through two powf calls the error stays < 1e-6 absolute.
    for i in 0..=100_000 {
        let x = i as f32 / 100_000.0;
        assert_close(f64::from(srgb_to_linear(linear_to_srgb(x))), f64::from(x), 1e-6);
        assert_close(f64::from(linear_to_srgb(srgb_to_linear(x))), f64::from(x), 1e-6);
    }
}

#[test]
fn every_u8_round_trips() {
    for v in 0..=255u8 {
        let lin = srgb8_to_linear(v);
        assert_eq!(quantize_unorm8(linear_to_srgb(lin)), v, "code {v} (linear {lin})");
        // The full pipeline with no exposure and the clamp tone map is also lossless.
        assert_eq!(to_srgb8(&[Vec3::splat(lin)], 0.0, Tonemap::Clamp)[0], [v; 3], "code {v}");
    }
}

#[test]
fn quantisation_rounds_and_clamps() {
    assert_eq!(quantize_unorm8(0.0), 0);
    assert_eq!(quantize_unorm8(1.0), 255);
    assert_eq!(quantize_unorm8(0.5 / 255.0 - 1e-6), 0);
    assert_eq!(quantize_unorm8(0.5 / 255.0 + 1e-6), 1);
    assert_eq!(quantize_unorm8(-3.0), 0);
    assert_eq!(quantize_unorm8(7.0), 255);
    assert_eq!(quantize_unorm8(f32::NAN), 0);
    assert_eq!(quantize_unorm8(f32::INFINITY), 255);
}
