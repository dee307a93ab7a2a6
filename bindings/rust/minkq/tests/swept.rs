//! Swept positions (`Scene::refit_swept`, `rebuild_swept`, their f64 and buffer variants)
//! through the safe crate: zero motion gives the static pairs and digests; box mode is its
//! definition (each element boxed over both positions) on a sheet flying through another,
//! the finer VT modes nest inside it and keep every contact the step passes through; a vertex
//! and an edge flying far through still ones are found, where static queries at either end
//! find nothing; leaf-exact and the EE segment modes are refused; float64 steps; positions of
//! the other precision are refused (naming the buffer), as are bad counts and NaNs, and the
//! scene keeps its state; every plain refit or rebuild makes the scene static again.
mod common;
use common::oracle::{assert_subset, point_triangle_sq, V};
use common::{grid_triangles, Rng};

use minkq::{
    Buffer, CountOut, Device, Error, Memory, Mode, PairBuffer, PairsOut, Query, QueryFlags, Reserve, Scene, SceneDesc,
    Stream,
};

const VT_MODES: [Mode; 4] = [Mode::Box, Mode::Sphere, Mode::CapsuleRay, Mode::CapsuleExact];
const N: i32 = 8;
const R: f32 = 0.05;

fn pairs(scene: &Scene, query: Query) -> Vec<[i32; 2]> {
    let mut out = Vec::new();
    scene.query_into(&query.with_flags(query.flags | QueryFlags::CANONICAL), &mut out).unwrap();
    out
}

fn pairs_and_digest(scene: &Scene, query: Query) -> (Vec<[i32; 2]>, Option<u64>) {
    let mut out = Vec::new();
    let info = scene.query_into(&query.with_flags(QueryFlags::CANONICAL | QueryFlags::DIGEST), &mut out).unwrap();
    (out, info.digest)
}

type Positions = Vec<[f32; 3]>;

/// Two jittered N x N sheets over the unit square and their triangles: sheet 0 (vertices
/// 0..N*N) still near z = 0, sheet 1 (vertices N*N..) at `lift` above it at t = 0 and, at
/// t = 1, sheared, waved and `lift` below it: it flies through sheet 0 over the step.
fn two_sheets(seed: u64, lift: f32) -> (Positions, Positions, Vec<[i32; 3]>) {
    let mut rng = Rng(seed);
    let (mut x0, mut x1) = (Vec::new(), Vec::new());
    for sheet in 0..2 {
        for j in 0..N {
            for i in 0..N {
                let (u, v) = (i as f32 / (N - 1) as f32, j as f32 / (N - 1) as f32);
                let jitter = 0.02 * (rng.uniform() as f32 - 0.5);
                if sheet == 0 {
                    x0.push([u, v, jitter]);
                    x1.push([u, v, jitter]);
                } else {
                    x0.push([u + 0.05, v, lift + jitter]);
                    x1.push([u + 0.2, v - 0.1, -lift + 0.1 * (6.0 * u).sin() + jitter]);
                }
            }
        }
    }
    let mut triangles = grid_triangles(N);
    let upper: Vec<[i32; 3]> = triangles.iter().map(|t| t.map(|v| v + N * N)).collect();
    triangles.extend(upper);
    (x0, x1, triangles)
}

fn lerp(a: [f32; 3], b: [f32; 3], t: f64) -> V {
    [0, 1, 2].map(|k| f64::from(a[k]) + t * (f64::from(b[k]) - f64::from(a[k])))
}
/// The box of `vertices` over both positions.
fn swept_box(x0: &[[f32; 3]], x1: &[[f32; 3]], vertices: &[i32]) -> (V, V) {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for &v in vertices {
        for p in [x0[v as usize], x1[v as usize]] {
            for k in 0..3 {
                lo[k] = lo[k].min(f64::from(p[k]));
                hi[k] = hi[k].max(f64::from(p[k]));
            }
        }
    }
    (lo, hi)
}

/// The largest per-axis gap between two boxes (<= r: box mode reports the pair).
fn gap((alo, ahi): (V, V), (blo, bhi): (V, V)) -> f64 {
    (0..3).map(|k| (alo[k] - bhi[k]).max(blo[k] - ahi[k])).fold(f64::NEG_INFINITY, f64::max)
}

