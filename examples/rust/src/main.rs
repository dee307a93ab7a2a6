//! The cloth broad phase of `minkq demo`, from Rust.
//!
//! Builds the default scene of `minkq demo` (a twisted sheet of 388 x 388 vertices, 3 turns,
//! radius 0.25 x the mean edge length), runs the VT and EE queries in every mode and prints the
//! same table: candidates, true contacts, false-positive ratio, false negatives, query time
//! (median of 3) and speedup over the box mode.
//!
//! The true contacts are the leaf_exact pairs (the primitive distance test at the leaves)
//! rather than `minkq demo`'s independent double-precision oracle; on the default scene the two
//! are equal, 62694 VT and 192090 EE contacts, and the demo checks that it finds those numbers.
//!
//!     cargo run --release -p minkq-demo -- [--backend cpu|cuda|auto] [--size N] [--radius-factor F]
use std::collections::HashSet;
use std::process::ExitCode;
use std::time::Instant;

use minkq::{Device, Mode, PairBuffer, Query, QueryFlags, QueryKind, Scene, SceneDesc};

const DEFAULT_SIZE: usize = 388;
const DEFAULT_FACTOR: f64 = 0.25;
/// What `minkq demo` prints for the default scene (its reference oracle's contacts).
const REFERENCE_CONTACTS: (usize, usize) = (62694, 192090);

struct Mesh {
    vertices: Vec<[f32; 3]>,
    triangles: Vec<[i32; 3]>,
}

/// n x n vertices on [0,1]^2 at z = 0, vertex (i, j) at index j * n + i; cell (i, j) gives
/// triangles (v00, v10, v11) and (v00, v11, v01). As the oracle's grid_sheet (oracle/).
fn grid_sheet(n: usize) -> Mesh {
    assert!(n >= 2, "n must be >= 2");
    let mut vertices = Vec::with_capacity(n * n);
    for j in 0..n {
        for i in 0..n {
            vertices.push([(i as f64 / (n - 1) as f64) as f32, (j as f64 / (n - 1) as f64) as f32, 0.0]);
        }
    }
    let mut triangles = Vec::with_capacity(2 * (n - 1) * (n - 1));
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let v00 = (j * n + i) as i32;
            let (v10, v01) = (v00 + 1, v00 + n as i32);
            let v11 = v01 + 1;
            triangles.push([v00, v10, v11]);
            triangles.push([v00, v11, v01]);
        }
    }
    Mesh { vertices, triangles }
}

/// grid_sheet(n) twisted about the x axis: (u, v) -> (u, (v - 1/2) cos t, (v - 1/2) sin t),
/// t = turns * 2 pi * u, bit for bit as the oracle's twisted_sheet (double arithmetic,
/// rounded to float).
fn twisted_sheet(n: usize, turns: f64) -> Mesh {
    let mut mesh = grid_sheet(n);
    for p in &mut mesh.vertices {
        let (u, v) = (p[0] as f64, p[1] as f64 - 0.5);
        let t = turns * 2.0 * std::f64::consts::PI * u;
        p[1] = (v * t.cos()) as f32;
        p[2] = (v * t.sin()) as f32;
    }
    mesh
}

/// Every distinct undirected triangle edge as (min, max), sorted: the C API's numbering.
fn derive_edges(triangles: &[[i32; 3]]) -> Vec<[i32; 2]> {
    let mut edges: Vec<[i32; 2]> = triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| [a.min(b), a.max(b)])
        .collect();
    edges.sort_unstable();
    edges.dedup();
    edges
}

/// The mean edge length, summed in edge order in double as the reference does.
fn mean_edge_length(vertices: &[[f32; 3]], edges: &[[i32; 2]]) -> f64 {
    let mut sum = 0.0;
    for e in edges {
        let (a, b) = (vertices[e[0] as usize], vertices[e[1] as usize]);
        let mut d2 = 0.0;
        for k in 0..3 {
            let d = a[k] as f64 - b[k] as f64;
            d2 += d * d;
        }
        sum += f64::sqrt(d2);
    }
    if edges.is_empty() {
        0.0
    } else {
        sum / edges.len() as f64
    }
}

struct Options {
    backend: String,
    size: usize,
    factor: f64,
}

