//! The stream-ordered swept steps (`Scene::refit_swept_async`, `rebuild_swept_async`) on the
//! CPU, where they run to completion and follow the rules they follow on CUDA: over several
//! steps (refits and a rebuild, float and float64) they give the blocking swept calls' pairs,
//! digests and trees, to blocking and asynchronous queries; a NaN or infinity in either buffer
//! is accepted at once, reported by `async_status` (naming the swept call and the first bad
//! vertex) and leaves the scene at rest at its kept start (the static pairs there); a missing
//! `Reserve::SWEPT` (or REFIT / REBUILD) reservation, positions of the other precision in
//! either buffer, a bad count and device memory on the CPU are refused at once, and the scene
//! keeps its state.
mod common;
use common::{grid_triangles, Rng};

use minkq::{
    Buffer, CountOut, Device, Error, Memory, Mode, PairsOut, Query, QueryFlags, Reserve, Scene, SceneDesc, Stream,
};

const N: i32 = 8;
const R: f32 = 0.05;
const VT_MODES: [Mode; 4] = [Mode::Box, Mode::Sphere, Mode::CapsuleRay, Mode::CapsuleExact];

type Positions = Vec<[f32; 3]>;

/// Two jittered N x N sheets over the unit square at step `step` (a step runs from
/// `sheets_at(step)` to `sheets_at(step + 1)`): sheet 0 (vertices 0..N*N) waving near z = 0,
/// sheet 1 (vertices N*N..) sliding and falling 0.15 a step from z = 0.3, through sheet 0
/// during steps 1 and 2.
fn sheets_at(step: i32) -> Positions {
    let mut rng = Rng(7);
    let s = step as f32;
    let mut x = Vec::new();
    for sheet in 0..2 {
        for j in 0..N {
            for i in 0..N {
                let (u, v) = (i as f32 / (N - 1) as f32, j as f32 / (N - 1) as f32);
                let jitter = 0.02 * (rng.uniform() as f32 - 0.5);
                let wave = 0.02 * (3.0 * u + s).sin();
                if sheet == 0 {
                    x.push([u, v, jitter + wave]);
                } else {
                    x.push([u + 0.03 * s, v - 0.02 * s, 0.3 - 0.15 * s + jitter + 2.0 * wave]);
                }
            }
        }
    }
    x
}

fn triangles() -> Vec<[i32; 3]> {
    let mut triangles = grid_triangles(N);
    let upper: Vec<[i32; 3]> = triangles.iter().map(|t| t.map(|v| v + N * N)).collect();
    triangles.extend(upper);
    triangles
}

/// Doubles that are not floats, far from the origin: the float64 path's rounding and radius
/// widening run.
fn far(x: &[[f32; 3]]) -> Vec<[f64; 3]> {
    x.iter().enumerate().map(|(v, p)| p.map(|c| 4096.0 + f64::from(c) + 1e-9 * v as f64)).collect()
}

fn queries() -> Vec<Query> {
    let mut queries: Vec<Query> = VT_MODES.iter().map(|&m| Query::vt(m, R)).collect();
    queries.push(Query::ee(Mode::Box, R));
    queries
}

fn pairs_and_digest(scene: &Scene, query: &Query) -> (Vec<[i32; 2]>, Option<u64>) {
    let mut out = Vec::new();
    let info = scene.query_into(&query.with_flags(QueryFlags::CANONICAL | QueryFlags::DIGEST), &mut out).unwrap();
    (out, info.digest)
}

/// `query` run stream-ordered into a buffer with room to spare, sorted.
fn async_pairs(scene: &Scene, query: &Query) -> Vec<[i32; 2]> {
    let (mut out, mut count) = (vec![[-1; 2]; 4096], 0u64);
    scene.query_async(query, PairsOut::from_slice(&mut out), CountOut::from_mut(&mut count), Stream::null()).unwrap();
    assert!(count as usize <= out.len(), "{query:?}: {count} pairs");
    out.truncate(count as usize);
    out.sort_unstable();
    out
}

