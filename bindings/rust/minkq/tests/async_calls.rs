//! The stream-ordered scene calls on the CPU, where they run to completion and follow the
//! rules they follow on CUDA: asynchronous refits, rebuilds and queries give the blocking
//! calls' pairs; the count is exact when the capacity is short and nothing is written past
//! the buffer; buffers and reservations are reused across calls; digests and stats are
//! unsupported; missing reservations and memory of the wrong kind are refused at once; a
//! non-finite vertex is reported by `async_status`, which clears it, and leaves the scene's
//! positions as they were.
mod common;
use common::grid_triangles;
use common::sheets::rolled_sheet;

use minkq::{
    Buffer, CountOut, Device, Error, Memory, Mode, PairsOut, Query, QueryFlags, Reserve, Scene, SceneDesc, Stream,
};

const N: i32 = 12;
const R: f32 = 0.04;

fn scene_at(vertices: &[[f32; 3]]) -> Scene {
    Scene::new(&Device::cpu().unwrap(), &SceneDesc::new(vertices, &grid_triangles(N))).unwrap()
}

fn blocking(scene: &Scene, query: &Query) -> Vec<[i32; 2]> {
    let mut pairs = Vec::new();
    scene.query_into(&query.with_flags(QueryFlags::CANONICAL), &mut pairs).unwrap();
    pairs
}

fn queries() -> Vec<Query> {
    vec![
        Query::vt(Mode::Sphere, R),
        Query::vt(Mode::Box, R).with_flags(QueryFlags::LEAF_EXACT),
        Query::ee(Mode::CapsuleExact, R),
        Query::ee(Mode::Box, R).with_flags(QueryFlags::LEAF_EXACT),
    ]
}

const GUARD: [i32; 2] = [-7, -7];

/// Runs `query` asynchronously (canonical) into `capacity` pairs followed by 16 guard pairs;
/// returns the count and the pairs written, after checking the guards.
fn run_async(scene: &Scene, query: &Query, capacity: usize) -> (u64, Vec<[i32; 2]>) {
    let mut storage = vec![GUARD; capacity + 16];
    let mut count = u64::MAX;
    let q = query.with_flags(QueryFlags::CANONICAL);
    scene
        .query_async(&q, PairsOut::from_slice(&mut storage[..capacity]), CountOut::from_mut(&mut count), Stream::null())
        .unwrap();
    assert!(storage[capacity..].iter().all(|p| *p == GUARD), "{q:?} wrote past its buffer");
    let written = storage[..capacity.min(count as usize)].to_vec();
    (count, written)
}

#[test]
fn async_queries_give_the_blocking_pairs_and_exact_counts() {
    let mut scene = scene_at(&rolled_sheet(N, 3, 0.0));
    scene.reserve(Reserve::REFIT, 4096).unwrap();
    for query in queries() {
        let expected = blocking(&scene, &query);
        assert!(expected.len() > 10, "{query:?}: too few pairs to test with ({})", expected.len());
        let (count, pairs) = run_async(&scene, &query, 4096);
        assert_eq!((count as usize, &pairs), (expected.len(), &expected), "{query:?}");
        // Exactly enough room.
        let (count, pairs) = run_async(&scene, &query, expected.len());
        assert_eq!((count as usize, &pairs), (expected.len(), &expected), "{query:?}");
        // Too little: the exact count, `capacity` of the pairs (any order), nothing past them.
        for capacity in [0, 1, expected.len() - 1] {
            let mut storage = vec![GUARD; capacity + 16];
            let mut count = 0u64;
            let out = PairsOut::from_slice(&mut storage[..capacity]);
            scene
                .query_async(
                    &query.with_flags(QueryFlags::CANONICAL),
                    out,
                    CountOut::from_mut(&mut count),
                    Stream::null(),
                )
                .unwrap();
            assert_eq!(count as usize, expected.len(), "{query:?}, capacity {capacity}");
            assert!(storage[capacity..].iter().all(|p| *p == GUARD), "{query:?}, capacity {capacity}: wrote past it");
            let mut written = storage[..capacity].to_vec();
            written.sort();
            written.dedup();
            assert_eq!(written.len(), capacity, "{query:?}, capacity {capacity}: a pair twice");
            assert!(written.iter().all(|p| expected.binary_search(p).is_ok()), "{query:?}: a pair not found");
        }
        // Without CANONICAL: the same set, in any order.
        let mut storage = vec![GUARD; expected.len()];
        let mut count = 0u64;
        scene
            .query_async(&query, PairsOut::from_slice(&mut storage), CountOut::from_mut(&mut count), Stream::null())
            .unwrap();
        storage.sort_unstable();
        assert_eq!((count as usize, storage), (expected.len(), expected.clone()), "{query:?}, not canonical");
    }
}

