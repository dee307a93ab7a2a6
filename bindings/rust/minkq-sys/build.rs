//! Links libminkq.so: from `MINKQ_LIB_DIR` when set (the CMake build's `capi/` folder or an
//! install's `lib/`), else built here with CMake from the repository this crate lives in (CPU
//! backend unless the `cuda` feature is on or `MINKQ_WITH_CUDA` says otherwise), else, outside the repository (a packaged
//! crate), from an installed minkq that `pkg-config minkq` finds. Dependents get the folder as
//! `DEP_MINKQ_LIB_DIR` and the library's SONAME, `libminkq.so.<MINKQ_ABI_VERSION>`, which the
//! folder must hold, as `DEP_MINKQ_SONAME`.
use std::env;
use std::path::{Path, PathBuf};
use std::process::Command;

fn main() {
    println!("cargo:rerun-if-env-changed=MINKQ_LIB_DIR");
    println!("cargo:rerun-if-env-changed=MINKQ_WITH_CUDA");
    let lib_dir = match env::var_os("MINKQ_LIB_DIR") {
        Some(dir) if !dir.is_empty() => PathBuf::from(dir),
        _ => build_with_cmake(),
    };
    let lib_dir = lib_dir.canonicalize().unwrap_or_else(|e| {
        panic!("MINKQ_LIB_DIR={}: {e}", lib_dir.display());
    });
    if !lib_dir.join("libminkq.so").exists() {
        panic!(
            "{} holds no libminkq.so: point MINKQ_LIB_DIR at the CMake build's capi folder \
             (e.g. build/capi) or unset it to build the library here",
            lib_dir.display()
        );
    }
    let soname = format!("libminkq.so.{}", abi_version());
    if !lib_dir.join(&soname).exists() {
        panic!(
            "{} holds no {soname}: its libminkq.so is of another ABI than these bindings \
             (MINKQ_ABI_VERSION in src/bindings.rs); rebuild or reinstall it",
            lib_dir.display()
        );
    }
    println!("cargo:rerun-if-changed={}", lib_dir.join("libminkq.so").display());
    println!("cargo:rustc-link-search=native={}", lib_dir.display());
    println!("cargo:rustc-link-lib=dylib=minkq");
    println!("cargo:lib_dir={}", lib_dir.display());
    println!("cargo:soname={soname}");
    println!("cargo:rustc-link-arg=-Wl,-rpath,{}", lib_dir.display());
}

/// MINKQ_ABI_VERSION as bindgen wrote it into src/bindings.rs.
fn abi_version() -> u32 {
    let bindings = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").unwrap()).join("src/bindings.rs");
    println!("cargo:rerun-if-changed={}", bindings.display());
    let text = std::fs::read_to_string(&bindings).unwrap_or_else(|e| panic!("{}: {e}", bindings.display()));
    text.lines()
        .find_map(|line| line.strip_prefix("pub const MINKQ_ABI_VERSION: u32 = ")?.strip_suffix(';')?.parse().ok())
        .unwrap_or_else(|| panic!("{} declares no MINKQ_ABI_VERSION", bindings.display()))
}

fn run(command: &mut Command) {
    let status = command.status().unwrap_or_else(|e| panic!("cannot run {command:?}: {e}"));
    if !status.success() {
        panic!("{command:?} failed with {status}");
    }
}

fn build_with_cmake() -> PathBuf {
    let manifest = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").unwrap());
    let root = manifest.join("../../..");
    if !root.join("capi/minkq.h").exists() {
        return installed_lib_dir(&root);
    }
    for dir in ["capi", "core", "CMakeLists.txt"] {
        println!("cargo:rerun-if-changed={}", root.join(dir).display());
    }
    let build = PathBuf::from(env::var_os("OUT_DIR").unwrap()).join("cmake-build");
    // The `cuda` feature asks for the CUDA backend; MINKQ_WITH_CUDA, when set, decides.
    let feature = if env::var_os("CARGO_FEATURE_CUDA").is_some() { "ON" } else { "OFF" };
    let cuda = env::var("MINKQ_WITH_CUDA").unwrap_or_else(|_| feature.into());
    run(Command::new("cmake").arg("-S").arg(&root).arg("-B").arg(&build).args([
        "-DCMAKE_BUILD_TYPE=Release",
        &format!("-DMINKQ_WITH_CUDA={cuda}"),
        "-DMINKQ_BUILD_TESTS=OFF",
        "-DMINKQ_BUILD_EXAMPLES=OFF",
        "-DMINKQ_WITH_MPI=OFF", // libminkq only: its MPI component is not the crate's
    ]));
    let jobs = env::var("NUM_JOBS").unwrap_or_else(|_| "2".into());
    run(Command::new("cmake").arg("--build").arg(&build).args(["--target", "minkq", "-j", &jobs]));
    lib_dir_of(&build)
}

/// The libdir of an installed minkq (`pkg-config --variable=libdir minkq`).
fn installed_lib_dir(root: &Path) -> PathBuf {
    println!("cargo:rerun-if-env-changed=PKG_CONFIG_PATH");
    let output = Command::new("pkg-config").args(["--variable=libdir", "minkq"]).output();
    match output {
        Ok(out) if out.status.success() && !out.stdout.is_empty() => {
            PathBuf::from(String::from_utf8_lossy(&out.stdout).trim())
        }
        _ => panic!(
            "MINKQ_LIB_DIR is unset, {} is not the minkq source tree and pkg-config finds no \
             installed minkq: set MINKQ_LIB_DIR to the folder holding libminkq.so",
            root.display()
        ),
    }
}

fn lib_dir_of(build: &Path) -> PathBuf {
    build.join("capi")
}
