//! ABI round trip: cbindgen turns the Rust FFI declarations (src/bindings.rs) back into C
//! headers, which are compiled in one translation unit with capi/minkq.h (and the public headers
//! it includes, put in place):
//! - types and constants, `rs_`-prefixed, under static assertions on the size, alignment and
//!   every field's offset and size of each struct, the size of each enum type and the value of
//!   every enumerator and version macro. The assertions cover the union of both sides' names,
//!   so a field, enumerator or struct present on one side only is a compile error too, even
//!   where it would change no size (a field added into padding);
//! - functions, unprefixed: they redeclare minkq.h's, and any signature that differs is a
//!   "conflicting types" error. The two sides must also declare the same set of functions.
//!
//! Needs `cbindgen` (Debian package cbindgen, or $CBINDGEN) and a C compiler ($CC or cc).
use std::collections::BTreeMap;
use std::env;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

fn crate_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn c_header() -> PathBuf {
    crate_dir().join("../../../capi/minkq.h")
}

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("abi_roundtrip").join(name);
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

// ---- A small C reader: enough for minkq.h and for cbindgen's output -------------------------

/// Structs with their field names, enums with their enumerators, integer `#define`s and the
/// names of the `minkq_` functions declared.
#[derive(Debug, Default)]
struct CDecls {
    structs: BTreeMap<String, Vec<String>>,
    enums: BTreeMap<String, Vec<String>>,
    defines: Vec<String>,
    functions: Vec<String>,
}

fn strip_comments(text: &str) -> String {
    let mut out = String::new();
    let mut rest = text;
    loop {
        let block = rest.find("/*");
        let line = rest.find("//");
        match (block, line) {
            (Some(b), l) if l.map_or(true, |l| b < l) => {
                out.push_str(&rest[..b]);
                let end = rest[b + 2..].find("*/").expect("unterminated comment") + b + 4;
                out.push(' ');
                rest = &rest[end..];
            }
            (_, Some(l)) => {
                out.push_str(&rest[..l]);
                rest = &rest[l..];
                rest = &rest[rest.find('\n').unwrap_or(rest.len())..];
            }
            _ => {
                out.push_str(rest);
                return out;
            }
        }
    }
}

fn tokens(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let chars: Vec<char> = text.chars().collect();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c.is_whitespace() {
            i += 1;
        } else if c.is_alphanumeric() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            out.push(chars[start..i].iter().collect());
        } else {
            out.push(c.to_string());
            i += 1;
        }
    }
    out
}

fn is_ident(t: &str) -> bool {
    t.chars().next().map_or(false, |c| c.is_alphabetic() || c == '_')
}

/// The declared name of each declaration in a struct body: the identifier before `[`, or the
/// last identifier of the declarator.
fn field_names(body: &[String]) -> Vec<String> {
    let mut names = Vec::new();
    for declaration in body.split(|t| t == ";") {
        for declarator in declaration.split(|t| t == ",") {
            let end = declarator.iter().position(|t| t == "[").unwrap_or(declarator.len());
            if let Some(name) = declarator[..end].iter().rev().find(|t| is_ident(t)) {
                names.push(name.clone());
            }
        }
    }
    names
}

fn enumerators(body: &[String]) -> Vec<String> {
    body.split(|t| t == ",").filter_map(|e| e.first().filter(|t| is_ident(t)).cloned()).collect()
}

fn parse_c(text: &str) -> CDecls {
    let text = strip_comments(text);
    let mut decls = CDecls::default();
    for line in text.lines() {
        let words: Vec<&str> = line.split_whitespace().collect();
        if words.len() == 3
            && words[0] == "#define"
            && words[2].trim_matches(|c| c == '(' || c == ')').parse::<i64>().is_ok()
        {
            decls.defines.push(words[1].to_string());
        }
    }
    let code: String = text.lines().filter(|l| !l.trim_start().starts_with('#')).collect::<Vec<_>>().join("\n");
    let t = tokens(&code);
    let mut i = 0;
    while i + 2 < t.len() {
        let keyword = t[i].as_str();
        if (keyword == "struct" || keyword == "enum") && is_ident(&t[i + 1]) && t[i + 2] == "{" {
            let name = t[i + 1].clone();
            let mut depth = 0;
            let mut j = i + 2;
            loop {
                if t[j] == "{" {
                    depth += 1;
                } else if t[j] == "}" {
                    depth -= 1;
                    if depth == 0 {
                        break;
                    }
                }
                j += 1;
            }
            let body = &t[i + 3..j];
            if keyword == "struct" {
                decls.structs.insert(name, field_names(body));
            } else {
                decls.enums.insert(name, enumerators(body));
            }
            i = j;
        } else if t[i].starts_with("minkq_") && t[i + 1] == "(" {
            decls.functions.push(t[i].clone());
        }
        i += 1;
    }
    decls.functions.sort();
    decls
}

