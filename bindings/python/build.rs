//! The extension links the libminkq.so.<ABI> that minkq-sys found or built (MINKQ_LIB_DIR, else a
//! CMake build of this repository in minkq-sys's OUT_DIR; CPU backend unless MINKQ_WITH_CUDA
//! says otherwise) and gets no rpath of its own: a build-tree path must not end up in a wheel.
//! maturin repairs the wheel (pyproject.toml: auditwheel = "repair"): it finds libminkq in the
//! folder minkq-sys passed to the linker, copies it with TBB and xxHash into minkq.libs/ and
//! sets the extension's rpath to $ORIGIN/../minkq.libs. The build tree's extension (pytest in
//! bindings/test.sh) finds the library through LD_LIBRARY_PATH.
use std::env;
use std::fs;
use std::path::PathBuf;

fn main() {
    // Older builds copied the library into the package (python/minkq/libminkq.so.1): a copy
    // left there would ship in a wheel beside the repaired one.
    let stale = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").unwrap()).join("python/minkq/libminkq.so.1");
    let _ = fs::remove_file(stale);
}
