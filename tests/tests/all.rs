//! The integration tests of furnace-tests, as one test binary: one compile and link of the
//! crate's dependencies for all of them, instead of one per file (most of CI's build time on
//! 2 cores). Each module is one file beside this one, run alone with
//! `cargo test -p furnace-tests --test all MODULE::`.

#[path = "adaptive.rs"]
mod adaptive;
#[path = "alpha_blend.rs"]
mod alpha_blend;
#[path = "alpha_mask.rs"]
mod alpha_mask;
#[path = "aovs.rs"]
mod aovs;
#[path = "area_lights.rs"]
mod area_lights;
#[path = "backends.rs"]
mod backends;
#[path = "brdf_parity.rs"]
mod brdf_parity;
#[path = "dispersion.rs"]
mod dispersion;
#[path = "display_parity.rs"]
mod display_parity;
#[path = "emission.rs"]
mod emission;
#[path = "environment.rs"]
mod environment;
#[path = "instancing.rs"]
mod instancing;
#[path = "integrator.rs"]
mod integrator;
#[path = "kernel.rs"]
mod kernel;
#[path = "mitsuba.rs"]
mod mitsuba;
#[path = "normal_map.rs"]
mod normal_map;
#[path = "path_parity.rs"]
mod path_parity;
#[path = "pbr_references.rs"]
mod pbr_references;
#[path = "point_lights.rs"]
mod point_lights;
#[path = "present.rs"]
mod present;
#[path = "sampler_parity.rs"]
mod sampler_parity;
#[path = "scene_parity.rs"]
mod scene_parity;
#[path = "stability.rs"]
mod stability;
#[path = "traversal_parity.rs"]
mod traversal_parity;
#[path = "white_furnace.rs"]
mod white_furnace;
