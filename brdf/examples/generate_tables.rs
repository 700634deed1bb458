//! Regenerates `brdf/src/tables.rs`, the Turquin `E_ss` tables and the sheen albedo table:
//! `cargo run --release -p furnace-brdf --example generate_tables`.

fn main() -> std::io::Result<()> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src/tables.rs");
    let tmp = path.with_extension("rs.tmp");
    std::fs::write(&tmp, furnace_brdf::turquin::tables_source())?;
    std::fs::rename(&tmp, &path)?; // atomic: a failed run never leaves a half-written table
    println!("wrote {}", path.display());
    Ok(())
}
