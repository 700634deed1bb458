//! The furnace path tracer on any GPU through [`wgpu`] (Vulkan, Metal, DX12), headless.
//!
//! The WGSL in [`wgsl`] is a twin of the Rust of the CPU crates: the samplers of
//! `furnace-sampling` bit for bit, the BRDFs of `furnace-brdf` to float rounding, the CWBVH
//! traversal of `furnace-accel`'s buffers hit for hit. Parity tests in `tests/` run both sides
//! on the same inputs.
//!
//! [`GpuContext`] picks an adapter and opens a device; [`kernel`] runs small compute kernels over
//! `u32` buffers (what the parity tests use).
//!
//! # Tests and adapters
//! The tests need an adapter: in CI that is Mesa's lavapipe (software Vulkan, installed by
//! `.ci/run`). A test that finds no adapter **fails**, unless the environment variable
//! `FURNACE_SKIP_GPU_TESTS=1` is set, in which case it prints why and passes (see
//! [`test_context`]).

pub mod brdf;
pub mod context;
pub mod film;
pub mod integrator;
pub mod kernel;
pub mod sampling;
pub mod scene;
pub mod traverse;
pub mod wgsl;

pub use context::{AdapterChoice, GpuContext, GpuError, test_context};
pub use integrator::GpuRenderer;