/// Every query of `scene` gives `expected`'s pairs and digests, blocking and stream-ordered.
fn assert_same_pairs(scene: &Scene, expected: &Scene, what: &str) {
    for query in queries() {
        let want = pairs_and_digest(expected, &query);
        assert!(!want.0.is_empty(), "{what}: {query:?} found nothing");
        assert_eq!(pairs_and_digest(scene, &query), want, "{what}: {query:?}");
        assert_eq!(async_pairs(scene, &query), want.0, "{what}: async {query:?}");
    }
}

/// The static scene's pairs at rest: the swept modes' static counterparts (capsule_exact is
/// the static sphere mode at zero motion).
fn assert_at_rest(scene: &Scene, fixed: &Scene, what: &str) {
    assert!(scene.is_swept(), "{what}: at rest, but swept positions");
    for query in queries() {
        let mode = if query.mode == Mode::CapsuleExact { Mode::Sphere } else { query.mode };
        let want = pairs_and_digest(fixed, &Query { mode, ..query });
        assert!(!want.0.is_empty(), "{what}: {query:?} found nothing");
        assert_eq!(pairs_and_digest(scene, &query), want, "{what}: {query:?} at rest");
        assert_eq!(async_pairs(scene, &query), want.0, "{what}: async {query:?} at rest");
    }
}

/// Runs a swept step on `scene`, stream-ordered or blocking.
fn step(scene: &mut Scene, rebuild: bool, stream_ordered: bool, x0: Buffer<'_>, x1: Buffer<'_>) -> minkq::Result<()> {
    match (rebuild, stream_ordered) {
        (false, false) => scene.refit_swept(x0, x1),
        (true, false) => scene.rebuild_swept(x0, x1),
        (false, true) => scene.refit_swept_async(x0, x1, Stream::null()),
        (true, true) => scene.rebuild_swept_async(x0, x1, Stream::null()),
    }
}

#[test]
fn async_swept_steps_equal_the_blocking_swept_steps() {
    let device = Device::cpu().unwrap();
    let triangles = triangles();
    for float64 in [false, true] {
        let positions: Vec<Positions> = (0..=4).map(sheets_at).collect();
        let doubles: Vec<Vec<[f64; 3]>> = positions.iter().map(|x| far(x)).collect();
        let scene_at = |x: usize| {
            let scene = if float64 {
                Scene::new(&device, &SceneDesc::new_f64(&doubles[x], &triangles))
            } else {
                Scene::new(&device, &SceneDesc::new(&positions[x], &triangles))
            };
            scene.unwrap()
        };
        let buffer =
            |x: usize| if float64 { Buffer::from_slice(&doubles[x]) } else { Buffer::from_slice(&positions[x]) };
        let (mut stepped, mut blocking) = (scene_at(0), scene_at(0));
        stepped.reserve(Reserve::REBUILD | Reserve::SWEPT, 4096).unwrap();
        // Refits, a rebuild, and a refit on the rebuilt trees.
        for (k, rebuild) in [false, false, true, false].into_iter().enumerate() {
            let what = format!("float64 {float64} step {k} rebuild {rebuild}");
            step(&mut stepped, rebuild, true, buffer(k), buffer(k + 1)).unwrap();
            step(&mut blocking, rebuild, false, buffer(k), buffer(k + 1)).unwrap();
            stepped.async_status(Stream::null()).unwrap();
            assert!(stepped.is_swept(), "{what}");
            assert_eq!(stepped.tree_growth().unwrap(), blocking.tree_growth().unwrap(), "{what}: other trees");
            assert_same_pairs(&stepped, &blocking, &what);
            // Swept, not static: every pair of either end, and in the step through the other
            // sheet pairs neither end has.
            let box_query = Query::vt(Mode::Box, R);
            let swept = pairs_and_digest(&stepped, &box_query).0;
            let ends = [pairs_and_digest(&scene_at(k), &box_query).0, pairs_and_digest(&scene_at(k + 1), &box_query).0];
            for end in &ends {
                assert!(end.iter().all(|p| swept.binary_search(p).is_ok()), "{what}: a static pair lost");
            }
            let only_swept = swept.iter().filter(|p| ends.iter().all(|end| end.binary_search(p).is_err())).count();
            assert!((k != 1) || only_swept > 100, "{what}: {only_swept} pairs of the step only");
        }
        // A plain stream-ordered refit makes it static again, as the blocking one does.
        stepped.refit_async(buffer(4), Stream::null()).unwrap();
        blocking.refit(buffer(4)).unwrap();
        stepped.async_status(Stream::null()).unwrap();
        assert!(!stepped.is_swept() && !blocking.is_swept());
        assert_same_pairs(&stepped, &blocking, &format!("float64 {float64} static again"));
    }
}

