//! Float64 vertices (`SceneFlags::FLOAT64`) through the safe crate: pairs that rounding to float
//! pulls apart are found in every mode, at creation and after refits and rebuilds (blocking,
//! from buffers and stream-ordered), where a float scene of the rounded positions loses them;
//! doubles that are floats already give the float scene's pairs and digests; a float64 scene
//! keeps every pair of the float scene of its rounded positions; vertices of the other
//! precision are refused by scenes (and doubles by BVHs) before the library could misread them;
//! a double beyond the float range is non-finite.
mod common;
use common::{grid_triangles, Rng};

use minkq::{
    Aabb, Buffer, Bvh, BvhBufferQuery, Device, Error, Memory, Mode, Query, QueryFlags, Reserve, Scene, SceneBuffers,
    SceneDesc, SceneFlags, Stream,
};

const R: f32 = 1e-3;
const VT_MODES: [Mode; 4] = [Mode::Box, Mode::Sphere, Mode::CapsuleRay, Mode::CapsuleExact];
const EE_MODES: [Mode; 3] = [Mode::Box, Mode::CapsuleRay, Mode::CapsuleExact];
const LEAF_FLAGS: [QueryFlags; 2] = [QueryFlags::empty(), QueryFlags::LEAF_EXACT];

/// The float spacing at x > 0.
fn ulp(x: f32) -> f64 {
    f64::from(f32::from_bits(x.to_bits() + 1)) - f64::from(x)
}

/// (plane, point) offsets near `base` with point - plane = fraction * r <= r in double, but
/// more than r apart once both are rounded to nearest float: one per fraction, as the C tests
/// choose them. Float distances near 2e4 are multiples of 2^-9 > r = 1e-3.
fn pulled_apart(base: f32, r: f32) -> Vec<(f64, f64)> {
    let u = ulp(base);
    let mut found = Vec::new();
    for fraction in [0.90, 0.93, 0.95, 0.97, 0.99, 0.999] {
        for k in 0..64 {
            let plane = f64::from(base) + (k as f64 / 64.0 - 0.5) * u;
            let point = plane + fraction * f64::from(r);
            if point as f32 - plane as f32 > r {
                assert!(point - plane <= f64::from(r));
                found.push((plane, point));
                break;
            }
        }
    }
    found
}

/// Vertex 3 at x = point facing a triangle in the plane x = plane.
fn vertex_over_triangle(plane: f64, point: f64) -> Vec<[f64; 3]> {
    vec![[plane, -1.0, -1.0], [plane, 2.0, -1.0], [plane, -1.0, 2.0], [point, 0.0, 0.0]]
}
const TRIANGLE: [[i32; 3]; 1] = [[0, 1, 2]];

/// Edge 0 along y at x = plane, edge 1 along z at x = point (an EE-only mesh).
fn crossed_edges(plane: f64, point: f64) -> Vec<[f64; 3]> {
    vec![[plane, -1.0, 0.0], [plane, 1.0, 0.0], [point, 0.0, -1.0], [point, 0.0, 1.0]]
}
const EDGES: [[i32; 2]; 2] = [[0, 1], [2, 3]];

fn rounded(vertices: &[[f64; 3]]) -> Vec<[f32; 3]> {
    vertices.iter().map(|v| v.map(|x| x as f32)).collect()
}

fn pairs(scene: &Scene, query: Query) -> Vec<[i32; 2]> {
    let mut out = Vec::new();
    scene.query_into(&query.with_flags(QueryFlags::CANONICAL), &mut out).unwrap();
    out
}

fn vt_scene(device: &Device, vertices: &[[f64; 3]]) -> Scene {
    Scene::new(device, &SceneDesc::new_f64(vertices, &TRIANGLE).flags(SceneFlags::VT | SceneFlags::DROP_INCIDENT))
        .unwrap()
}

fn ee_scene(device: &Device, vertices: &[[f64; 3]]) -> Scene {
    let desc = SceneDesc::new_f64(vertices, &[]).edges(&EDGES).flags(SceneFlags::EE | SceneFlags::DROP_INCIDENT);
    Scene::new(device, &desc).unwrap()
}

/// Every VT mode, with and without LEAF_EXACT, finds exactly (3, 0).
fn assert_vt_found(scene: &Scene, what: &str) {
    for flags in LEAF_FLAGS {
        for mode in VT_MODES {
            let query = Query::vt(mode, R).with_flags(flags);
            assert_eq!(pairs(scene, query), vec![[3, 0]], "{what}: {query:?}");
        }
    }
}

