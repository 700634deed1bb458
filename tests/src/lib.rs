//! Cross-crate tests of furnace and the fixtures every crate's tests share. Test-only
//! (`publish = false`): nothing a user builds depends on it.
//!
//! The tests in `tests/` check one crate against another or against an independent renderer:
//! CPU vs GPU (the WGSL twins of the samplers, BRDFs, scene records and traversal; whole images),
//! both integrators vs the Mitsuba 3 references, and each check written once over both
//! backends ([`backends::Backend`]).
//!
//! The fixtures: [`data`] (the one copy of each test asset, `tests/data/`), [`rng::Rng`] (the
//! tests' seeded generator), [`gltf`] (glTF scenes written in memory, PNG textures),
//! [`chi2`] (the chi-square harness of every sampling routine, with its file output),
//! [`cbox`] (the Cornell box references and the z statistics), [`gpu`] (the GPU test context
//! and small compute kernels), [`layout`] (WGSL struct layouts by reflection), [`lobes`] (the
//! table of BSDF lobes that the chi-square, consistency, white-furnace and GPU parity tests
//! iterate), [`pbr`] (the glTF PBR material references' object regions and per-object score).
//!
//! Crates below this one in the graph use the fixtures from their own integration tests through
//! a dev-dependency (a cycle through dev-dependencies only, which Cargo allows).

pub mod backends;
pub mod cbox;
pub mod chi2;
pub mod data;
pub mod gltf;
pub mod gpu;
pub mod layout;
pub mod lobes;
pub mod pbr;
pub mod rng;

pub use rng::Rng;
