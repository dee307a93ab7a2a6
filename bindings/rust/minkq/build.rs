//! Lets this crate's tests, doctests and examples find libminkq.so at run time without
//! LD_LIBRARY_PATH: an rpath to the folder minkq-sys linked (DEP_MINKQ_LIB_DIR).
fn main() {
    if let Some(dir) = std::env::var_os("DEP_MINKQ_LIB_DIR") {
        println!("cargo:rustc-link-arg=-Wl,-rpath,{}", dir.to_string_lossy());
    }
}
