//! src/bindings.rs is bindgen's output for capi/minkq.h (and minkq_async.h, which it includes),
//! checked in. This test runs bindgen again (the `bindgen` command of Debian's bindgen package,
//! or $BINDGEN) with the same arguments and fails if the fresh output differs in any token.
//! Layout does not count: the fresh output is left unformatted and both are compared without
//! whitespace and without the trailing commas that rustfmt adds or drops as it wraps lines. After
//! an intended change to minkq.h, regenerate with
//! `MINKQ_BLESS=1 cargo test -p minkq-sys --test bindgen_fresh` (which writes bindgen's
//! rustfmt-formatted output) and review the diff.
use std::env;
use std::fs;
use std::path::PathBuf;
use std::process::Command;

/// The bindgen arguments that produced src/bindings.rs (after the header path).
const BINDGEN_ARGS: &[&str] = &[
    "--allowlist-function",
    "minkq_.*",
    "--allowlist-type",
    "minkq_.*",
    "--allowlist-var",
    "MINKQ_.*",
    "--size_t-is-usize",
    "--no-prepend-enum-name",
];

/// The token text: no whitespace, no comma before a closing bracket.
fn tokens_only(text: &str) -> String {
    let mut out: String = text.split_whitespace().collect();
    for close in [")", "}", "]", ">"] {
        out = out.replace(&format!(",{close}"), close);
    }
    out
}

#[test]
fn checked_in_bindings_equal_a_fresh_generation() {
    let crate_dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let header = crate_dir.join("../../../capi/minkq.h");
    let checked_in_path = crate_dir.join("src/bindings.rs");
    let checked_in = fs::read_to_string(&checked_in_path).unwrap();
    let program = env::var("BINDGEN").unwrap_or_else(|_| "bindgen".into());

    // Different bindgen versions print the same API differently: compare like with like.
    let version = Command::new(&program)
        .arg("--version")
        .output()
        .unwrap_or_else(|e| panic!("cannot run {program} ({e}): install Debian's bindgen package or set BINDGEN"));
    let version = String::from_utf8_lossy(&version.stdout).trim().replace("bindgen ", "");
    let generated_by = checked_in.lines().next().unwrap_or("").to_string();
    assert!(
        generated_by.contains(&format!("rust-bindgen {version} ")),
        "src/bindings.rs says {generated_by:?} but {program} is {version}: use the same bindgen \
         (Debian 12's package) or regenerate with MINKQ_BLESS=1 and review the diff"
    );

    let bless = env::var_os("MINKQ_BLESS").is_some();
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bindings.fresh.rs");
    let mut command = Command::new(&program);
    command.arg(&header).args(BINDGEN_ARGS).arg("--output").arg(&out);
    if !bless {
        command.arg("--no-rustfmt-bindings"); // the same tokens whether rustfmt is there or not
    }
    let status = command.status().expect("bindgen runs");
    assert!(status.success(), "bindgen failed on {}", header.display());
    let fresh = fs::read_to_string(&out).unwrap();

    if bless {
        fs::write(&checked_in_path, &fresh).unwrap();
        return;
    }
    assert!(
        tokens_only(&fresh) == tokens_only(&checked_in),
        "src/bindings.rs is stale: capi/minkq.h changed. Regenerate with \
         `MINKQ_BLESS=1 cargo test -p minkq-sys --test bindgen_fresh`, review the diff and bump \
         MINKQ_ABI_VERSION if a layout, value or signature changed (fresh output: {})",
        out.display()
    );
}
