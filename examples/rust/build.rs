//! An rpath to the folder minkq-sys linked, so that `cargo run` needs no LD_LIBRARY_PATH.
fn main() {
    if let Some(dir) = std::env::var_os("DEP_MINKQ_LIB_DIR") {
        println!("cargo:rustc-link-arg=-Wl,-rpath,{}", dir.to_string_lossy());
    }
}