/// Every EE mode, with and without LEAF_EXACT, finds exactly (0, 1).
fn assert_ee_found(scene: &Scene, what: &str) {
    for flags in LEAF_FLAGS {
        for mode in EE_MODES {
            let query = Query::ee(mode, R).with_flags(flags);
            assert_eq!(pairs(scene, query), vec![[0, 1]], "{what}: {query:?}");
        }
    }
}

fn leaf_exact_vt() -> Query {
    Query::vt(Mode::Box, R).with_flags(QueryFlags::LEAF_EXACT)
}

fn leaf_exact_ee() -> Query {
    Query::ee(Mode::Box, R).with_flags(QueryFlags::LEAF_EXACT)
}

#[test]
fn pairs_that_rounding_pulls_apart_are_found_in_every_mode() {
    let device = Device::cpu().unwrap();
    let cases = pulled_apart(2e4, R);
    assert_eq!(cases.len(), 6);
    for (plane, point) in cases {
        let what = format!("plane {plane} point {point}");
        let (vt, ee) = (vertex_over_triangle(plane, point), crossed_edges(plane, point));
        // The rounded positions as a float scene: its leaf test rightly finds them beyond r.
        let float_vt = Scene::new(&device, &SceneDesc::new(&rounded(&vt), &TRIANGLE)).unwrap();
        assert!(!float_vt.is_float64());
        assert!(pairs(&float_vt, leaf_exact_vt()).is_empty(), "{what}");
        let float_ee =
            Scene::new(&device, &SceneDesc::new(&rounded(&ee), &[]).edges(&EDGES).flags(SceneFlags::EE)).unwrap();
        assert!(pairs(&float_ee, leaf_exact_ee()).is_empty(), "{what}");
        // The doubles: found in every mode.
        let scene = vt_scene(&device, &vt);
        assert!(scene.is_float64());
        assert_vt_found(&scene, &what);
        assert_ee_found(&ee_scene(&device, &ee), &what);
        // The default flags (VT, EE, incident pairs dropped, edges derived) find it too.
        let full = Scene::new(&device, &SceneDesc::new_f64(&vt, &TRIANGLE)).unwrap();
        assert_vt_found(&full, &what);
    }
}

#[test]
fn buffers_of_doubles_create_float64_scenes() {
    let device = Device::cpu().unwrap();
    let (plane, point) = pulled_apart(2e4, R)[2];
    let vt = vertex_over_triangle(plane, point);
    let flags = SceneFlags::VT | SceneFlags::DROP_INCIDENT | SceneFlags::FLOAT64;
    // A slice of [f64; 3] with the flag.
    let desc = SceneBuffers::new(Buffer::from_slice(&vt), Buffer::from_slice(&TRIANGLE)).flags(flags);
    assert_vt_found(&Scene::from_buffers(&device, &desc).unwrap(), "slice buffer");
    // SceneDesc::new_f64 converts with the flag added, also when other flags replaced its own.
    let converted = SceneBuffers::from(&SceneDesc::new_f64(&vt, &TRIANGLE).flags(SceneFlags::VT));
    assert_eq!(converted.flags, SceneFlags::VT | SceneFlags::FLOAT64);
    // A raw buffer of 4 doubles per record (32 bytes): read as doubles because of the flag.
    let padded: Vec<[f64; 4]> = vt.iter().map(|v| [v[0], v[1], v[2], f64::NAN]).collect();
    // SAFETY: four 32-byte records starting with x, y, z, borrowed from `padded`.
    let raw = unsafe { Buffer::from_raw_parts(padded.as_ptr().cast(), 32, padded.len(), Memory::Host) };
    let scene = Scene::from_buffers(&device, &SceneBuffers::new(raw, Buffer::from_slice(&TRIANGLE)).flags(flags));
    assert_vt_found(&scene.unwrap(), "raw buffer, stride 32");
    // A stride under 3 doubles is refused by the library.
    // SAFETY: as above; the library refuses the stride before reading.
    let short = unsafe { Buffer::from_raw_parts(padded.as_ptr().cast(), 16, padded.len(), Memory::Host) };
    let err = Scene::from_buffers(&device, &SceneBuffers::new(short, Buffer::from_slice(&TRIANGLE)).flags(flags));
    assert!(matches!(err, Err(Error::InvalidArgument(_))), "{err:?}");
}

