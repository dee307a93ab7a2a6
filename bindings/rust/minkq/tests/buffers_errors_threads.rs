//! Buffers, digests, errors and threads through the safe crate: strided records and BVH
//! buffer queries give the pairs of packed slices; a short buffer gets the exact count and
//! nothing written past it; digests are an independent XXH64 (common::xxh64) of the canonical
//! pairs; bad input gets its error and message; scenes move to other threads and share their
//! device.
mod common;
use common::oracle::{pairs_of, Pairs};
use common::sheets::crumpled_sheet;
use common::xxh64::xxh64;

use std::sync::{Arc, Mutex};
use std::thread;

use minkq::{
    Aabb, Buffer, Bvh, BvhBufferQuery, BvhQuery, Device, Error, Memory, Mode, PairBuffer, PairsOut, Query, QueryFlags,
    Scene, SceneBuffers, SceneDesc, SceneFlags,
};

/// Strided records read in place give the pairs of the packed slices: vertices as vec4
/// records, edges as the last two columns of a (E, 4) table, pairs written through PairsOut.
#[test]
fn strided_buffers_give_the_pairs_of_packed_slices() {
    let device = Device::cpu().unwrap();
    let mesh = crumpled_sheet(9, 21);
    let r = 0.03;
    let packed = Scene::new(&device, &SceneDesc::new(&mesh.vertices, &mesh.triangles)).unwrap();
    let edges = packed.edges().unwrap();
    let vec4: Vec<[f32; 4]> = mesh.vertices.iter().map(|v| [v[0], v[1], v[2], f32::NAN]).collect();
    let table: Vec<[i32; 4]> = edges.iter().map(|e| [-7, -7, e[0], e[1]]).collect();
    // SAFETY: vec4 records of 16 bytes starting with x, y, z; 16-byte edge records with the
    // two vertices 8 bytes in; both borrowed for the scene's construction.
    let (vertices, table_edges) = unsafe {
        (
            Buffer::from_raw_parts(vec4.as_ptr().cast(), 16, vec4.len(), Memory::Host),
            Buffer::from_raw_parts(table.as_ptr().cast(), 16, table.len(), Memory::Host).offset(8),
        )
    };
    let mut strided = Scene::from_buffers(
        &device,
        &SceneBuffers::new(vertices, Buffer::from_slice(&mesh.triangles)).edges(table_edges),
    )
    .unwrap();
    assert_eq!(strided.edges().unwrap(), edges);
    for query in [
        Query::vt(Mode::Sphere, r).with_flags(QueryFlags::LEAF_EXACT),
        Query::ee(Mode::CapsuleExact, r).with_flags(QueryFlags::LEAF_EXACT),
    ] {
        let expected = pairs_of(&packed, query);
        let mut storage = vec![[0i32; 2]; expected.len() + 3];
        let info = strided.query_into(&query, PairsOut::from_slice(&mut storage)).unwrap();
        let got: Pairs = storage[..info.count as usize].iter().map(|p| (p[0], p[1])).collect();
        assert_eq!(got, expected, "{:?}", query.kind);
    }
    // Refit from strided records: lift every vertex; the pairs stay those of a packed refit.
    let lifted: Vec<[f32; 4]> = vec4.iter().map(|v| [v[0] * 0.5, v[1], v[2] * 0.5, 0.0]).collect();
    // SAFETY: as above.
    strided.refit(unsafe { Buffer::from_raw_parts(lifted.as_ptr().cast(), 16, lifted.len(), Memory::Host) }).unwrap();
    let mut packed = packed;
    packed.refit(&lifted.iter().map(|v| [v[0], v[1], v[2]]).collect::<Vec<_>>()).unwrap();
    let query = Query::ee(Mode::CapsuleExact, r).with_flags(QueryFlags::LEAF_EXACT);
    assert_eq!(pairs_of(&strided, query), pairs_of(&packed, query));
    // Device memory on the CPU backend: refused, the scene unchanged.
    // SAFETY: never read: the CPU device rejects device memory before reading.
    let on_gpu = unsafe { Buffer::from_raw_parts(vec4.as_ptr().cast(), 16, vec4.len(), Memory::Device) };
    assert!(matches!(strided.refit(on_gpu), Err(Error::InvalidArgument(m)) if m.contains("device memory")));
    assert_eq!(pairs_of(&strided, query), pairs_of(&packed, query));
}

