//! Loads one glTF file and prints its statistics and warnings: `cargo run -p furnace-scene
//! --example load_one -- FILE`.
fn main() {
    for f in std::env::args().skip(1) {
        match furnace_scene::Scene::load(&f) {
            Ok(s) => {
                println!("{f}: {:?}", s.stats());
                for w in &s.warnings {
                    println!("  warning: {w}");
                }
            }
            Err(e) => println!("error: {e}"),
        }
    }
}