// ---- The round trip ---------------------------------------------------------------------------

fn tool(var: &str, default: &str) -> String {
    env::var(var).unwrap_or_else(|_| default.to_string())
}

/// Runs cbindgen with `config` (in tests/abi) on the Rust declarations in `dir`/bindings.rs;
/// returns the header's path.
fn cbindgen(config: &str, header: &str, dir: &Path) -> PathBuf {
    let input = dir.join("bindings.rs");
    let output = dir.join(header);
    let program = tool("CBINDGEN", "cbindgen");
    let result = Command::new(&program)
        .arg("--quiet")
        .arg("--config")
        .arg(crate_dir().join("tests/abi").join(config))
        .arg("--output")
        .arg(&output)
        .arg(&input)
        .output()
        .unwrap_or_else(|e| panic!("cannot run {program} ({e}): install Debian's cbindgen or set CBINDGEN"));
    assert!(result.status.success(), "cbindgen failed: {}", String::from_utf8_lossy(&result.stderr));
    output
}

/// The translation unit asserting that `c` (minkq.h) and `rust` (the rs_-prefixed header)
/// agree; fails to compile on any difference.
fn assertions(c: &CDecls, rust: &CDecls) -> String {
    let strip = |n: &String| n.strip_prefix("rs_").unwrap_or(n).to_string();
    let mut out = String::from(
        "/* Generated by minkq-sys/tests/abi_roundtrip.rs: C (minkq.h) against Rust (bindings.rs via cbindgen). */\n\
         #include <stddef.h>\n#include \"minkq.h\"\n#include \"minkq_from_rust.h\"\n#include \"minkq_functions_from_rust.h\"\n\
         #define SAME_LAYOUT(T) _Static_assert(sizeof(T) == sizeof(rs_##T) && _Alignof(T) == _Alignof(rs_##T), \"ABI drift: size or alignment of \" #T);\n\
         #define SAME_FIELD(T, f) _Static_assert(offsetof(T, f) == offsetof(rs_##T, f) && sizeof(((T*)0)->f) == sizeof(((rs_##T*)0)->f), \"ABI drift: offset or size of \" #T \".\" #f);\n\
         #define SAME_VALUE(V) _Static_assert((V) == (rs_##V), \"ABI drift: value of \" #V);\n",
    );
    // Opaque handles have no body in C and a zero-sized placeholder in Rust: nothing to compare.
    let rust_structs: BTreeMap<String, &Vec<String>> = rust
        .structs
        .iter()
        .filter(|(_, fields)| fields.as_slice() != ["_unused"])
        .map(|(n, f)| (strip(n), f))
        .collect();
    let mut names: Vec<&String> = c.structs.keys().chain(rust_structs.keys()).collect();
    names.sort();
    names.dedup();
    for name in names {
        out += &format!("SAME_LAYOUT({name})\n");
        let mut fields: Vec<&String> = c.structs.get(name).into_iter().flatten().collect();
        fields.extend(rust_structs.get(name).into_iter().flat_map(|f| f.iter()));
        let mut seen = Vec::new();
        for f in fields {
            if !seen.contains(&f) {
                seen.push(f);
                out += &format!("SAME_FIELD({name}, {f})\n");
            }
        }
    }
    for name in c.enums.keys() {
        out += &format!("SAME_LAYOUT({name})\n");
    }
    let mut values: Vec<String> = c.enums.values().flatten().cloned().collect();
    values.extend(c.defines.iter().filter(|d| d.starts_with("MINKQ_")).cloned());
    values.extend(rust.defines.iter().filter(|d| d.starts_with("rs_")).map(strip));
    values.sort();
    values.dedup();
    for v in values {
        out += &format!("SAME_VALUE({v})\n");
    }
    out
}