#[test]
fn bvh_buffer_queries_equal_slice_queries() {
    let device = Device::cpu().unwrap();
    let boxes: Vec<Aabb> = (0..40).map(|i| Aabb::new([i as f32 * 0.1; 3], [i as f32 * 0.1 + 0.15; 3])).collect();
    let bvh = Bvh::from_buffer(&device, Buffer::from_slice(&boxes)).unwrap();
    let segments: Vec<[[f32; 3]; 2]> =
        (0..30).map(|i| [[i as f32 * 0.13, 0.5, 0.5], [1.0, i as f32 * 0.1, 2.0]]).collect();
    let mut expected = Vec::new();
    let query = BvhQuery::capsules(&segments, Mode::CapsuleExact, 0.05).with_flags(QueryFlags::CANONICAL);
    bvh.query_into(&query, &mut expected).unwrap();
    assert!(!expected.is_empty());
    let starts: Vec<[f32; 3]> = segments.iter().map(|s| s[0]).collect();
    let ends: Vec<[f32; 3]> = segments.iter().map(|s| s[1]).collect();
    let split =
        BvhBufferQuery::capsules(Buffer::from_slice(&starts), Buffer::from_slice(&ends), Mode::CapsuleExact, 0.05)
            .with_flags(QueryFlags::CANONICAL);
    let mut out = vec![[0; 2]; expected.len()];
    let info = bvh.query_into(split, PairsOut::from_slice(&mut out)).unwrap();
    assert_eq!((info.count as usize, out), (expected.len(), expected.clone()));
    let mut small = vec![[0; 2]; 1];
    match bvh.query_into(split, PairsOut::from_slice(&mut small)) {
        Err(Error::Capacity { needed, .. }) => assert_eq!(needed as usize, expected.len()),
        other => panic!("{other:?}"),
    }
}

#[test]
fn capacity_reports_the_exact_count_and_writes_nothing_past_the_buffer() {
    let device = Device::cpu().unwrap();
    let mesh = crumpled_sheet(10, 3);
    let scene = Scene::new(&device, &SceneDesc::new(&mesh.vertices, &mesh.triangles)).unwrap();
    let q = Query::ee(Mode::Box, 0.05).with_flags(QueryFlags::CANONICAL);
    let mut all = Vec::new();
    let info = scene.query_into(&q, &mut all).unwrap();
    assert_eq!(info.count as usize, all.len());
    assert!(all.len() > 10);
    let mut small = vec![[-7, -7]; all.len()];
    let short = all.len() - 3;
    match scene.query_into(&q, &mut small[..short]) {
        Err(Error::Capacity { needed, message }) => {
            assert_eq!(needed as usize, all.len());
            assert!(message.contains(&all.len().to_string()), "{message}");
        }
        other => panic!("expected Capacity, got {other:?}"),
    }
    assert!(small[short..].iter().all(|p| *p == [-7, -7]), "wrote past the buffer");
    let info = scene.query_into(&q, &mut small).unwrap();
    assert_eq!((info.count as usize, small), (all.len(), all.clone()));
    // query_vec reuses and regrows its Vec.
    let mut reused = Vec::with_capacity(2);
    scene.query_into(&q, &mut reused).unwrap();
    assert_eq!(reused, all);
}

#[test]
fn digest_is_xxh64_of_the_canonical_little_endian_pairs() {
    assert_eq!(xxh64(b""), 0xEF46DB3751D8E999); // the specification's empty-input value
    let device = Device::cpu().unwrap();
    let mesh = crumpled_sheet(12, 11);
    let scene = Scene::new(&device, &SceneDesc::new(&mesh.vertices, &mesh.triangles)).unwrap();
    let mut buffer = PairBuffer::new().unwrap();
    for q in [Query::vt(Mode::Sphere, 0.04), Query::ee(Mode::CapsuleExact, 0.04), Query::ee(Mode::Box, 0.0)] {
        let q = q.with_flags(QueryFlags::DIGEST);
        let pairs = scene.query(&q, &mut buffer).unwrap().to_vec();
        let mut sorted = pairs.clone();
        sorted.sort();
        assert_eq!(pairs, sorted, "DIGEST implies canonical order");
        let bytes: Vec<u8> = pairs.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
        assert_eq!(buffer.digest(), xxh64(&bytes), "{q:?}");
        let mut out = Vec::new();
        assert_eq!(scene.query_into(&q, &mut out).unwrap().digest, Some(buffer.digest()));
        // Without DIGEST, the info carries none.
        let plain = Query { flags: QueryFlags::empty(), ..q };
        assert_eq!(scene.query_into(&plain, &mut out).unwrap().digest, None);
    }
}