#[test]
fn refit_and_rebuild_take_f64_vertices() {
    let device = Device::cpu().unwrap();
    let (plane, point) = pulled_apart(2e4, R)[3];
    let near = vertex_over_triangle(plane, point);
    let mut far = near.clone();
    far[3][0] += 0.5;
    let mut scene = vt_scene(&device, &far);
    assert!(pairs(&scene, leaf_exact_vt()).is_empty());

    scene.refit(&near).unwrap();
    assert_vt_found(&scene, "refit_f64");
    scene.refit(&far).unwrap();
    assert!(pairs(&scene, leaf_exact_vt()).is_empty());
    scene.rebuild(&near).unwrap();
    assert_vt_found(&scene, "rebuild_f64");
    assert_eq!(scene.tree_growth().unwrap(), 1.0);

    // Through buffers: slices and a raw strided buffer.
    scene.refit(Buffer::from_slice(&far)).unwrap();
    assert!(pairs(&scene, leaf_exact_vt()).is_empty());
    scene.rebuild(Buffer::from_slice(&near)).unwrap();
    assert_vt_found(&scene, "rebuild_buffer");
    let padded: Vec<[f64; 4]> = far.iter().map(|v| [v[0], v[1], v[2], 0.0]).collect();
    // SAFETY: four 32-byte records starting with x, y, z, borrowed from `padded`.
    scene.refit(unsafe { Buffer::from_raw_parts(padded.as_ptr().cast(), 32, 4, Memory::Host) }).unwrap();
    assert!(pairs(&scene, leaf_exact_vt()).is_empty());

    // Stream-ordered (on the CPU they have run when they return).
    scene.reserve(Reserve::REFIT | Reserve::REBUILD, 0).unwrap();
    scene.refit_async(Buffer::from_slice(&near), Stream::null()).unwrap();
    scene.async_status(Stream::null()).unwrap();
    assert_vt_found(&scene, "refit_async");
    scene.rebuild_async(Buffer::from_slice(&far), Stream::null()).unwrap();
    scene.async_status(Stream::null()).unwrap();
    assert!(pairs(&scene, leaf_exact_vt()).is_empty());
    scene.rebuild_async(Buffer::from_slice(&near), Stream::null()).unwrap();
    scene.async_status(Stream::null()).unwrap();
    assert_vt_found(&scene, "rebuild_async");

    // EE after a refit.
    let (plane, point) = pulled_apart(2e4, R)[0];
    let near = crossed_edges(plane, point);
    let mut far = near.clone();
    far[2][0] += 0.5;
    far[3][0] += 0.5;
    let mut scene = ee_scene(&device, &far);
    assert!(pairs(&scene, leaf_exact_ee()).is_empty());
    scene.refit(&near).unwrap();
    assert_ee_found(&scene, "EE refit_f64");
}

/// A jittered n x n sheet in float, then at `offset` in double with every coordinate nudged by
/// up to half its float spacing (so that rounding moves every vertex).
fn sheets(n: i32, seed: u64, offset: f64) -> (Vec<[f32; 3]>, Vec<[f64; 3]>) {
    let mut rng = Rng(seed);
    let mut floats = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let (u, v) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
            let z = 0.05 * (9.0 * u).sin() * (7.0 * v).cos() + 0.01 * (rng.uniform() - 0.5);
            floats.push([u as f32, v as f32, z as f32]);
        }
    }
    let doubles = floats
        .iter()
        .map(|p| {
            p.map(|x| {
                let x = f64::from(x) + offset;
                x + (rng.uniform() - 0.5) * ulp((x.abs() as f32).max(f32::MIN_POSITIVE))
            })
        })
        .collect();
    (floats, doubles)
}

fn every_query(r: f32) -> Vec<Query> {
    let mut queries = Vec::new();
    for flags in LEAF_FLAGS {
        queries.extend(VT_MODES.map(|m| Query::vt(m, r).with_flags(flags)));
        queries.extend(EE_MODES.map(|m| Query::ee(m, r).with_flags(flags)));
    }
    queries
}

#[test]
fn doubles_that_are_floats_give_the_float_scene_pairs_and_digests() {
    let device = Device::cpu().unwrap();
    let triangles = grid_triangles(10);
    let (floats, _) = sheets(10, 7, 0.0);
    let doubles: Vec<[f64; 3]> = floats.iter().map(|p| p.map(f64::from)).collect();
    let float_scene = Scene::new(&device, &SceneDesc::new(&floats, &triangles)).unwrap();
    let double_scene = Scene::new(&device, &SceneDesc::new_f64(&doubles, &triangles)).unwrap();
    for query in every_query(0.15) {
        let q = query.with_flags(QueryFlags::DIGEST);
        let (mut a, mut b) = (Vec::new(), Vec::new());
        let (ia, ib) = (float_scene.query_into(&q, &mut a).unwrap(), double_scene.query_into(&q, &mut b).unwrap());
        assert!(!a.is_empty(), "{query:?}");
        assert_eq!(a, b, "{query:?}");
        assert_eq!(ia.digest, ib.digest, "{query:?}");
    }
}