/// Compiles the round trip of `bindings_rs` against `minkq_h`; Ok, or Err with the compiler's
/// messages.
fn round_trip(name: &str, bindings_rs: &str, minkq_h: &str) -> Result<String, String> {
    let dir = scratch(name);
    fs::write(dir.join("bindings.rs"), bindings_rs).unwrap();
    let rust_types = cbindgen("cbindgen.toml", "minkq_from_rust.h", &dir);
    let rust_functions = cbindgen("cbindgen-functions.toml", "minkq_functions_from_rust.h", &dir);
    fs::write(dir.join("minkq.h"), minkq_h).unwrap();
    let c = parse_c(minkq_h);
    let rust = parse_c(&fs::read_to_string(&rust_types).unwrap());
    let rust_fns = parse_c(&fs::read_to_string(&rust_functions).unwrap()).functions;
    if c.functions != rust_fns {
        let only = |a: &[String], b: &[String]| a.iter().filter(|f| !b.contains(f)).cloned().collect::<Vec<_>>();
        return Err(format!(
            "ABI drift: functions only in minkq.h: {:?}; only in bindings.rs: {:?}",
            only(&c.functions, &rust_fns),
            only(&rust_fns, &c.functions)
        ));
    }
    if c.functions.len() < 20 {
        return Err(format!("the reader found too few functions in minkq.h: {:?}", c.functions));
    }
    let unit = assertions(&c, &rust);
    let source = dir.join("abi_roundtrip.c");
    fs::write(&source, &unit).unwrap();
    let compiler = tool("CC", "cc");
    let result = Command::new(&compiler)
        .args(["-std=c11", "-fsyntax-only", "-Wall", "-Werror"])
        .arg("-I")
        .arg(&dir)
        .arg(&source)
        .output()
        .unwrap_or_else(|e| panic!("cannot run the C compiler {compiler}: {e}"));
    if result.status.success() {
        Ok(unit)
    } else {
        Err(String::from_utf8_lossy(&result.stderr).into_owned())
    }
}

fn bindings() -> String {
    fs::read_to_string(crate_dir().join("src/bindings.rs")).unwrap()
}

/// The C API as one text: minkq.h with each public header it includes (`#include "..."`:
/// minkq_async.h) put in place of its line, so that every declaration is read and compiled.
fn minkq_h() -> String {
    let header = c_header();
    let mut text = String::new();
    for line in fs::read_to_string(&header).unwrap().lines() {
        match line.strip_prefix("#include \"").and_then(|rest| rest.strip_suffix('"')) {
            Some(part) => text += &fs::read_to_string(header.with_file_name(part)).unwrap(),
            None => text += &format!("{line}\n"),
        }
    }
    text
}

/// Inserts `line` as the last line of the body of `struct name`, in either language.
fn add_last_field(text: &str, open: &str, line: &str) -> String {
    let start = text.find(open).unwrap_or_else(|| panic!("{open:?} not found"));
    let close = start + text[start..].find("\n}").unwrap();
    format!("{}\n{}{}", &text[..close], line, &text[close..])
}