#[test]
fn a_non_finite_coordinate_leaves_the_scene_at_rest_at_its_kept_start() {
    let device = Device::cpu().unwrap();
    let triangles = triangles();
    let static_at = |x: &[[f32; 3]]| Scene::new(&device, &SceneDesc::new(x, &triangles)).unwrap();
    let (p1, p2, p3, p4) = (sheets_at(1), sheets_at(2), sheets_at(3), sheets_at(4));

    // Never swept before: at rest at the creation positions.
    let mut scene = static_at(&p1);
    scene.reserve(Reserve::REFIT | Reserve::SWEPT, 0).unwrap();
    let mut bad = p2.clone();
    bad[9][0] = f32::NAN;
    scene.refit_swept_async(Buffer::from_slice(&p1), Buffer::from_slice(&bad), Stream::null()).unwrap();
    let result = scene.async_status(Stream::null());
    let expected = "minkq_scene_refit_swept_async: vertex 9 has a non-finite coordinate (in x0 or x1)";
    assert!(matches!(&result, Err(Error::NonFinite(m)) if m.contains(expected)), "{result:?}");
    assert_eq!(scene.async_status(Stream::null()), Ok(()), "the pending error was not cleared");
    assert_at_rest(&scene, &static_at(&p1), "from static");
    // Swept but at rest: leaf-exact is still refused.
    let leaf_exact = Query::vt(Mode::Box, R).with_flags(QueryFlags::LEAF_EXACT);
    assert!(matches!(scene.query_into(&leaf_exact, &mut Vec::new()), Err(Error::Unsupported(_))));

    // After an accepted step p1 -> p2, bad steps p3 -> p4 keep its start p1, as both ends.
    let mut scene = static_at(&p1);
    scene.reserve(Reserve::REBUILD | Reserve::SWEPT, 0).unwrap();
    scene.refit_swept_async(Buffer::from_slice(&p1), Buffer::from_slice(&p2), Stream::null()).unwrap();
    scene.async_status(Stream::null()).unwrap();
    let fixed = static_at(&p1);
    // (call, [(in x1, vertex, value)], the vertex reported)
    type Bad = &'static [(bool, usize, f32)];
    let cases: [(&str, Bad, usize); 4] = [
        ("refit", &[(true, 70, f32::NAN)], 70),
        ("rebuild", &[(false, 3, f32::INFINITY)], 3),
        ("refit", &[(false, 100, f32::NEG_INFINITY)], 100),
        ("rebuild", &[(false, 40, f32::NAN), (true, 12, f32::NAN)], 12), // the first bad vertex
    ];
    for (call, bad_values, reported) in cases {
        let (mut x0, mut x1) = (p3.clone(), p4.clone());
        for &(in_x1, v, value) in bad_values {
            let target = if in_x1 { &mut x1 } else { &mut x0 };
            target[v][2] = value;
        }
        let result = step(&mut scene, call == "rebuild", true, Buffer::from_slice(&x0), Buffer::from_slice(&x1));
        assert_eq!(result, Ok(()), "{call}: a non-finite coordinate is no error at once");
        match scene.async_status(Stream::null()) {
            Err(Error::NonFinite(message)) => {
                let expected = format!("minkq_scene_{call}_swept_async: vertex {reported} has a non-finite");
                assert!(message.contains(&expected), "{message}");
                assert!(message.contains("at rest"), "{message}");
            }
            other => panic!("{call}: expected NonFinite, got {other:?}"),
        }
        assert_at_rest(&scene, &fixed, &format!("{call} {bad_values:?}"));
        if call == "rebuild" {
            assert_eq!(scene.tree_growth().unwrap(), 1.0, "trees built for the kept positions");
        }
    }

    // The first refused step is reported; a later good one does not hide it, and applies.
    let mut bad = p3.clone();
    bad[5][1] = f32::NAN;
    scene.refit_swept_async(Buffer::from_slice(&bad), Buffer::from_slice(&p4), Stream::null()).unwrap();
    scene.rebuild_swept_async(Buffer::from_slice(&p2), Buffer::from_slice(&p3), Stream::null()).unwrap();
    let result = scene.async_status(Stream::null());
    assert!(matches!(&result, Err(Error::NonFinite(m)) if m.contains("refit_swept_async: vertex 5 ")), "{result:?}");
    let mut blocking = static_at(&p1);
    blocking.rebuild_swept(&p2, &p3).unwrap();
    assert_same_pairs(&scene, &blocking, "good step after a refused one");
    assert_eq!(scene.async_status(Stream::null()), Ok(()));
}