/// Box mode equals its definition on every pair, away from the boundary (gaps within 1e-5 of
/// r may go either way in float): incident pairs dropped, EE pairs once.
fn check_box_definition(scene: &Scene, x0: &[[f32; 3]], x1: &[[f32; 3]], triangles: &[[i32; 3]], what: &str) {
    let (r, eps) = (f64::from(R), 1e-5);
    let vt = pairs(scene, Query::vt(Mode::Box, R));
    let (mut inside, mut outside) = (0, 0);
    for v in 0..x0.len() as i32 {
        for (t, tri) in triangles.iter().enumerate() {
            if tri.contains(&v) {
                continue;
            }
            let g = gap(swept_box(x0, x1, &[v]), swept_box(x0, x1, tri));
            let found = vt.binary_search(&[v, t as i32]).is_ok();
            if g <= r - eps {
                assert!(found, "{what}: VT ({v}, {t}) gap {g} missed");
                inside += 1;
            } else if g > r + eps {
                assert!(!found, "{what}: VT ({v}, {t}) gap {g} reported");
                outside += 1;
            }
        }
    }
    assert!(inside > 100 && outside > 100, "{what}: VT {inside} in, {outside} out");
    let edges = scene.edges().unwrap();
    let ee = pairs(scene, Query::ee(Mode::Box, R));
    let mut inside = 0;
    for (e, a) in edges.iter().enumerate() {
        for (f, b) in edges.iter().enumerate().skip(e + 1) {
            if a.iter().any(|v| b.contains(v)) {
                continue;
            }
            let g = gap(swept_box(x0, x1, a), swept_box(x0, x1, b));
            let found = ee.binary_search(&[e as i32, f as i32]).is_ok();
            if g <= r - eps {
                assert!(found, "{what}: EE ({e}, {f}) gap {g} missed");
                inside += 1;
            } else if g > r + eps {
                assert!(!found, "{what}: EE ({e}, {f}) gap {g} reported");
            }
        }
    }
    assert!(inside > 100, "{what}: EE {inside} in");
}

#[test]
fn zero_motion_gives_the_static_pairs() {
    let device = Device::cpu().unwrap();
    let (x, _, triangles) = two_sheets(1, 0.03); // sheet 1 within r of sheet 0
    let fixed = Scene::new(&device, &SceneDesc::new(&x, &triangles)).unwrap();
    for rebuild in [false, true] {
        let mut still = Scene::new(&device, &SceneDesc::new(&x, &triangles)).unwrap();
        if rebuild {
            still.rebuild_swept(&x, &x).unwrap();
        } else {
            still.refit_swept(&x, &x).unwrap();
        }
        assert!(still.is_swept());
        for mode in VT_MODES {
            let static_mode = if mode == Mode::CapsuleExact { Mode::Sphere } else { mode };
            let (got, digest) = pairs_and_digest(&still, Query::vt(mode, R));
            let (want, want_digest) = pairs_and_digest(&fixed, Query::vt(static_mode, R));
            assert!(!want.is_empty(), "{mode:?}");
            assert_eq!(got, want, "rebuild {rebuild} {mode:?}");
            assert_eq!(digest, want_digest, "rebuild {rebuild} {mode:?}");
        }
        let (got, digest) = pairs_and_digest(&still, Query::ee(Mode::Box, R));
        assert!(!got.is_empty());
        assert_eq!((got, digest), pairs_and_digest(&fixed, Query::ee(Mode::Box, R)), "rebuild {rebuild} EE");
        // A plain refit ends the swept state: leaf-exact and EE capsules run again.
        still.refit(&x).unwrap();
        assert!(!still.is_swept());
        let exact = Query::ee(Mode::CapsuleExact, R).with_flags(QueryFlags::LEAF_EXACT);
        assert_eq!(pairs(&still, exact), pairs(&fixed, exact));
    }
}

