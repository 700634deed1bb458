//! The integration tests of furnace-scene, as one test binary: one compile and link of the
//! crate's dependencies for all of them, instead of one per file (most of CI's build time on
//! 2 cores). Each module is one file beside this one, run alone with
//! `cargo test -p furnace-scene --test all MODULE::`.

#[path = "attributes.rs"]
mod attributes;
#[path = "bad_geometry.rs"]
mod bad_geometry;
#[path = "compressed.rs"]
mod compressed;
#[path = "corpus.rs"]
mod corpus;
#[path = "environment.rs"]
mod environment;
#[path = "fuzz.rs"]
mod fuzz;
#[path = "hostile.rs"]
mod hostile;
#[path = "instancing.rs"]
mod instancing;
#[path = "material_extensions.rs"]
mod material_extensions;
#[path = "posing.rs"]
mod posing;
#[path = "scenes.rs"]
mod scenes;
#[path = "textures.rs"]
mod textures;