#[test]
fn bad_input_gets_its_error_and_message() {
    let device = Device::cpu().unwrap();
    let mesh = crumpled_sheet(4, 1);
    let mut vertices = mesh.vertices.clone();
    vertices[5][1] = f32::INFINITY;
    let err = Scene::new(&device, &SceneDesc::new(&vertices, &mesh.triangles)).unwrap_err();
    assert!(matches!(&err, Error::NonFinite(m) if m.starts_with("vertex 5 has a non-finite coordinate")), "{err}");
    assert_eq!(err.to_string(), format!("MINKQ_ERROR_NON_FINITE: {}", err.message()));

    let mut triangles = mesh.triangles.clone();
    triangles[3][2] = 16;
    let err = Scene::new(&device, &SceneDesc::new(&mesh.vertices, &triangles)).unwrap_err();
    assert_eq!(err, Error::IndexOutOfRange("triangle 3 references vertex 16 but the scene has 16 vertices".into()));
    triangles[3][2] = -1;
    assert!(matches!(Scene::new(&device, &SceneDesc::new(&mesh.vertices, &triangles)), Err(Error::IndexOutOfRange(_))));
    let bad_edges = [[0, 99]];
    let err = Scene::new(&device, &SceneDesc::new(&mesh.vertices, &mesh.triangles).edges(&bad_edges)).unwrap_err();
    assert!(matches!(err, Error::IndexOutOfRange(_)));
    let err = Scene::new(&device, &SceneDesc::new(&mesh.vertices, &mesh.triangles).flags(SceneFlags::DROP_INCIDENT))
        .unwrap_err();
    assert!(matches!(err, Error::InvalidArgument(_)));

    let mut scene = Scene::new(&device, &SceneDesc::new(&mesh.vertices, &mesh.triangles)).unwrap();
    let mut out = PairBuffer::new().unwrap();
    assert!(matches!(scene.query(&Query::vt(Mode::Sphere, -1.0), &mut out), Err(Error::InvalidArgument(_))));
    assert!(matches!(scene.query(&Query::vt(Mode::Sphere, f32::NAN), &mut out), Err(Error::NonFinite(_))));
    assert!(matches!(scene.refit(&vertices), Err(Error::NonFinite(_))));
    // A failed refit keeps the previous positions.
    assert_eq!(pairs_of(&scene, Query::vt(Mode::Sphere, 0.3)), {
        let fresh = Scene::new(&device, &SceneDesc::new(&mesh.vertices, &mesh.triangles)).unwrap();
        pairs_of(&fresh, Query::vt(Mode::Sphere, 0.3))
    });
    assert!(matches!(Device::new("cuda:x"), Err(Error::InvalidArgument(_))));
    assert!(matches!(Device::new("cp\0u"), Err(Error::InvalidArgument(_))));
    if minkq::cuda_device_count() == 0 {
        assert!(matches!(Device::new("cuda:0"), Err(Error::Unsupported(_))));
    }
    let err = Bvh::new(&device, &[Aabb::new([0.0, f32::NAN, 0.0], [1.0; 3])]).unwrap_err();
    assert!(matches!(err, Error::NonFinite(_)));
}

#[test]
fn scenes_move_to_other_threads_and_share_their_device() {
    // Device is Send but not Sync: share it through a Mutex to build from several threads.
    let device = Arc::new(Mutex::new(Device::cpu().unwrap()));
    let handles: Vec<_> = (0..4u64)
        .map(|seed| {
            let device = Arc::clone(&device);
            thread::spawn(move || {
                let mesh = crumpled_sheet(10, seed);
                let scene = {
                    let device = device.lock().unwrap();
                    Scene::new(&device, &SceneDesc::new(&mesh.vertices, &mesh.triangles)).unwrap()
                };
                // Queries run concurrently with other threads' scenes on the same device.
                let q = Query::ee(Mode::CapsuleExact, 0.03).with_flags(QueryFlags::DIGEST);
                let mut out = Vec::new();
                (scene.query_into(&q, &mut out).unwrap(), scene)
            })
        })
        .collect();
    let results: Vec<_> = handles.into_iter().map(|h| h.join().unwrap()).collect();
    drop(device); // the scenes keep the device alive
    for (seed, (info, scene)) in results.into_iter().enumerate() {
        // Moved back to this thread, still usable; the same answer as a fresh query.
        let moved = thread::spawn(move || {
            let q = Query::ee(Mode::CapsuleExact, 0.03).with_flags(QueryFlags::DIGEST);
            scene.query_into(&q, &mut Vec::new()).unwrap()
        })
        .join()
        .unwrap();
        assert_eq!(info, moved, "seed {seed}");
    }
}