#[test]
fn a_missing_swept_reservation_is_refused_at_once_and_the_scene_keeps_its_state() {
    let device = Device::cpu().unwrap();
    let triangles = triangles();
    let (p0, p1) = (sheets_at(0), sheets_at(1));
    let (b0, b1) = (Buffer::from_slice(&p0), Buffer::from_slice(&p1));
    let fixed = Scene::new(&device, &SceneDesc::new(&p0, &triangles)).unwrap();
    let expect_refused = |scene: &mut Scene, rebuild: bool, needs: &str, what: &str| {
        match step(scene, rebuild, true, b0, b1) {
            Err(Error::InvalidArgument(m)) => {
                let call = if rebuild { "rebuild" } else { "refit" };
                assert!(m.contains(&format!("{call}_swept_async needs scratch reserved first")), "{what}: {m}");
                assert!(m.contains(needs), "{what}: {m}");
            }
            other => panic!("{what}: expected InvalidArgument, got {other:?}"),
        }
        assert!(!scene.is_swept(), "{what}");
        assert_eq!(scene.async_status(Stream::null()), Ok(()), "{what}: nothing enqueued");
        for query in queries() {
            assert_eq!(pairs_and_digest(scene, &query), pairs_and_digest(&fixed, &query), "{what}: {query:?}");
        }
    };
    let (refit_needs, rebuild_needs) =
        ("MINKQ_RESERVE_REFIT | MINKQ_RESERVE_SWEPT", "MINKQ_RESERVE_REBUILD | MINKQ_RESERVE_SWEPT");

    // The plain reservations do not cover swept steps.
    let mut scene = Scene::new(&device, &SceneDesc::new(&p0, &triangles)).unwrap();
    expect_refused(&mut scene, false, refit_needs, "nothing reserved");
    expect_refused(&mut scene, true, rebuild_needs, "nothing reserved");
    scene.reserve(Reserve::REFIT | Reserve::REBUILD, 64).unwrap();
    expect_refused(&mut scene, false, refit_needs, "REFIT | REBUILD");
    expect_refused(&mut scene, true, rebuild_needs, "REFIT | REBUILD");
    scene.refit_async(b1, Stream::null()).unwrap(); // which do cover plain steps
    scene.refit_async(b0, Stream::null()).unwrap();

    // SWEPT alone covers neither; with REFIT it covers refits, with REBUILD both.
    let mut scene = Scene::new(&device, &SceneDesc::new(&p0, &triangles)).unwrap();
    scene.reserve(Reserve::SWEPT, 0).unwrap();
    expect_refused(&mut scene, false, refit_needs, "SWEPT");
    expect_refused(&mut scene, true, rebuild_needs, "SWEPT");
    scene.reserve(Reserve::REFIT, 0).unwrap(); // reservations grow: REFIT | SWEPT now
    expect_refused(&mut scene, true, rebuild_needs, "REFIT | SWEPT");
    scene.refit_swept_async(b0, b1, Stream::null()).unwrap();
    assert!(scene.is_swept());
    scene.reserve(Reserve::REBUILD, 0).unwrap();
    scene.rebuild_swept_async(b0, b1, Stream::null()).unwrap();
    scene.async_status(Stream::null()).unwrap();
    let mut blocking = Scene::new(&device, &SceneDesc::new(&p0, &triangles)).unwrap();
    blocking.rebuild_swept(&p0, &p1).unwrap();
    assert_same_pairs(&scene, &blocking, "reserved at last");
}