fn parse_args() -> Result<Options, String> {
    let mut options = Options { backend: "auto".into(), size: DEFAULT_SIZE, factor: DEFAULT_FACTOR };
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        let (name, inline) = match arg.split_once('=') {
            Some((n, v)) => (n.to_string(), Some(v.to_string())),
            None => (arg.clone(), None),
        };
        if name == "--help" || name == "-h" {
            return Err("usage: minkq-demo [--backend cpu|cuda|auto] [--size N] [--radius-factor F]".into());
        }
        let value = match inline.or_else(|| args.next()) {
            Some(v) => v,
            None => return Err(format!("option {name} needs a value")),
        };
        match name.as_str() {
            "--backend" => options.backend = value,
            "--size" => {
                options.size = value
                    .parse()
                    .ok()
                    .filter(|s| (2..=20000).contains(s))
                    .ok_or("--size: an integer from 2 to 20000")?
            }
            "--radius-factor" => {
                options.factor =
                    value.parse().ok().filter(|f: &f64| *f >= 0.0).ok_or("--radius-factor: a number >= 0")?
            }
            _ => return Err(format!("unknown option {name}")),
        }
    }
    Ok(options)
}

fn run(options: &Options) -> Result<bool, minkq::Error> {
    let mesh = twisted_sheet(options.size, 3.0);
    let edges = derive_edges(&mesh.triangles);
    let h = mean_edge_length(&mesh.vertices, &edges);
    let r = (options.factor * h) as f32; // the library takes a float radius
    let n = options.size;
    let device = Device::new(&options.backend)?;
    println!(
        "minkq demo (Rust): twisted sheet {n}x{n}, 3 turns: {} vertices, {} triangles, {} edges",
        mesh.vertices.len(),
        mesh.triangles.len(),
        edges.len()
    );
    println!("radius {} = {} x mean edge length {}; device {}", g6(r as f64), options.factor, g6(h), device.name());
    let start = Instant::now();
    let scene = Scene::new(&device, &SceneDesc::new(&mesh.vertices, &mesh.triangles))?;
    println!("scene build {:.1} ms", start.elapsed().as_secs_f64() * 1e3);
    assert_eq!(scene.edges()?, edges, "the library's edge numbering differs from derive_edges");

    let leaf = QueryFlags::LEAF_EXACT;
    // query_into writes memory of ours: a Vec grows to the pairs (a slice would be a fixed
    // capacity, a PairsOut device memory); query below reuses the library's PairBuffer.
    let mut contacts = Vec::new();
    scene.query_into(&Query::vt(Mode::Sphere, r).with_flags(leaf), &mut contacts)?;
    let true_vt: HashSet<[i32; 2]> = contacts.iter().copied().collect();
    scene.query_into(&Query::ee(Mode::CapsuleExact, r).with_flags(leaf), &mut contacts)?;
    let true_ee: HashSet<[i32; 2]> = contacts.iter().copied().collect();
    let mut buffer = PairBuffer::new()?;
    println!("true contacts: the leaf_exact pairs, {} VT and {} EE\n", true_vt.len(), true_ee.len());

    let modes = [
        (QueryKind::Vt, "box", Mode::Box, false),
        (QueryKind::Vt, "sphere", Mode::Sphere, false),
        (QueryKind::Vt, "sphere+leaf_exact", Mode::Sphere, true),
        (QueryKind::Ee, "box", Mode::Box, false),
        (QueryKind::Ee, "capsule_ray", Mode::CapsuleRay, false),
        (QueryKind::Ee, "capsule_exact", Mode::CapsuleExact, false),
        (QueryKind::Ee, "capsule_exact+leaf_exact", Mode::CapsuleExact, true),
    ];
    println!(
        "{:<4} {:<26} {:>12} {:>12} {:>9} {:>10} {:>10} {:>8}",
        "kind", "mode", "candidates", "true", "fp ratio", "false neg", "query ms", "speedup"
    );
    let (mut false_negatives, mut box_ms) = (0usize, 0.0);
    for (kind, name, mode, leaf_exact) in modes {
        let mut query = Query::new(kind, mode, r);
        if leaf_exact {
            query = query.with_flags(leaf);
        }
        let mut times = [0.0f64; 3];
        for t in &mut times {
            let start = Instant::now();
            scene.query(&query, &mut buffer)?;
            *t = start.elapsed().as_secs_f64() * 1e3;
        }
        times.sort_by(|a, b| a.total_cmp(b));
        let ms = times[1];
        if mode == Mode::Box {
            box_ms = ms;
        }
        let got: HashSet<[i32; 2]> = buffer.pairs().iter().copied().collect();
        let truth = if kind == QueryKind::Vt { &true_vt } else { &true_ee };
        let missing = truth.iter().filter(|p| !got.contains(*p)).count();
        false_negatives += missing;
        let fp = if truth.is_empty() { 0.0 } else { (buffer.len() as f64 - truth.len() as f64) / truth.len() as f64 };
        let speedup = if ms > 0.0 { box_ms / ms } else { 0.0 };
        println!(
            "{:<4} {:<26} {:>12} {:>12} {:>9.3} {:>10} {:>10.2} {:>7.2}x",
            kind.name().to_uppercase(),
            name,
            buffer.len(),
            truth.len(),
            fp,
            missing,
            ms,
            speedup
        );
    }
    let mut ok = true;
    if false_negatives > 0 {
        println!("\nFAIL: {false_negatives} true contacts missing from the candidates");
        ok = false;
    } else {
        println!("\nno false negatives");
    }
    if options.size == DEFAULT_SIZE && options.factor == DEFAULT_FACTOR {
        let found = (true_vt.len(), true_ee.len());
        if found == REFERENCE_CONTACTS {
            println!("true contacts equal `minkq demo`'s reference oracle: {} VT, {} EE", found.0, found.1);
        } else {
            println!(
                "FAIL: true contacts {found:?} differ from `minkq demo`'s reference oracle {REFERENCE_CONTACTS:?}"
            );
            ok = false;
        }
    }
    Ok(ok)
}