#[test]
fn async_refit_and_rebuild_steps_reuse_buffers_and_match_blocking_scenes() {
    let first = rolled_sheet(N, 3, 0.0);
    let mut scene = scene_at(&first);
    scene.reserve(Reserve::REFIT | Reserve::REBUILD, 4096).unwrap();
    // Reservations only grow: a smaller one later changes nothing.
    scene.reserve(Reserve::REFIT, 16).unwrap();
    let (vt, ee) = (Query::vt(Mode::Box, R).with_flags(QueryFlags::LEAF_EXACT), Query::ee(Mode::CapsuleExact, R));
    let mut vt_pairs = vec![GUARD; 4096 + 16];
    let mut ee_pairs = vec![GUARD; 4096 + 16];
    let (mut vt_count, mut ee_count) = (0u64, 0u64);
    for step in 1..6 {
        let vertices = rolled_sheet(N, 3 + step, 0.05 * step as f64);
        if step % 2 == 0 {
            scene.rebuild_async(Buffer::from_slice(&vertices), Stream::null()).unwrap();
        } else {
            scene.refit_async(Buffer::from_slice(&vertices), Stream::null()).unwrap();
        }
        let reference = scene_at(&vertices);
        let canonical = QueryFlags::CANONICAL;
        scene
            .query_vt_ee_async(
                &vt.with_flags(canonical),
                &ee.with_flags(canonical),
                PairsOut::from_slice(&mut vt_pairs[..4096]),
                CountOut::from_mut(&mut vt_count),
                PairsOut::from_slice(&mut ee_pairs[..4096]),
                CountOut::from_mut(&mut ee_count),
                Stream::null(),
            )
            .unwrap();
        scene.async_status(Stream::null()).unwrap();
        let (vt_expected, ee_expected) = (blocking(&reference, &vt), blocking(&reference, &ee));
        assert_eq!(&vt_pairs[..vt_count as usize], &vt_expected[..], "step {step}: VT");
        assert_eq!(&ee_pairs[..ee_count as usize], &ee_expected[..], "step {step}: EE");
        assert!(vt_pairs[4096..].iter().chain(&ee_pairs[4096..]).all(|p| *p == GUARD));
        // The blocking calls see the positions the asynchronous ones gave the scene.
        assert_eq!(blocking(&scene, &vt), vt_expected, "step {step}: blocking VT after async");
        if step % 2 == 0 {
            assert_eq!(scene.tree_growth().unwrap(), 1.0, "step {step}: a rebuild resets the growth");
        }
    }
    // query_vt_ee_async with a short EE buffer: both counts exact, VT written in full.
    let vt_expected = blocking(&scene, &vt);
    let ee_expected = blocking(&scene, &ee);
    let mut short = vec![GUARD; ee_expected.len() - 1 + 16];
    scene
        .query_vt_ee_async(
            &vt.with_flags(QueryFlags::CANONICAL),
            &ee,
            PairsOut::from_slice(&mut vt_pairs[..4096]),
            CountOut::from_mut(&mut vt_count),
            PairsOut::from_slice(&mut short[..ee_expected.len() - 1]),
            CountOut::from_mut(&mut ee_count),
            Stream::null(),
        )
        .unwrap();
    assert_eq!((vt_count as usize, ee_count as usize), (vt_expected.len(), ee_expected.len()));
    assert_eq!(&vt_pairs[..vt_expected.len()], &vt_expected[..]);
    let n = ee_expected.len() - 1;
    assert!(short[n..].iter().all(|p| *p == GUARD), "wrote past the short buffer");
    assert!(short[..n].iter().all(|p| ee_expected.contains(p)), "a pair not found");
}

#[test]
fn digest_and_stats_are_unsupported_and_nothing_is_written() {
    let mut scene = scene_at(&rolled_sheet(N, 3, 0.0));
    scene.reserve(Reserve::REFIT, 4096).unwrap();
    for flags in [QueryFlags::DIGEST, QueryFlags::STATS, QueryFlags::CANONICAL | QueryFlags::DIGEST] {
        for query in queries() {
            let mut pairs = vec![GUARD; 4096];
            let mut count = 12345u64;
            let result = scene.query_async(
                &query.with_flags(flags),
                PairsOut::from_slice(&mut pairs),
                CountOut::from_mut(&mut count),
                Stream::null(),
            );
            assert!(matches!(result, Err(Error::Unsupported(_))), "{flags:?}: {result:?}");
            assert_eq!(count, 12345, "{flags:?}: the count was written");
            assert!(pairs.iter().all(|p| *p == GUARD), "{flags:?}: pairs were written");
        }
    }
    let (mut a, mut b) = ([GUARD; 8], [GUARD; 8]);
    let (mut ca, mut cb) = (0u64, 0u64);
    let result = scene.query_vt_ee_async(
        &Query::vt(Mode::Box, R),
        &Query::ee(Mode::Box, R).with_flags(QueryFlags::STATS),
        PairsOut::from_slice(&mut a),
        CountOut::from_mut(&mut ca),
        PairsOut::from_slice(&mut b),
        CountOut::from_mut(&mut cb),
        Stream::null(),
    );
    assert!(matches!(result, Err(Error::Unsupported(_))), "{result:?}");
}