#[test]
fn swept_box_mode_is_its_definition_and_the_finer_vt_modes_nest() {
    let device = Device::cpu().unwrap();
    for seed in [1, 2] {
        let (x0, x1, triangles) = two_sheets(seed, 0.4);
        let mut refitted = Scene::new(&device, &SceneDesc::new(&x0, &triangles)).unwrap();
        refitted.refit_swept(&x0, &x1).unwrap();
        let mut rebuilt = Scene::new(&device, &SceneDesc::new(&x0, &triangles)).unwrap();
        rebuilt.rebuild_swept(&x0, &x1).unwrap();
        assert_eq!(rebuilt.tree_growth().unwrap(), 1.0);
        check_box_definition(&refitted, &x0, &x1, &triangles, "refit_swept");
        check_box_definition(&rebuilt, &x0, &x1, &triangles, "rebuild_swept");
        // From buffers: x1 as padded (vec4) records read in place, the same pairs.
        let padded: Vec<[f32; 4]> = x1.iter().map(|p| [p[0], p[1], p[2], f32::NAN]).collect();
        let mut from_buffers = Scene::new(&device, &SceneDesc::new(&x0, &triangles)).unwrap();
        // SAFETY: x1.len() 16-byte records starting with x, y, z, borrowed from `padded`.
        let x1_buffer = unsafe { Buffer::from_raw_parts(padded.as_ptr().cast(), 16, padded.len(), Memory::Host) };
        from_buffers.refit_swept(Buffer::from_slice(&x0), x1_buffer).unwrap();

        let ee = pairs(&refitted, Query::ee(Mode::Box, R));
        assert_eq!(ee, pairs(&rebuilt, Query::ee(Mode::Box, R)));
        assert_eq!(ee, pairs(&from_buffers, Query::ee(Mode::Box, R)));
        let by_mode: Vec<Vec<[i32; 2]>> = VT_MODES.iter().map(|&m| pairs(&refitted, Query::vt(m, R))).collect();
        for (mode, found) in VT_MODES.iter().zip(&by_mode) {
            assert_eq!(found, &pairs(&rebuilt, Query::vt(*mode, R)), "seed {seed} {mode:?}");
            assert_eq!(found, &pairs(&from_buffers, Query::vt(*mode, R)), "seed {seed} {mode:?}");
        }
        let [boxes, sphere, ray, exact] = [&by_mode[0], &by_mode[1], &by_mode[2], &by_mode[3]];
        assert_eq!(sphere, exact, "sphere is capsule_exact on swept positions");
        assert_subset(exact, ray, "capsule_exact in capsule_ray");
        assert_subset(ray, boxes, "capsule_ray in box");
        assert!(exact.len() < boxes.len());

        // Every contact at 33 times of the step (within r less a margin) is a capsule_exact pair.
        let mut contacts = Vec::new();
        for k in 0..=32 {
            let t = f64::from(k) / 32.0;
            for v in 0..x0.len() {
                let p = lerp(x0[v], x1[v], t);
                for (ti, tri) in triangles.iter().enumerate() {
                    let [a, b, c] = tri.map(|w| lerp(x0[w as usize], x1[w as usize], t));
                    let within = point_triangle_sq(p, a, b, c).sqrt() <= f64::from(R) * (1.0 - 1e-4);
                    if within && !tri.contains(&(v as i32)) {
                        contacts.push([v as i32, ti as i32]);
                    }
                }
            }
        }
        contacts.sort_unstable();
        contacts.dedup();
        assert!(contacts.len() > 50, "seed {seed}: {} contacts", contacts.len());
        assert_subset(&contacts, exact, "sampled contacts in capsule_exact");
    }
}

/// Triangle 0 in the plane x = 0 and edge 3 (vertices 4-5, along z) stay still; vertex 3 and
/// edge 4 (vertices 6-7, along y) fly from x = -length to x = +length straight through them.
fn flying(length: f32) -> (Positions, Positions) {
    let x0 = vec![
        [0.0, -1.0, -1.0],
        [0.0, 2.0, -1.0],
        [0.0, -1.0, 2.0],
        [-length, 0.1, 0.1],
        [0.0, 0.0, -5.0],
        [0.0, 0.0, -4.0],
        [-length, 0.5, -4.5],
        [-length, -0.5, -4.5],
    ];
    let mut x1 = x0.clone();
    for v in [3, 6, 7] {
        x1[v][0] = length;
    }
    (x0, x1)
}
const FLYING_TRIANGLES: [[i32; 3]; 1] = [[0, 1, 2]];
const FLYING_EDGES: [[i32; 2]; 5] = [[0, 1], [0, 2], [1, 2], [4, 5], [6, 7]];

