//! The extension finds libminkq.so.1 next to itself ($ORIGIN: the copy placed in the package
//! below, which the wheel ships) or, in a build tree, in the folder minkq-sys linked.
use std::env;
use std::fs;
use std::path::PathBuf;

fn main() {
    let lib_dir = PathBuf::from(env::var_os("DEP_MINKQ_LIB_DIR").expect("minkq-sys sets DEP_MINKQ_LIB_DIR"));
    println!("cargo:rustc-cdylib-link-arg=-Wl,-rpath,$ORIGIN:{}", lib_dir.display());
    // Ship the library inside the Python package (python/minkq/libminkq.so.1, git-ignored):
    // maturin puts everything under python/minkq into the wheel.
    let soname = "libminkq.so.1";
    let source = lib_dir.join(soname);
    let package = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").unwrap()).join("python/minkq");
    println!("cargo:rerun-if-changed={}", source.display());
    if source.exists() {
        let target = package.join(soname);
        let _ = fs::remove_file(&target);
        fs::copy(&source, &target)
            .unwrap_or_else(|e| panic!("cannot copy {} into {}: {e}", source.display(), package.display()));
    }
}
