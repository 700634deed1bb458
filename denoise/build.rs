//! With the `oidn` feature: checks `OIDN_DIR`, gives this crate's own test, example and bench
//! binaries an rpath to `$OIDN_DIR/lib` (where `libOpenImageDenoise.so.2` is; the OIDN libraries
//! find each other through their own `$ORIGIN` rpath), and hands that directory on to the crates
//! that depend on this one as `DEP_FURNACE_DENOISE_OIDN_LIB_DIR` (see README.md, "Run-time
//! library path": `cargo::rustc-link-arg` reaches only this package's binaries).
//!
//! The `oidn` crate's own build script does the linking (`-L $OIDN_DIR/lib -lOpenImageDenoise`,
//! or pkg-config when `OIDN_DIR` is unset — then the library is a system one and needs no rpath).

use std::env;
use std::path::PathBuf;

fn main() {
    println!("cargo::rerun-if-changed=build.rs");
    println!("cargo::rerun-if-env-changed=OIDN_DIR");
    if env::var_os("CARGO_FEATURE_OIDN").is_none() {
        return;
    }
    let Some(dir) = env::var_os("OIDN_DIR").filter(|d| !d.is_empty()).map(PathBuf::from) else {
        return;
    };
    // The oidn crate's build script runs in its own directory under ~/.cargo/registry, so a
    // relative OIDN_DIR would mean something else there; an rpath must be absolute anyway.
    if !dir.is_absolute() {
        panic!(
            "OIDN_DIR must be an absolute path, got {:?} (OIDN_DIR=$(bash denoise/install-oidn.sh) gives one)",
            dir
        );
    }
    let lib = dir.join("lib");
    if !lib.join("libOpenImageDenoise.so").exists()
        && !lib.join("libOpenImageDenoise.dylib").exists()
        && !lib.join("OpenImageDenoise.lib").exists()
    {
        panic!(
            "OIDN_DIR={} has no lib/libOpenImageDenoise.so: install OIDN 2.5.1 with `bash denoise/install-oidn.sh` \
             and set OIDN_DIR to the directory it prints",
            dir.display()
        );
    }
    let lib = lib.to_str().unwrap_or_else(|| panic!("OIDN_DIR is not UTF-8: {:?}", dir));
    // `-Wl,-rpath,DIR` splits at commas.
    if lib.contains(',') {
        panic!("OIDN_DIR must not contain a comma (it goes into -Wl,-rpath,…): {lib}");
    }
    if env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("windows") {
        // All of this package's linked targets: unit tests, integration tests, examples, benches.
        println!("cargo::rustc-link-arg=-Wl,-rpath,{lib}");
    }
    println!("cargo::metadata=OIDN_LIB_DIR={lib}");
}
