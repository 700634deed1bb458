//! With the `denoise` feature, furnace-denoise's build script publishes the directory of the
//! Open Image Denoise libraries it linked (`DEP_FURNACE_DENOISE_OIDN_LIB_DIR`): the `furnace`
//! binary gets an rpath to it, so it runs without `LD_LIBRARY_PATH`.

fn main() {
    println!("cargo::rerun-if-changed=build.rs");
    println!("cargo::rerun-if-env-changed=DEP_FURNACE_DENOISE_OIDN_LIB_DIR");
    if let Ok(dir) = std::env::var("DEP_FURNACE_DENOISE_OIDN_LIB_DIR") {
        println!("cargo::rustc-link-arg=-Wl,-rpath,{dir}");
    }
}