fn every_static_query() -> Vec<Query> {
    let mut queries = Vec::new();
    for flags in [QueryFlags::empty(), QueryFlags::LEAF_EXACT] {
        queries.extend(VT_MODES.map(|m| Query::vt(m, 0.01).with_flags(flags)));
        queries.extend([Mode::Box, Mode::CapsuleRay, Mode::CapsuleExact].map(|m| Query::ee(m, 0.01).with_flags(flags)));
    }
    queries
}

#[test]
fn a_vertex_and_an_edge_flying_through_still_ones_are_found() {
    let device = Device::cpu().unwrap();
    for length in [1.0, 100.0, 1e4] {
        let (x0, x1) = flying(length);
        let desc = SceneDesc::new(&x0, &FLYING_TRIANGLES).edges(&FLYING_EDGES);
        let mut scene = Scene::new(&device, &desc).unwrap();
        // Apart at either end: no static query finds anything.
        for query in every_static_query() {
            assert!(pairs(&scene, query).is_empty(), "length {length} at x0: {query:?}");
        }
        scene.refit(&x1).unwrap();
        for query in every_static_query() {
            assert!(pairs(&scene, query).is_empty(), "length {length} at x1: {query:?}");
        }
        for rebuild in [false, true] {
            if rebuild {
                scene.rebuild_swept(&x0, &x1).unwrap();
            } else {
                scene.refit_swept(&x0, &x1).unwrap();
            }
            let what = format!("length {length} rebuild {rebuild}");
            for mode in VT_MODES {
                assert_eq!(pairs(&scene, Query::vt(mode, 0.01)), vec![[3, 0]], "{what} {mode:?}");
            }
            assert_eq!(pairs(&scene, Query::ee(Mode::Box, 0.01)), vec![[3, 4]], "{what}");
            // Both kinds in one pass, and stream-ordered: the same pairs.
            let (mut vt_out, mut ee_out) = (PairBuffer::new().unwrap(), PairBuffer::new().unwrap());
            let (vt_query, ee_query) = (Query::vt(Mode::CapsuleRay, 0.01), Query::ee(Mode::Box, 0.01));
            let (vt, ee) = scene.query_vt_ee(&vt_query, &ee_query, &mut vt_out, &mut ee_out).unwrap();
            assert_eq!((vt, ee), (&[[3, 0]][..], &[[3, 4]][..]), "{what}");
            let (mut out, mut count) = ([[0; 2]; 4], 0u64);
            let (out_buffer, count_out) = (PairsOut::from_slice(&mut out), CountOut::from_mut(&mut count));
            scene.query_async(&ee_query, out_buffer, count_out, Stream::null()).unwrap();
            scene.async_status(Stream::null()).unwrap();
            assert_eq!((count, out[0]), (1, [3, 4]), "{what}");
        }
        // Static again at x1: nothing.
        scene.rebuild(&x1).unwrap();
        assert!(!scene.is_swept());
        for query in every_static_query() {
            assert!(pairs(&scene, query).is_empty(), "length {length} back at x1: {query:?}");
        }
    }
}

fn assert_unsupported<T: std::fmt::Debug>(result: minkq::Result<T>, needle: &str, what: &str) {
    match result {
        Err(Error::Unsupported(m)) => assert!(m.contains(needle), "{what}: {m}"),
        other => panic!("{what}: expected Unsupported, got {other:?}"),
    }
}