#[test]
fn missing_reservations_and_wrong_arguments_are_refused_at_once() {
    let vertices = rolled_sheet(N, 3, 0.0);
    let mut scene = scene_at(&vertices);
    let moved = rolled_sheet(N, 4, 0.1);
    let before = blocking(&scene, &Query::ee(Mode::Box, R));
    for result in [
        scene.refit_async(Buffer::from_slice(&moved), Stream::null()),
        scene.rebuild_async(Buffer::from_slice(&moved), Stream::null()),
    ] {
        assert!(matches!(&result, Err(Error::InvalidArgument(_))), "{result:?}");
    }
    assert_eq!(blocking(&scene, &Query::ee(Mode::Box, R)), before, "a refused call moved the scene");
    // A canonical query needs its capacity reserved; a plain one needs nothing.
    let mut pairs = vec![GUARD; 64];
    let mut count = 0u64;
    let canonical = Query::ee(Mode::Box, R).with_flags(QueryFlags::CANONICAL);
    let result =
        scene.query_async(&canonical, PairsOut::from_slice(&mut pairs), CountOut::from_mut(&mut count), Stream::null());
    assert!(matches!(&result, Err(Error::InvalidArgument(_))), "{result:?}");
    scene
        .query_async(
            &Query::ee(Mode::Box, R),
            PairsOut::from_slice(&mut pairs),
            CountOut::from_mut(&mut count),
            Stream::null(),
        )
        .unwrap();
    assert_eq!(count as usize, before.len());
    // REFIT does not cover rebuilds; a canonical capacity over the reservation is refused.
    scene.reserve(Reserve::REFIT, 32).unwrap();
    scene.refit_async(Buffer::from_slice(&moved), Stream::null()).unwrap();
    let result = scene.rebuild_async(Buffer::from_slice(&moved), Stream::null());
    assert!(matches!(&result, Err(Error::InvalidArgument(_))), "{result:?}");
    let result =
        scene.query_async(&canonical, PairsOut::from_slice(&mut pairs), CountOut::from_mut(&mut count), Stream::null());
    assert!(matches!(&result, Err(Error::InvalidArgument(_))), "capacity 64 over 32 reserved: {result:?}");
    scene
        .query_async(&canonical, PairsOut::from_slice(&mut pairs[..32]), CountOut::from_mut(&mut count), Stream::null())
        .unwrap();
    // Unknown reservation bits; the blocking errors of the description and buffers.
    assert!(matches!(scene.reserve(Reserve::empty(), 0), Ok(())));
    let result = scene.refit_async(Buffer::from_slice(&moved[..10]), Stream::null());
    assert!(matches!(&result, Err(Error::InvalidArgument(_))), "{result:?}");
    let result = scene.query_async(
        &Query::ee(Mode::Sphere, R),
        PairsOut::from_slice(&mut pairs),
        CountOut::from_mut(&mut count),
        Stream::null(),
    );
    assert!(matches!(&result, Err(Error::InvalidArgument(_))), "{result:?}");
    let result = scene.query_async(
        &Query::ee(Mode::Box, f32::NAN),
        PairsOut::from_slice(&mut pairs),
        CountOut::from_mut(&mut count),
        Stream::null(),
    );
    assert!(matches!(&result, Err(Error::NonFinite(_))), "{result:?}");
    let result = scene.query_vt_ee_async(
        &Query::ee(Mode::Box, R),
        &Query::vt(Mode::Box, R),
        PairsOut::from_slice(&mut [GUARD; 4]),
        CountOut::from_mut(&mut 0),
        PairsOut::from_slice(&mut [GUARD; 4]),
        CountOut::from_mut(&mut 0),
        Stream::null(),
    );
    assert!(matches!(&result, Err(Error::InvalidArgument(_))), "swapped kinds: {result:?}");
    // One count for both queries (only raw parts can alias).
    let mut shared = 0u64;
    let (a, b) = unsafe {
        // SAFETY: host memory of `shared`, written by this CPU call only (it refuses the alias).
        (CountOut::from_raw_parts(&mut shared, Memory::Host), CountOut::from_raw_parts(&mut shared, Memory::Host))
    };
    let result = scene.query_vt_ee_async(
        &Query::vt(Mode::Box, R),
        &Query::ee(Mode::Box, R),
        PairsOut::from_slice(&mut [GUARD; 4]),
        a,
        PairsOut::from_slice(&mut [GUARD; 4]),
        b,
        Stream::null(),
    );
    assert!(matches!(&result, Err(Error::InvalidArgument(_))), "aliased counts: {result:?}");
    // Device memory on a CPU device, refused by the crate before the library could write it.
    let mut storage = [GUARD; 4];
    // SAFETY: never written: the CPU device refuses device memory.
    let on_gpu = unsafe { PairsOut::from_raw_parts(storage.as_mut_ptr().cast(), 4, Memory::Device) };
    let result = scene.query_async(&Query::ee(Mode::Box, R), on_gpu, CountOut::from_mut(&mut count), Stream::null());
    assert!(matches!(&result, Err(Error::InvalidArgument(m)) if m.starts_with("out: device memory")), "{result:?}");
    let mut on_gpu_count = 99u64;
    // SAFETY: as above.
    let count_out = unsafe { CountOut::from_raw_parts(&mut on_gpu_count, Memory::Device) };
    let result =
        scene.query_async(&Query::ee(Mode::Box, R), PairsOut::from_slice(&mut storage), count_out, Stream::null());
    assert!(matches!(&result, Err(Error::InvalidArgument(m)) if m.starts_with("count: device memory")), "{result:?}");
    assert_eq!((on_gpu_count, storage), (99, [GUARD; 4]));
    // SAFETY: never read: the CPU device refuses device vertices.
    let device_vertices = unsafe { Buffer::from_raw_parts(moved.as_ptr().cast(), 12, moved.len(), Memory::Device) };
    let result = scene.refit_async(device_vertices, Stream::null());
    assert!(matches!(&result, Err(Error::InvalidArgument(_))), "{result:?}");
    // A CPU device ignores the stream it is given.
    // SAFETY: ignored by the CPU device.
    let stream = unsafe { Stream::from_raw(0x1234 as *mut std::ffi::c_void) };
    scene.refit_async(Buffer::from_slice(&moved), stream).unwrap();
    scene.async_status(stream).unwrap();
}