#[test]
fn a_float64_scene_keeps_every_pair_of_its_rounded_float_scene() {
    let device = Device::cpu().unwrap();
    let triangles = grid_triangles(12);
    for (seed, offset) in [(1, 0.0), (2, 1e4), (3, -3e5)] {
        let (_, doubles) = sheets(12, seed, offset);
        let float_scene = Scene::new(&device, &SceneDesc::new(&rounded(&doubles), &triangles)).unwrap();
        let mut scene = Scene::new(&device, &SceneDesc::new_f64(&doubles, &triangles)).unwrap();
        let check = |scene: &Scene, what: &str| {
            for query in every_query(0.15) {
                let (rounded_pairs, got) = (pairs(&float_scene, query), pairs(scene, query));
                assert!(!rounded_pairs.is_empty(), "{query:?}");
                let lost: Vec<_> = rounded_pairs.iter().filter(|p| got.binary_search(p).is_err()).collect();
                assert!(lost.is_empty(), "offset {offset} {what} {query:?} lost {lost:?}");
            }
        };
        check(&scene, "created");
        scene.refit(&doubles).unwrap();
        check(&scene, "refit");
        scene.rebuild(&doubles).unwrap();
        check(&scene, "rebuilt");
    }
}

fn assert_precision_refused<T: std::fmt::Debug>(result: minkq::Result<T>, call: &str, got: &str, wanted: &str) {
    match result {
        Err(Error::InvalidArgument(m)) => {
            assert!(m.starts_with(&format!("{call}: ")), "{m}");
            assert!(m.contains(got) && m.contains(wanted) && m.contains("SceneFlags::FLOAT64"), "{m}");
        }
        other => panic!("{call}: expected InvalidArgument, got {other:?}"),
    }
}

#[test]
fn vertices_of_the_other_precision_are_refused() {
    let device = Device::cpu().unwrap();
    let (plane, point) = pulled_apart(2e4, R)[1];
    let doubles = vertex_over_triangle(plane, point);
    let floats = rounded(&doubles);
    let (f32s, f64s) = ("[f32; 3]", "[f64; 3]");

    // A float64 scene refuses floats in every call, and keeps its positions and trees.
    let mut scene = vt_scene(&device, &doubles);
    scene.reserve(Reserve::REBUILD, 0).unwrap();
    assert_precision_refused(scene.refit(&floats), "refit", f32s, f64s);
    assert_precision_refused(scene.rebuild(&floats), "rebuild", f32s, f64s);
    assert_precision_refused(scene.refit(Buffer::from_slice(&floats)), "refit", f32s, f64s);
    assert_precision_refused(scene.rebuild(Buffer::from_slice(&floats)), "rebuild", f32s, f64s);
    let async_refit = scene.refit_async(Buffer::from_slice(&floats), Stream::null());
    assert_precision_refused(async_refit, "refit_async", f32s, f64s);
    let async_rebuild = scene.rebuild_async(Buffer::from_slice(&floats), Stream::null());
    assert_precision_refused(async_rebuild, "rebuild_async", f32s, f64s);
    scene.async_status(Stream::null()).unwrap();
    assert_vt_found(&scene, "after the refused calls");

    // A float scene refuses doubles in every call.
    let mut scene = Scene::new(&device, &SceneDesc::new(&floats, &TRIANGLE)).unwrap();
    scene.reserve(Reserve::REBUILD, 0).unwrap();
    let err = scene.refit(&doubles).unwrap_err();
    assert_eq!(
        err,
        Error::InvalidArgument(
            "refit: [f64; 3] vertices, but a scene without SceneFlags::FLOAT64 reads [f32; 3]".into()
        )
    );
    assert_precision_refused(scene.rebuild(&doubles), "rebuild", f64s, f32s);
    assert_precision_refused(scene.refit(Buffer::from_slice(&doubles)), "refit", f64s, f32s);
    assert_precision_refused(scene.rebuild(Buffer::from_slice(&doubles)), "rebuild", f64s, f32s);
    let async_refit = scene.refit_async(Buffer::from_slice(&doubles), Stream::null());
    assert_precision_refused(async_refit, "refit_async", f64s, f32s);
    let async_rebuild = scene.rebuild_async(Buffer::from_slice(&doubles), Stream::null());
    assert_precision_refused(async_rebuild, "rebuild_async", f64s, f32s);
    assert!(pairs(&scene, leaf_exact_vt()).is_empty(), "the float scene kept its positions");

    // Creation: the flag and the slice disagree.
    let flagged = SceneDesc::new(&floats, &TRIANGLE).flags(SceneFlags::VT | SceneFlags::FLOAT64);
    assert_precision_refused(Scene::new(&device, &flagged), "create", f32s, f64s);
    let unflagged = SceneBuffers::new(Buffer::from_slice(&doubles), Buffer::from_slice(&TRIANGLE));
    assert_precision_refused(Scene::from_buffers(&device, &unflagged), "create", f64s, f32s);

    // Raw buffers carry no precision: the scene's flag decides (here: doubles, read as such).
    let mut scene = vt_scene(&device, &doubles);
    // SAFETY: four packed 24-byte records of 3 doubles, borrowed from `doubles`.
    scene.refit(unsafe { Buffer::from_raw_parts(doubles.as_ptr().cast(), 0, 4, Memory::Host) }).unwrap();
    assert_vt_found(&scene, "raw packed doubles");
}