#[test]
fn leaf_exact_and_the_ee_segment_modes_are_refused() {
    let device = Device::cpu().unwrap();
    let (x0, x1) = flying(1.0);
    let mut scene = Scene::new(&device, &SceneDesc::new(&x0, &FLYING_TRIANGLES).edges(&FLYING_EDGES)).unwrap();
    scene.refit_swept(&x0, &x1).unwrap();
    let mut out = PairBuffer::new().unwrap();
    let leaf = "LEAF_EXACT on swept positions";
    for mode in VT_MODES {
        let query = Query::vt(mode, 0.01).with_flags(QueryFlags::LEAF_EXACT);
        assert_unsupported(scene.query(&query, &mut out), leaf, &format!("VT {mode:?}"));
        assert_unsupported(scene.query_into(&query, &mut Vec::new()), leaf, "query_into");
        assert_unsupported(scene.work(&query), leaf, "work");
    }
    assert_unsupported(
        scene.query(&Query::ee(Mode::Box, 0.01).with_flags(QueryFlags::LEAF_EXACT), &mut out),
        leaf,
        "EE box",
    );
    for mode in [Mode::CapsuleRay, Mode::CapsuleExact] {
        let query = Query::ee(mode, 0.01);
        assert_unsupported(scene.query(&query, &mut out), "box mode only", &format!("EE {mode:?}"));
        let mut vt_out = PairBuffer::new().unwrap();
        let both = scene.query_vt_ee(&Query::vt(Mode::Box, 0.01), &query, &mut vt_out, &mut out);
        assert_unsupported(both, "box mode only", "query_vt_ee");
        let (mut pairs_out, mut count) = ([[0; 2]; 4], 0u64);
        let (pairs_out, count_out) = (PairsOut::from_slice(&mut pairs_out), CountOut::from_mut(&mut count));
        assert_unsupported(scene.query_async(&query, pairs_out, count_out, Stream::null()), "box mode only", "async");
    }
    // Sphere mode for EE stays an invalid argument, as on static positions.
    assert!(matches!(scene.query(&Query::ee(Mode::Sphere, 0.01), &mut out), Err(Error::InvalidArgument(_))));
    // The refusals leave the scene swept, its pairs as they were.
    assert!(scene.is_swept());
    assert_eq!(pairs(&scene, Query::vt(Mode::Sphere, 0.01)), vec![[3, 0]]);
}

/// (plane, point) near `base` with point - plane = 0.95 r in double but more than r apart once
/// rounded to float.
fn pulled_apart(base: f32, r: f32) -> (f64, f64) {
    let u = f64::from(f32::from_bits(base.to_bits() + 1)) - f64::from(base);
    (0..64)
        .map(|k| f64::from(base) + (f64::from(k) / 64.0 - 0.5) * u)
        .map(|plane| (plane, plane + 0.95 * f64::from(r)))
        .find(|&(plane, point)| point as f32 - plane as f32 > r)
        .unwrap()
}

fn rounded(vertices: &[[f64; 3]]) -> Vec<[f32; 3]> {
    vertices.iter().map(|v| v.map(|x| x as f32)).collect()
}

