//! # furnace-cpu
//!
//! The reference CPU integrator of furnace: a unidirectional path tracer (Kajiya, "The
//! Rendering Equation", SIGGRAPH 1986) with next-event estimation of every light and multiple
//! importance sampling of emitters and sun discs (Veach 1995), BSDF sampling of
//! the glTF metallic-roughness material (`furnace_brdf`), rows rendered in parallel with rayon
//! and accumulated in `f64` ([`furnace_render::Film`]). It is meant to be read: the GPU integrator is its twin.
//!
//! ## The algorithm ([`CpuRenderer::sample`])
//!
//! For sample `index` of pixel `(x, y)`:
//!
//! 1. **Camera ray** through the film point `(x + u₀, y + u₁)` (a one-pixel box filter; row 0 at
//!    the top), `(u₀, u₁)` = sampler dimensions 0–1.
//! 2. **Closest hit** in the BVH (`furnace_accel`; alpha-masked materials are tested in the
//!    traversal). A ray that leaves the scene adds `throughput · sky` and ends the path.
//! 3. At a hit: the position from the barycentrics, the geometric normal `Ng`, and the
//!    interpolated shading normal `Ns` (with the material's normal map applied through the
//!    vertex tangents when it has one). For a double-sided material both normals are turned to
//!    the side the ray came from; the back of a single-sided material is black and ends the
//!    path. The material is evaluated at the hit's UV (`Material::evaluate`) into the layered
//!    glTF BSDF `furnace_brdf::HitBsdf` (`MetallicRoughness`, mixed with a dielectric where it
//!    transmits) with [`RenderSettings::specular`](furnace_render::RenderSettings::specular).
//! 4. **Emission**: `throughput · emissive` is added — on the front of the surface only (emission
//!    is one-sided, as in the references' conventions; the back of a double-sided emitter is dark).
//!    Reached by a BSDF-sampled ray (not the camera's), it is weighted by the power heuristic
//!    against the emitter sample that could have chosen the same point from the previous vertex:
//!    `w = p_bsdf² / (p_bsdf² + p_light²)` with `p_light = P(triangle) · d² / (area · cos θ_light)`.
//! 5. If the path already has [`RenderSettings::bounces`](furnace_render::RenderSettings::bounces) scattering events, it ends here.
//!    Otherwise this hit is a scattering event:
//!    * **Delta sun** (gathered *only* here): if `-sun.direction` is above `Ng` and a
//!      shadow ray from the offset point (`offset_ray_origin(p, Ng)`) reaches infinity, add
//!      `throughput · f(wo, wi)·cos θi · E_sun` (`Bsdf::eval` includes the cosine).
//!    * **Point and spot lights** (delta lights, gathered *only* here): for each, toward `wi`
//!      at distance `d` above `Ng`, a shadow ray stopping `SHADOW_EPSILON·d` short of it; add
//!      `throughput · f(wo, wi)·cos θi · I(−wi, d) / d²` (`PointLight::intensity_towards`: the
//!      spot cone and the range window), nothing where that is not finite (a light on the
//!      surface).
//!    * **Emitters** (next-event estimation): one emissive triangle chosen in proportion to its
//!      power by an alias table (`furnace_scene::Emitters`), a point uniform on its area, a
//!      shadow ray; the sample is weighted by the power heuristic against BSDF sampling.
//!    * **Sun discs**: one direction uniform in each disc's cone, a shadow ray, weighted
//!      likewise; a sampled ray that escapes inside the cone sees the disc's radiance, weighted
//!      against the cone sample ([`RenderSettings::light_sampling`](furnace_render::RenderSettings::light_sampling) chooses BSDF only, light
//!      samples only, or both).
//!    * **BSDF sample** `wi` from three sampler dimensions; `throughput *= eval/pdf`. A
//!      direction above `Ns`'s horizon but below `Ng`'s ends the path. The sky is gathered only
//!      by such sampled rays escaping (step 2).
//!    * **Russian roulette** (if enabled), from the third event on: survive with probability
//!      `q = min(1, max(throughput))`, and divide by `q` (unbiased).
//!
//! With `bounces = B`, light is gathered at up to `B` scattering events (Mitsuba's
//! `max_depth = B + 1`): `B = 0` shows only what the camera sees directly (sky, emitters),
//! `B = 1` is direct lighting.
//!
//! ## Sampler dimensions
//!
//! The path reads the sampler dimensions of [`furnace_render::layout`]: the pixel position
//! first, then four per scattering event (BSDF direction, lobe choice, Russian roulette), then
//! — only in scenes with emitters or a sun disc — a block of eight per event for the light
//! samples.
//!
//! ## Determinism
//!
//! A sample depends only on `(pixel, index, dimension, seed)` and each pixel's samples are added
//! in index order by one task, so a [`furnace_render::Film`] is bit-identical for any thread count
//! (`tests/determinism.rs`).
//!
//! ## Tests
//!
//! * `tests/furnace.rs` — white furnaces (Lambert albedo 1 → 1; GGX α = 1 → the quadrature of
//!   its directional albedo; with Turquin compensation → 1), an emissive sphere seen from inside
//!   (`1 − 2^−(B+1)` exactly: the bounce convention; Russian roulette unbiased), a sunlit floor.
//!
//! In the workspace's `furnace-tests` crate: `mitsuba.rs` — the Cornell box at 256², direct
//! and 4 bounces, against Mitsuba 3 references (per-channel mean ratio within ±0.5%, per-pixel
//! z std in [0.9, 1.15], each pixel's error from its own samples); `stability.rs` — scales
//! 1e-12 … 1e12, extreme radiance, bad geometry; `backends.rs` — fixed-N samplers, every
//! sampler on the white furnace; `alpha_mask.rs` — alpha MASK cut-outs let camera and shadow
//! rays through, pixel by pixel against the analytic values; `normal_map.rs` — normal-mapped
//! Lambert planes shade as the tilted cosine (generated and file tangents, both handedness
//! signs, green up in the image).
//! * `tests/film.rs` — no drift over 10⁶ frames; non-finite samples rejected.
//! * `tests/determinism.rs` — bit-identical films with 1 and 2 threads.
//!
//! `cargo bench -p furnace-cpu` prints Msamples/s on the Cornell box.
//!
//! ## Example
//!
//! ```
//! use furnace_cpu::CpuRenderer;
//! use furnace_render::{Integrator, RenderSettings};
//! use furnace_scene::builtin;
//! use glam::Vec3;
//!
//! // A white furnace: a Lambert sphere of albedo 1 under a sky of radiance 1 looks like the sky.
//! let scene = builtin::furnace_sphere(builtin::lambert(Vec3::ONE), 16);
//! let camera = scene.default_camera();
//! let settings = RenderSettings { width: 16, height: 16, ..Default::default() };
//! let mut renderer = CpuRenderer::new(scene, &camera, settings)?;
//! renderer.render_pass(0, 4)?;
//! let film = renderer.film()?;
//! let centre = film.pixel(8, 8);
//! assert!((centre - glam::DVec3::ONE).abs().max_element() < 1e-3);
//! assert_eq!(film.rejected(), 0);
//! # Ok::<(), furnace_render::RenderError>(())
//! ```

mod integrator;

pub use integrator::CpuRenderer;