/// printf's %.6g.
fn g6(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let exponent = x.abs().log10().floor() as i32;
    if (-5..6).contains(&exponent) {
        let decimals = (5 - exponent).max(0) as usize;
        let s = format!("{x:.decimals$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        let s = format!("{x:.5e}");
        let (mantissa, exp) = s.split_once('e').unwrap();
        let mantissa =
            if mantissa.contains('.') { mantissa.trim_end_matches('0').trim_end_matches('.') } else { mantissa };
        let exp: i32 = exp.parse().unwrap();
        format!("{mantissa}e{}{:02}", if exp < 0 { '-' } else { '+' }, exp.abs())
    }
}

fn main() -> ExitCode {
    let options = match parse_args() {
        Ok(o) => o,
        Err(message) => {
            eprintln!("minkq-demo: {message}");
            return ExitCode::from(2);
        }
    };
    match run(&options) {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(e) => {
            eprintln!("minkq-demo: {e}");
            ExitCode::from(3)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_scene_true_contacts_equal_minkq_demo_reference() {
        let mesh = twisted_sheet(DEFAULT_SIZE, 3.0);
        let edges = derive_edges(&mesh.triangles);
        assert_eq!((mesh.vertices.len(), mesh.triangles.len(), edges.len()), (150544, 299538, 450081));
        let h = mean_edge_length(&mesh.vertices, &edges);
        let r = (DEFAULT_FACTOR * h) as f32;
        assert_eq!(g6(r as f64), "0.00235628"); // as `minkq demo` prints it
        assert_eq!(g6(h), "0.00942512");
        let device = Device::cpu().unwrap();
        let scene = Scene::new(&device, &SceneDesc::new(&mesh.vertices, &mesh.triangles)).unwrap();
        let mut buffer = PairBuffer::new().unwrap();
        let leaf = QueryFlags::LEAF_EXACT;
        let vt = scene.query(&Query::vt(Mode::Sphere, r).with_flags(leaf), &mut buffer).unwrap().len();
        let ee = scene.query(&Query::ee(Mode::CapsuleExact, r).with_flags(leaf), &mut buffer).unwrap().len();
        assert_eq!((vt, ee), REFERENCE_CONTACTS);
    }

    #[test]
    fn g6_formats_as_printf() {
        for (x, s) in [
            (0.00235628f64, "0.00235628"),
            (1.0, "1"),
            (123456.0, "123456"),
            (1234567.0, "1.23457e+06"),
            (1e-7, "1e-07"),
            (0.25, "0.25"),
        ] {
            assert_eq!(g6(x), s);
        }
    }
}