#[test]
fn float64_steps() {
    let device = Device::cpu().unwrap();
    // A vertex sliding past a triangle near x = 2e4, 0.95 r in front of it in double (2^-9 > r
    // once rounded to float), from y = -10 to y = +10: beside it at either end.
    let r = 1e-3;
    let (plane, point) = pulled_apart(2e4, r);
    let x0 = vec![[plane, -1.0, -1.0], [plane, 2.0, -1.0], [plane, -1.0, 2.0], [point, -10.0, 0.1]];
    let mut x1 = x0.clone();
    x1[3][1] = 10.0;
    let mut scene = Scene::new(&device, &SceneDesc::new_f64(&x0, &FLYING_TRIANGLES)).unwrap();
    let mut float_scene = Scene::new(&device, &SceneDesc::new(&rounded(&x0), &FLYING_TRIANGLES)).unwrap();
    float_scene.refit_swept(&rounded(&x0), &rounded(&x1)).unwrap();
    for rebuild in [false, true] {
        assert!(pairs(&scene, Query::vt(Mode::Box, r)).is_empty());
        if rebuild {
            scene.rebuild_swept(&x0, &x1).unwrap();
        } else {
            scene.refit_swept(&x0, &x1).unwrap();
        }
        assert!(scene.is_swept() && scene.is_float64());
        for mode in VT_MODES {
            assert_eq!(pairs(&scene, Query::vt(mode, r)), vec![[3, 0]], "rebuild {rebuild} {mode:?}");
            assert!(pairs(&float_scene, Query::vt(mode, r)).is_empty(), "{mode:?}: rounding pulls them apart");
        }
        scene.refit(&x0).unwrap();
        assert!(!scene.is_swept());
    }

    // Doubles that are floats: the float scene's swept pairs and digests, from slices and
    // from buffers of doubles.
    let (f0, f1, triangles) = two_sheets(3, 0.4);
    let widen = |v: &[[f32; 3]]| -> Vec<[f64; 3]> { v.iter().map(|p| p.map(f64::from)).collect() };
    let (d0, d1) = (widen(&f0), widen(&f1));
    let mut floats = Scene::new(&device, &SceneDesc::new(&f0, &triangles)).unwrap();
    floats.refit_swept(&f0, &f1).unwrap();
    let mut doubles = Scene::new(&device, &SceneDesc::new_f64(&d0, &triangles)).unwrap();
    let mut from_buffers = Scene::new(&device, &SceneDesc::new_f64(&d0, &triangles)).unwrap();
    doubles.refit_swept(&d0, &d1).unwrap();
    from_buffers.rebuild_swept(Buffer::from_slice(&d0), Buffer::from_slice(&d1)).unwrap();
    let queries = VT_MODES.iter().map(|&m| Query::vt(m, R)).chain([Query::ee(Mode::Box, R)]);
    for query in queries {
        let want = pairs_and_digest(&floats, query);
        assert!(!want.0.is_empty(), "{query:?}");
        assert_eq!(pairs_and_digest(&doubles, query), want, "{query:?}");
        assert_eq!(pairs_and_digest(&from_buffers, query), want, "{query:?}");
    }
}

fn assert_precision_refused(result: minkq::Result<()>, call: &str, buffer: &str, got: &str, wanted: &str) {
    let expected = if got == "[f64; 3]" { "without" } else { "with" };
    let message =
        format!("{call}: {buffer}: {got} vertices, but a scene {expected} SceneFlags::FLOAT64 reads {wanted}");
    assert_eq!(result, Err(Error::InvalidArgument(message)));
}

