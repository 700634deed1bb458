//! The furnace path tracer on any GPU through [`wgpu`] (Vulkan, Metal, DX12), headless.
//!
//! The WGSL in [`wgsl`] is a twin of the Rust of the CPU crates: the samplers of
//! `furnace-sampling` bit for bit, the BRDFs of `furnace-brdf` to float rounding, the CWBVH
//! traversal of `furnace-accel`'s buffers hit for hit. The parity tests (the workspace's
//! `furnace-tests` crate) run both sides on the same inputs.
//!
//! [`GpuContext`] picks an adapter and opens a device; [`GpuRenderer`] renders a scene into a
//! drift-free [`film::GpuFilm`], read back as a [`furnace_render::Film`].
//!
//! ```no_run
//! use furnace_gpu::{AdapterChoice, GpuContext, GpuRenderer};
//! let scene = furnace_scene::builtin::cornell_box()?;
//! let ctx = GpuContext::new(&AdapterChoice::Best)?;
//! let settings = furnace_render::RenderSettings::default(); // 256², 4 bounces, Owen-Sobol
//! let mut gpu = GpuRenderer::new(ctx, &scene, &scene.default_camera(), settings)?;
//! gpu.render_pass(0, 64)?; // samples 0..64 of every pixel
//! let film = gpu.film()?; // f64 sums and counts, read back
//! println!("pixel (0, 0): {:?}", film.pixel(0, 0));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! | test (in `furnace-tests`) | what it checks |
//! |---|---|
//! | `sampler_parity.rs` | the five samplers bit-identical to furnace-sampling on 5.6·10⁵ cases |
//! | `brdf_parity.rs` | eval / pdf / sample within 1e-5 of furnace-brdf on 1.2·10⁶ records |
//! | `traversal_parity.rs` | same triangle and t as furnace-accel on ≥ 10⁵ rays per scene; stack overflow |
//! | `scene_parity.rs` | attributes, materials, textures and alpha tests as furnace-scene / furnace-cpu |
//! | `integrator.rs` | images against furnace-cpu: same samples → same image; independent → z-test |
//! | `display_parity.rs` | [`display`]'s tone maps and sRGB encoding as furnace-post's, to float rounding; 8-bit codes |
//!
//! This crate's own tests (`film.rs`: 10⁶ frames without drift in both precisions;
//! `errors.rs`: device loss, oversized buffers) and the parity tests need an adapter: in CI
//! that is Mesa's software Vulkan driver (installed by `.ci/run`). A test that finds no
//! adapter **fails**, unless the environment variable `FURNACE_SKIP_GPU_TESTS=1` is set, in
//! which case it prints why and passes (`furnace_tests::gpu::test_context`).

pub mod brdf;
pub mod context;
pub mod display;
pub mod film;
pub mod integrator;
pub mod memory;
pub mod multi;
pub mod present;
pub mod sampling;
pub mod scene;
pub mod shared;
pub mod traverse;
pub mod wgsl;

pub use context::{AdapterChoice, GpuContext, GpuError, pci_address};
pub use integrator::GpuRenderer;
pub use multi::MultiGpuRenderer;