#[test]
fn wrong_buffers_in_either_position_are_refused_at_once_and_the_scene_keeps_its_state() {
    let device = Device::cpu().unwrap();
    let triangles = triangles();
    let (p0, p1) = (sheets_at(0), sheets_at(1));
    let (d0, d1) = (far(&p0), far(&p1));
    let (f0, f1, g0, g1) =
        (Buffer::from_slice(&p0), Buffer::from_slice(&p1), Buffer::from_slice(&d0), Buffer::from_slice(&d1));
    let precision = |call: &str, buffer: &str, float64_scene: bool| {
        let (got, with, wanted) =
            if float64_scene { ("[f32; 3]", "with", "[f64; 3]") } else { ("[f64; 3]", "without", "[f32; 3]") };
        Err(Error::InvalidArgument(format!(
            "{call}_swept_async: {buffer}: {got} vertices, but a scene {with} SceneFlags::FLOAT64 reads {wanted}"
        )))
    };
    for float64 in [false, true] {
        let mut scene = if float64 {
            Scene::new(&device, &SceneDesc::new_f64(&d0, &triangles)).unwrap()
        } else {
            Scene::new(&device, &SceneDesc::new(&p0, &triangles)).unwrap()
        };
        scene.reserve(Reserve::REBUILD | Reserve::SWEPT, 0).unwrap();
        let before: Vec<_> = queries().iter().map(|q| pairs_and_digest(&scene, q)).collect();
        let (right0, right1, wrong0, wrong1) = if float64 { (g0, g1, f0, f1) } else { (f0, f1, g0, g1) };
        for (call, rebuild) in [("refit", false), ("rebuild", true)] {
            let what = format!("float64 {float64} {call}");
            // The other precision in x0, in x1, in both (x0 is named first).
            assert_eq!(step(&mut scene, rebuild, true, wrong0, right1), precision(call, "x0", float64), "{what}");
            assert_eq!(step(&mut scene, rebuild, true, right0, wrong1), precision(call, "x1", float64), "{what}");
            assert_eq!(step(&mut scene, rebuild, true, wrong0, wrong1), precision(call, "x0", float64), "{what}");
            // Another vertex count, in either buffer.
            let short = |b: Buffer<'_>| unsafe {
                // SAFETY: the first 7 records of a live buffer (raw: read as the scene's precision).
                Buffer::from_raw_parts(b.data(), b.byte_stride(), 7, Memory::Host)
            };
            for (x0, x1, name) in [(short(right0), right1, "x0"), (right0, short(right1), "x1")] {
                let result = step(&mut scene, rebuild, true, x0, x1);
                let expected = format!("minkq_scene_{call}_swept_async with 7 {name} vertices but the scene has 128");
                assert_eq!(result, Err(Error::InvalidArgument(expected)), "{what}");
            }
            // Device memory on a CPU device, in either buffer.
            let on_gpu = |b: Buffer<'_>| unsafe {
                // SAFETY: never read: the CPU device refuses device memory.
                Buffer::from_raw_parts(b.data(), b.byte_stride(), b.len(), Memory::Device)
            };
            for (x0, x1, name) in [(on_gpu(right0), right1, "x0"), (right0, on_gpu(right1), "x1")] {
                let (result, expected) =
                    (step(&mut scene, rebuild, true, x0, x1), format!("{name} is in device memory"));
                assert!(
                    matches!(&result, Err(Error::InvalidArgument(m)) if m.starts_with(&expected)),
                    "{what}: {result:?}"
                );
            }
            assert!(!scene.is_swept(), "{what}");
            assert_eq!(scene.async_status(Stream::null()), Ok(()), "{what}: nothing enqueued");
            let after: Vec<_> = queries().iter().map(|q| pairs_and_digest(&scene, q)).collect();
            assert_eq!(after, before, "{what}: a refused step moved the scene");
        }
        // The right buffers are taken.
        scene.rebuild_swept_async(right0, right1, Stream::null()).unwrap();
        scene.async_status(Stream::null()).unwrap();
        assert!(scene.is_swept());
    }
}