#[test]
fn a_bvh_refuses_doubles() {
    let device = Device::cpu().unwrap();
    let doubles = [[0.0f64; 3], [1.0; 3]];
    let expected = |call: &str| Error::InvalidArgument(format!("{call}: [f64; 3] records, but a Bvh reads floats"));
    assert_eq!(Bvh::from_buffer(&device, Buffer::from_slice(&doubles)).unwrap_err(), expected("create: boxes"));
    let mut bvh = Bvh::new(&device, &[Aabb::new([0.0; 3], [1.0; 3])]).unwrap();
    assert_eq!(bvh.refit(Buffer::from_slice(&doubles)).unwrap_err(), expected("refit: boxes"));
    assert_eq!(bvh.rebuild(Buffer::from_slice(&doubles)).unwrap_err(), expected("rebuild: boxes"));
    let spheres = BvhBufferQuery::spheres(Buffer::from_slice(&doubles), Mode::Sphere, 0.1);
    let mut out = Vec::new();
    assert_eq!(
        bvh.query_into(spheres, minkq::PairsOut::from_slice(&mut [[0; 2]; 4])).unwrap_err(),
        expected("query: first")
    );
    let capsules = BvhBufferQuery::capsules(
        Buffer::from_slice(&[[0.0f32; 3]]),
        Buffer::from_slice(&[[1.0f64; 3]]),
        Mode::CapsuleExact,
        0.1,
    );
    assert_eq!(
        bvh.query_into(capsules, minkq::PairsOut::from_slice(&mut [[0; 2]; 4])).unwrap_err(),
        expected("query: second")
    );
    // Floats still pass.
    let centres = [[0.5f32; 3]];
    let ok = BvhBufferQuery::spheres(Buffer::from_slice(&centres), Mode::Sphere, 0.1);
    out.resize(4, [0; 2]);
    assert_eq!(bvh.query_into(ok, minkq::PairsOut::from_slice(&mut out)).unwrap().count, 1);
}

#[test]
fn a_double_beyond_the_float_range_is_non_finite() {
    let device = Device::cpu().unwrap();
    let (plane, point) = pulled_apart(2e4, R)[4];
    let good = vertex_over_triangle(plane, point);
    for bad_value in [1e39, -1e39, f64::MAX, f64::NAN, f64::INFINITY] {
        let mut bad = good.clone();
        bad[2][1] = bad_value;
        let non_finite = |result: minkq::Result<()>, what: &str| match result {
            Err(Error::NonFinite(m)) => assert!(m.contains("vertex 2"), "{what} {bad_value}: {m}"),
            other => panic!("{what} {bad_value}: expected NonFinite, got {other:?}"),
        };
        non_finite(Scene::new(&device, &SceneDesc::new_f64(&bad, &TRIANGLE)).map(drop), "create");
        let mut scene = vt_scene(&device, &good);
        non_finite(scene.refit(&bad), "refit_f64");
        non_finite(scene.rebuild(&bad), "rebuild_f64");
        assert_vt_found(&scene, "kept its positions");
        scene.reserve(Reserve::REBUILD, 0).unwrap();
        scene.refit_async(Buffer::from_slice(&bad), Stream::null()).unwrap();
        non_finite(scene.async_status(Stream::null()), "refit_async");
        scene.rebuild_async(Buffer::from_slice(&bad), Stream::null()).unwrap();
        non_finite(scene.async_status(Stream::null()), "rebuild_async");
        assert_vt_found(&scene, "kept its positions after async");
    }
    // The largest float itself is finite.
    let mut edge = good.clone();
    edge[2][1] = f64::from(f32::MAX);
    Scene::new(&device, &SceneDesc::new_f64(&edge, &TRIANGLE)).unwrap();
}