#[test]
fn rust_declarations_match_the_c_header() {
    let unit = round_trip("match", &bindings(), &minkq_h())
        .unwrap_or_else(|e| panic!("ABI drift between minkq.h and bindings.rs:\n{e}"));
    // The reader must have found the ABI, or the assertions would be vacuous.
    for expected in [
        "SAME_LAYOUT(minkq_buffer)",
        "SAME_FIELD(minkq_buffer, memory)",
        "SAME_FIELD(minkq_scene_desc, edges)",
        "SAME_FIELD(minkq_geometry_desc, struct_size)",
        "SAME_FIELD(minkq_geometry_desc, thickness)",
        "SAME_VALUE(MINKQ_GEOMETRY_STATIC)",
        "SAME_VALUE(MINKQ_ELEMENT_EDGE)",
        "SAME_FIELD(minkq_query_desc, radius)",
        "SAME_FIELD(minkq_query_info, digest)",
        "SAME_FIELD(minkq_query_stats, candidates)",
        "SAME_FIELD(minkq_bvh_query_desc, second)",
        "SAME_LAYOUT(minkq_status)",
        "SAME_VALUE(MINKQ_ERROR_INTERNAL)",
        "SAME_VALUE(MINKQ_MODE_CAPSULE_EXACT)",
        "SAME_VALUE(MINKQ_SHAPE_BOX)",
        "SAME_VALUE(MINKQ_RESERVE_REBUILD)",
        "SAME_LAYOUT(minkq_reserve_flags)",
        "SAME_VALUE(MINKQ_ABI_VERSION)",
    ] {
        assert!(unit.contains(expected), "the round trip lost {expected}:\n{unit}");
    }
}

#[test]
fn a_field_added_to_the_rust_side_only_fails() {
    // minkq_buffer ends in 4 bytes of padding, so this extra u32 changes no size: only the
    // per-field assertions can catch it.
    let drifted = add_last_field(&bindings(), "pub struct minkq_buffer {", "    pub extra: u32,");
    let err = round_trip("rust_field", &drifted, &minkq_h()).expect_err("a Rust-only field compiled");
    assert!(err.contains("extra"), "{err}");
}

#[test]
fn a_field_added_to_the_c_side_only_fails() {
    let drifted = add_last_field(&minkq_h(), "typedef struct minkq_buffer {", "  uint32_t extra;");
    let err = round_trip("c_field", &bindings(), &drifted).expect_err("a C-only field compiled");
    assert!(err.contains("extra"), "{err}");
}

#[test]
fn a_changed_enum_value_fails() {
    let drifted = minkq_h().replace("MINKQ_MODE_CAPSULE_EXACT = 3", "MINKQ_MODE_CAPSULE_EXACT = 4");
    assert_ne!(drifted, minkq_h());
    let err = round_trip("enum_value", &bindings(), &drifted).expect_err("a changed enumerator compiled");
    assert!(err.contains("value of MINKQ_MODE_CAPSULE_EXACT"), "{err}");
}

#[test]
fn an_enumerator_added_to_one_side_only_fails() {
    let drifted =
        minkq_h().replace("MINKQ_ERROR_INTERNAL = 9", "MINKQ_ERROR_INTERNAL = 9,\n  MINKQ_ERROR_TIMEOUT = 10");
    assert_ne!(drifted, minkq_h());
    let err = round_trip("enumerator", &bindings(), &drifted).expect_err("a C-only enumerator compiled");
    assert!(err.contains("MINKQ_ERROR_TIMEOUT"), "{err}");
}

#[test]
fn a_changed_function_signature_fails() {
    let drifted = bindings().replace(
        "pub fn minkq_scene_refit(scene: *mut minkq_scene, vertices: minkq_buffer)",
        "pub fn minkq_scene_refit(scene: *mut minkq_scene, vertices: *const minkq_buffer)",
    );
    assert_ne!(drifted, bindings());
    let err = round_trip("function_signature", &drifted, &minkq_h()).expect_err("a changed signature compiled");
    assert!(err.contains("conflicting types") && err.contains("minkq_scene_refit"), "{err}");
}

#[test]
fn a_function_missing_on_one_side_fails() {
    let drifted = minkq_h().replace(
        "int minkq_cuda_device_count(void);",
        "int minkq_cuda_device_count(void);\nint minkq_cuda_device_reset(int ordinal);",
    );
    assert_ne!(drifted, minkq_h());
    let err = round_trip("function_set", &bindings(), &drifted).expect_err("a C-only function passed");
    assert!(err.contains("minkq_cuda_device_reset"), "{err}");
}

#[test]
fn a_changed_field_type_fails() {
    let drifted = bindings().replace("pub radius: f32,", "pub radius: f64,");
    assert_ne!(drifted, bindings());
    let err = round_trip("field_type", &drifted, &minkq_h()).expect_err("a changed field type compiled");
    assert!(err.contains("minkq_query_desc"), "{err}");
}