#[test]
fn a_non_finite_vertex_is_reported_by_async_status_and_the_scene_keeps_its_positions() {
    let vertices = rolled_sheet(N, 3, 0.0);
    let mut scene = scene_at(&vertices);
    scene.reserve(Reserve::REFIT | Reserve::REBUILD, 4096).unwrap();
    let before: Vec<_> = queries().iter().map(|q| blocking(&scene, q)).collect();
    let async_before: Vec<_> = queries().iter().map(|q| run_async(&scene, q, 4096)).collect();
    for (call, bad_value) in [("refit", f32::NAN), ("rebuild", f32::INFINITY), ("refit", f32::NEG_INFINITY)] {
        let mut bad = rolled_sheet(N, 9, 0.3);
        bad[12][1] = bad_value;
        let result = if call == "refit" {
            scene.refit_async(Buffer::from_slice(&bad), Stream::null())
        } else {
            scene.rebuild_async(Buffer::from_slice(&bad), Stream::null())
        };
        assert_eq!(result, Ok(()), "{call}: a non-finite vertex is not an error at once");
        // The queries run on the positions the scene kept.
        for (k, query) in queries().iter().enumerate() {
            assert_eq!(blocking(&scene, query), before[k], "{call}: {query:?} after a refused refit");
            assert_eq!(run_async(&scene, query, 4096), async_before[k], "{call}: async {query:?}");
        }
        match scene.async_status(Stream::null()) {
            Err(Error::NonFinite(message)) => {
                assert!(message.contains(&format!("minkq_scene_{call}_async")), "{message}");
                assert!(message.contains("vertex 12"), "{message}");
            }
            other => panic!("{call}: expected NonFinite, got {other:?}"),
        }
        assert_eq!(scene.async_status(Stream::null()), Ok(()), "{call}: the pending error was not cleared");
    }
    // The first refused call is reported; a later good one does not hide it.
    let mut bad = vertices.clone();
    bad[3][0] = f32::NAN;
    scene.refit_async(Buffer::from_slice(&bad), Stream::null()).unwrap();
    let moved = rolled_sheet(N, 5, 0.2);
    scene.refit_async(Buffer::from_slice(&moved), Stream::null()).unwrap();
    let result = scene.async_status(Stream::null());
    assert!(matches!(&result, Err(Error::NonFinite(m)) if m.contains("vertex 3")), "{result:?}");
    assert_eq!(blocking(&scene, &queries()[2]), blocking(&scene_at(&moved), &queries()[2]), "the good refit applied");
    assert_eq!(scene.async_status(Stream::null()), Ok(()));
}
