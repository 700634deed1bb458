//! The kernel harness itself: a kernel that squares its input and counts invocations.

use furnace_tests::gpu::{self as kernel, test_context};

#[test]
fn kernel_round_trips_u32_and_f32_bits() {
    let Some(ctx) = test_context() else { return };
    eprintln!("adapter: {}", ctx.describe());
    let src = format!(
        "{}\n{}",
        kernel::PREAMBLE,
        r#"
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = invocation_index(gid, groups);
    if i >= params.x { return; }
    output[2u * i] = input[i] * input[i];
    output[2u * i + 1u] = bitcast<u32>(sqrt(bitcast<f32>(input[i])));
}
"#
    );
    // More invocations than one dispatch row of 65535 workgroups × 64, to test the 2-D split.
    let n = 65_535 * 64 + 1000;
    let input: Vec<u32> = (0..n).collect();
    let out = kernel::run(&ctx, &src, &input, 2 * n as usize, n).unwrap();
    for i in 0..n as usize {
        assert_eq!(out[2 * i], (i as u32).wrapping_mul(i as u32), "u32 square of {i}");
    }
    // sqrt is correctly rounded on every adapter we target? Not required by WGSL (2.5 ULP
    // allowed); check within 3 ULP on a few normal floats only.
    let probe = [1.0f32, 2.0, 4.0, 0.5];
    let input: Vec<u32> = probe.iter().map(|x| x.to_bits()).collect();
    let out = kernel::run(&ctx, &src, &input, 8, 4).unwrap();
    for (k, x) in probe.iter().enumerate() {
        let got = f32::from_bits(out[2 * k + 1]);
        assert!((got - x.sqrt()).abs() <= 3.0 * f32::EPSILON * x.sqrt(), "sqrt({x}) = {got}");
    }
}

#[test]
fn invalid_wgsl_is_an_error_not_a_panic() {
    let Some(ctx) = test_context() else { return };
    let err = kernel::run(&ctx, "this is not wgsl", &[], 4, 1).unwrap_err();
    eprintln!("{err}");
    assert!(err.to_string().contains("GPU error"), "{err}");
}

/// The layout checker itself: WGSL's vec3 alignment rule (16) shows in the offsets.
#[test]
fn naga_reflection_reports_wgsl_offsets() {
    let src = "struct S { a: f32, b: vec3<f32>, c: u32 }";
    let layout = furnace_tests::layout::wgsl_struct(src, "S");
    assert_eq!(layout.size, 32);
    assert_eq!(layout.members, vec![("a".into(), 0), ("b".into(), 16), ("c".into(), 28)]);
    furnace_tests::layout::assert_layout(src, "S", 32, &[("a", 0), ("b", 16), ("c", 28)]);
    let mismatch = std::panic::catch_unwind(|| {
        furnace_tests::layout::assert_layout(src, "S", 32, &[("a", 0), ("b", 4), ("c", 16)])
    });
    assert!(mismatch.is_err(), "a wrong offset must fail");
}

/// Many contexts, one after another, in one process: each works. Contexts share one
/// `wgpu::Instance` (a `furnace chart` study makes a renderer per configuration and checkpoint,
/// and a driver may run out of instances); this checks that shared-instance contexts stay
/// independent and usable.
#[test]
fn forty_contexts_in_one_process_all_work() {
    if test_context().is_none() {
        return;
    }
    let src = format!(
        "{}\n{}",
        kernel::PREAMBLE,
        r#"
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = invocation_index(gid, groups);
    if i >= params.x { return; }
    output[i] = input[i] + 1u;
}
"#
    );
    for k in 0..40u32 {
        let ctx = test_context().unwrap_or_else(|| panic!("context {k}: no adapter"));
        let out = kernel::run(&ctx, &src, &[k], 1, 1).unwrap();
        assert_eq!(out, [k + 1], "context {k}");
    }
}