#[test]
fn positions_of_the_other_precision_are_refused_and_the_scene_keeps_its_state() {
    let device = Device::cpu().unwrap();
    let (x0, x1) = flying(1.0);
    let (d0, d1): (Vec<[f64; 3]>, Vec<[f64; 3]>) =
        (x0.iter().map(|p| p.map(f64::from)).collect(), x1.iter().map(|p| p.map(f64::from)).collect());
    let (f32s, f64s) = ("[f32; 3]", "[f64; 3]");
    let sphere = Query::vt(Mode::Sphere, 0.01);

    // A float scene, swept: doubles in either buffer are refused.
    let mut scene = Scene::new(&device, &SceneDesc::new(&x0, &FLYING_TRIANGLES)).unwrap();
    scene.refit_swept(&x0, &x1).unwrap();
    fn f(v: &[[f32; 3]]) -> Buffer<'_> {
        Buffer::from_slice(v)
    }
    fn d(v: &[[f64; 3]]) -> Buffer<'_> {
        Buffer::from_slice(v)
    }
    assert_precision_refused(scene.refit_swept(&d0, &d1), "refit_swept", "x0", f64s, f32s);
    assert_precision_refused(scene.rebuild_swept(&d0, &d1), "rebuild_swept", "x0", f64s, f32s);
    assert_precision_refused(scene.refit_swept(f(&x0), d(&d1)), "refit_swept", "x1", f64s, f32s);
    assert_precision_refused(scene.rebuild_swept(d(&d0), f(&x1)), "rebuild_swept", "x0", f64s, f32s);
    assert_precision_refused(scene.rebuild_swept(f(&x0), d(&d1)), "rebuild_swept", "x1", f64s, f32s);
    assert!(scene.is_swept());
    assert_eq!(pairs(&scene, sphere), vec![[3, 0]]);

    // A float64 scene, static: floats in either buffer are refused, and it stays static.
    let mut scene = Scene::new(&device, &SceneDesc::new_f64(&d0, &FLYING_TRIANGLES)).unwrap();
    assert_precision_refused(scene.refit_swept(&x0, &x1), "refit_swept", "x0", f32s, f64s);
    assert_precision_refused(scene.rebuild_swept(&x0, &x1), "rebuild_swept", "x0", f32s, f64s);
    assert_precision_refused(scene.refit_swept(d(&d0), f(&x1)), "refit_swept", "x1", f32s, f64s);
    assert_precision_refused(scene.rebuild_swept(d(&d0), f(&x1)), "rebuild_swept", "x1", f32s, f64s);
    assert!(!scene.is_swept());
    assert!(pairs(&scene, sphere.with_flags(QueryFlags::LEAF_EXACT)).is_empty());

    // Bad counts and NaNs (either buffer): the library's errors; a swept scene stays swept.
    let mut scene = Scene::new(&device, &SceneDesc::new(&x0, &FLYING_TRIANGLES)).unwrap();
    scene.rebuild_swept(&x0, &x1).unwrap();
    let expected = |call: &str, buffer: &str| {
        Error::InvalidArgument(format!("{call} with 7 {buffer} vertices but the scene has 8"))
    };
    assert_eq!(scene.refit_swept(&x0, &x1[..7]), Err(expected("refit_swept", "x1")));
    assert_eq!(scene.rebuild_swept(&x0[..7], &x1), Err(expected("rebuild_swept", "x0")));
    let mut bad = x1.clone();
    bad[5][2] = f32::NAN;
    for (result, buffer) in [(scene.refit_swept(&x0, &bad), "x1"), (scene.rebuild_swept(&bad, &x1), "x0")] {
        assert!(matches!(result, Err(Error::NonFinite(m)) if m.starts_with(&format!("{buffer} vertex 5 "))));
    }
    assert!(scene.is_swept());
    assert_eq!(pairs(&scene, sphere), vec![[3, 0]]);
}

#[test]
fn every_plain_refit_or_rebuild_ends_the_swept_state() {
    let device = Device::cpu().unwrap();
    let (x0, x1) = flying(1.0);
    let mut scene = Scene::new(&device, &SceneDesc::new(&x0, &FLYING_TRIANGLES).edges(&FLYING_EDGES)).unwrap();
    assert!(!scene.is_swept());
    scene.reserve(Reserve::REFIT | Reserve::REBUILD, 0).unwrap();
    let leaf_exact = Query::vt(Mode::Box, 0.01).with_flags(QueryFlags::LEAF_EXACT);
    type PlainCall<'a> = &'a dyn Fn(&mut Scene) -> minkq::Result<()>;
    let plain: [(&str, PlainCall); 6] = [
        ("refit", &|s| s.refit(&x1)),
        ("rebuild", &|s| s.rebuild(&x1)),
        ("refit_buffer", &|s| s.refit(Buffer::from_slice(&x1))),
        ("rebuild_buffer", &|s| s.rebuild(Buffer::from_slice(&x1))),
        ("refit_async", &|s| {
            s.refit_async(Buffer::from_slice(&x1), Stream::null())?;
            s.async_status(Stream::null())
        }),
        ("rebuild_async", &|s| {
            s.rebuild_async(Buffer::from_slice(&x1), Stream::null())?;
            s.async_status(Stream::null())
        }),
    ];
    for (what, call) in plain {
        scene.refit_swept(&x0, &x1).unwrap();
        assert!(scene.is_swept(), "{what}");
        assert!(scene.query(&leaf_exact, &mut PairBuffer::new().unwrap()).is_err(), "{what}");
        call(&mut scene).unwrap();
        assert!(!scene.is_swept(), "{what}");
        // Static queries at x1 again: leaf-exact and EE capsules run, and find nothing.
        assert!(pairs(&scene, leaf_exact).is_empty(), "{what}");
        assert!(pairs(&scene, Query::vt(Mode::Sphere, 0.01)).is_empty(), "{what}");
        assert!(pairs(&scene, Query::ee(Mode::CapsuleExact, 0.01)).is_empty(), "{what}");
    }
}
