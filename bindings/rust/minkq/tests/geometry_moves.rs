//! Scenes of many geometries (`Scene::from_geometries`) as they move and fail, through the safe
//! crate: one geometry refitted or rebuilt gives a fresh scene's pairs while a static body stays
//! (and whole-scene refits take the moving geometries' vertices only); a swept cloth over a
//! static body gives the concatenated mesh's swept pairs; static geometries refuse to move;
//! float64 geometries keep the double truth beside float ones; bad input comes back with the
//! library's messages (or, for what the C API cannot see, this crate's); and global ids map
//! back to (geometry, local id), empty geometries included.
mod common;
use common::draped::{
    all_kinds, every_kind_flags, located, pairs_of, queries, query_kind, without_body_own, Draped, ALL_KINDS,
};

use minkq::{
    Buffer, Device, Element, Error, GeometryDesc, GeometryFlags, Kinds, Memory, Mode, PairBuffer, Query, QueryFlags,
    QueryKind, Reserve, Scene, Stream,
};

/// The vertices moved by `d`.
fn moved(vertices: &[[f32; 3]], d: [f32; 3]) -> Vec<[f32; 3]> {
    vertices.iter().map(|p| [p[0] + d[0], p[1] + d[1], p[2] + d[2]]).collect()
}

/// Every kind's queries give the same pairs on both scenes (some of them pairs).
fn assert_same_pairs(a: &Scene, b: &Scene, r: f32, what: &str) {
    for kind in ALL_KINDS.map(query_kind) {
        let mut found = 0;
        for query in queries(kind, r) {
            let got = pairs_of(a, &query);
            assert_eq!(got, pairs_of(b, &query), "{what}: {kind} {query:?}");
            found += got.len();
        }
        assert!(found > 0, "{what}: {kind} should find pairs here");
    }
}

#[test]
fn moving_one_geometry_gives_a_fresh_scene_pairs() {
    let draped = Draped::new(12, 16);
    let device = Device::cpu().unwrap();
    let mut scene = draped.scene();
    let r = 0.03;
    let lowered = moved(&draped.cloth, [0.05, -0.02, -0.03]);
    let fresh = Scene::from_geometries(
        &device,
        &[GeometryDesc::mesh(&lowered, &draped.cloth_triangles).kinds(all_kinds()), draped.body_desc()],
    )
    .unwrap();
    scene.refit_geometry(0, &lowered).unwrap();
    assert_same_pairs(&scene, &fresh, r, "refit_geometry");
    scene.rebuild_geometry(0, &draped.cloth).unwrap();
    assert_eq!(scene.tree_growth().unwrap(), 1.0);
    assert_same_pairs(&scene, &draped.scene(), r, "rebuild_geometry back");
    // A whole-scene refit moves the moving geometries: the cloth's vertices alone.
    scene.refit(&lowered).unwrap();
    assert_same_pairs(&scene, &fresh, r, "whole-scene refit");
    scene.rebuild(Buffer::from_slice(&draped.cloth)).unwrap();
    assert_same_pairs(&scene, &draped.scene(), r, "whole-scene rebuild");
    let all: Vec<[f32; 3]> = draped.cloth.iter().chain(&draped.body).copied().collect();
    let err = scene.refit(&all).unwrap_err();
    let expected =
        format!("refit with {} vertices but the scene's moving geometries have {}", all.len(), draped.cloth.len());
    assert_eq!(err, Error::InvalidArgument(expected));
}

#[test]
fn a_swept_cloth_gives_the_concatenated_mesh_swept_pairs() {
    let draped = Draped::new(10, 12);
    let mut scene = draped.scene();
    // From well above the body to through it: apart at the start, far past at the end.
    let (x0, x1) = (moved(&draped.cloth, [0.0, 0.0, 0.5]), moved(&draped.cloth, [0.0, 0.0, -0.5]));
    let (mut whole, _, _) = draped.concatenated(every_kind_flags());
    let with_body = |cloth: &[[f32; 3]]| cloth.iter().chain(&draped.body).copied().collect::<Vec<_>>();
    scene.refit_geometry_swept(0, &x0, &x1).unwrap();
    whole.refit_swept(&with_body(&x0), &with_body(&x1)).unwrap();
    assert!(scene.is_swept() && whole.is_swept());
    let r = 0.01;
    for kind in ALL_KINDS.map(query_kind) {
        for mode in Mode::ALL {
            if kind == QueryKind::Ee && mode != Mode::Box {
                continue; // swept EE runs box mode only
            }
            let query = Query::new(kind, mode, r);
            let got = pairs_of(&scene, &query);
            assert_eq!(got, without_body_own(&scene, kind, pairs_of(&whole, &query)), "{kind} {mode}");
            let cross = located(&scene, kind, &got).iter().filter(|[a, b]| a.0 != b.0).count();
            assert!(cross > 5, "{kind} {mode}: the swept cloth must cross the body, {cross} cross pairs");
        }
    }
    let mut buffer = PairBuffer::new().unwrap();
    let err = scene.query(&Query::vt(Mode::Box, r).with_flags(QueryFlags::LEAF_EXACT), &mut buffer).unwrap_err();
    assert!(matches!(err, Error::Unsupported(_)));
    // At rest at either end the cloth is far from the body.
    for end in [&x0, &x1] {
        scene.rebuild_geometry(0, end).unwrap();
        assert!(!scene.is_swept());
        let pairs = pairs_of(&scene, &Query::vt(Mode::Box, r));
        assert!(located(&scene, QueryKind::Vt, &pairs).iter().all(|[a, b]| a.0 == b.0));
    }
    scene.rebuild_geometry_swept(0, &x0, &x1).unwrap();
    let vt = Query::vt(Mode::CapsuleExact, r);
    assert_eq!(pairs_of(&scene, &vt), without_body_own(&scene, QueryKind::Vt, pairs_of(&whole, &vt)));
}

#[test]
fn static_geometries_refuse_to_move() {
    let draped = Draped::new(8, 8);
    let mut scene = draped.scene();
    let query = Query::vt(Mode::Box, 0.03);
    let before = pairs_of(&scene, &query);
    let expected =
        Error::InvalidArgument("geometry 1 is static (MINKQ_GEOMETRY_STATIC): it is built once and never moves".into());
    let body = moved(&draped.body, [0.0, 0.0, 0.05]);
    assert_eq!(scene.refit_geometry(1, &body), Err(expected.clone()));
    assert_eq!(scene.rebuild_geometry(1, &body), Err(expected.clone()));
    assert_eq!(scene.refit_geometry_swept(1, &draped.body, &body), Err(expected.clone()));
    assert_eq!(scene.rebuild_geometry_swept(1, &draped.body, &body), Err(expected.clone()));
    // Even doubles, which the geometry could not read either: the library's message comes first.
    let doubles: Vec<[f64; 3]> = body.iter().map(|p| p.map(f64::from)).collect();
    assert_eq!(scene.refit_geometry(1, &doubles), Err(expected));
    assert_eq!(pairs_of(&scene, &query), before, "nothing moved");
    assert!(!scene.is_swept());
}

#[test]
fn float64_geometries_keep_the_double_truth_beside_float_ones() {
    let device = Device::cpu().unwrap();
    // A triangle in the plane x = 20000.0009 and a vertex 0.95e-3 in front of it, where floats
    // lie 2^-9 apart: rounded to float they are more than r = 1e-3 apart.
    let (plane, point) = (20000.0009f64, 20000.00185f64);
    let triangle = [[plane, -1.0, -1.0], [plane, 2.0, -1.0], [plane, -1.0, 2.0]];
    let (near, far) = ([[point, 0.0, 0.0]], [[point + 1.0, 0.0, 0.0]]);
    let r = 1e-3f32;
    let query = Query::vt(Mode::Box, r).with_flags(QueryFlags::LEAF_EXACT);
    let round = |v: &[[f64; 3]]| v.iter().map(|p| p.map(|c| c as f32)).collect::<Vec<_>>();
    let vt = || GeometryDesc::mesh(&triangle, &[[0, 1, 2]]).kinds(Kinds::VT);
    let mut scene = Scene::from_geometries(&device, &[vt(), GeometryDesc::mesh(&far, &[]).kinds(Kinds::VT)]).unwrap();
    assert!(scene.is_float64());
    assert!(pairs_of(&scene, &query).is_empty());
    scene.refit_geometry(1, &near).unwrap();
    assert_eq!(pairs_of(&scene, &query).into_iter().collect::<Vec<_>>(), [[3, 0]]);
    // Whole-scene refits of an all-double scene take doubles.
    let all: Vec<[f64; 3]> = triangle.iter().chain(&far).copied().collect();
    scene.refit(&all).unwrap();
    assert!(pairs_of(&scene, &query).is_empty());
    let (tri32, near32) = (round(&triangle), round(&near));
    let floats = Scene::from_geometries(
        &device,
        &[GeometryDesc::mesh(&tri32, &[[0, 1, 2]]).kinds(Kinds::VT), GeometryDesc::mesh(&near32, &[]).kinds(Kinds::VT)],
    )
    .unwrap();
    assert!(pairs_of(&floats, &query).is_empty(), "rounded to float, the pair is lost");

    // Mixed precisions: each geometry takes its own, a whole-scene move none.
    let mut mixed =
        Scene::from_geometries(&device, &[vt(), GeometryDesc::mesh(&near32, &[]).kinds(Kinds::VT)]).unwrap();
    assert!(!mixed.is_float64());
    mixed.refit_geometry(0, &triangle).unwrap();
    mixed.refit_geometry(1, &near32).unwrap();
    let err = mixed.refit_geometry(1, &near).unwrap_err();
    let message = "geometry 1: refit: [f64; 3] vertices, but a geometry without GeometryFlags::FLOAT64 reads [f32; 3]";
    assert_eq!(err, Error::InvalidArgument(message.into()));
    let err = mixed.refit_geometry_swept(0, Buffer::from_slice(&triangle), Buffer::from_slice(&tri32)).unwrap_err();
    let message =
        "geometry 0: refit_swept: x1: [f32; 3] vertices, but a geometry with GeometryFlags::FLOAT64 reads [f64; 3]";
    assert_eq!(err, Error::InvalidArgument(message.into()));
    // The library's message, whichever precision the slice has.
    for err in [mixed.refit(&round(&all)).unwrap_err(), mixed.rebuild(&all).unwrap_err()] {
        assert!(matches!(&err, Error::InvalidArgument(m) if m.contains("mix float32 and float64")), "{err:?}");
    }

    // A raw buffer of doubles needs the flag; a float slice with it is refused.
    let padded: Vec<[f64; 4]> = triangle.iter().map(|p| [p[0], p[1], p[2], 7.0]).collect();
    // SAFETY: three 32-byte records starting with 3 doubles, borrowed from `padded`.
    let raw = unsafe { Buffer::from_raw_parts(padded.as_ptr().cast(), 32, 3, Memory::Host) };
    let from_raw = GeometryDesc::from_buffers(raw, Buffer::from_slice(&[[0, 1, 2]]))
        .kinds(Kinds::VT)
        .flags(GeometryFlags::FLOAT64); // no self pairs: (vertex, its own triangle) would be one
    let scene = Scene::from_geometries(&device, &[from_raw, GeometryDesc::mesh(&near, &[]).kinds(Kinds::VT)]).unwrap();
    assert_eq!(pairs_of(&scene, &query).into_iter().collect::<Vec<_>>(), [[3, 0]]);
    let wrong = GeometryDesc::mesh(&tri32, &[[0, 1, 2]]).flags(GeometryFlags::FLOAT64);
    let err = Scene::from_geometries(&device, &[vt(), wrong]).unwrap_err();
    let message = "geometry 1: create: [f32; 3] vertices, but a geometry with GeometryFlags::FLOAT64 reads [f64; 3]";
    assert_eq!(err, Error::InvalidArgument(message.into()));
}

#[test]
fn bad_input_comes_back_with_the_library_messages() {
    let device = Device::cpu().unwrap();
    let tri = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let ok = GeometryDesc::mesh(&tri, &[[0, 1, 2]]);
    let create = |geometries: &[GeometryDesc<'_>]| Scene::from_geometries(&device, geometries).unwrap_err();
    assert_eq!(create(&[]), Error::InvalidArgument("count is 0: a scene holds at least one geometry".into()));
    assert_eq!(
        create(&[ok, GeometryDesc::mesh(&tri, &[[0, 1, 7]])]),
        Error::IndexOutOfRange("geometry 1: triangle 0 references vertex 7 but the geometry has 3 vertices".into())
    );
    let kinds =
        "geometry 0: kinds is 0: set one or more of MINKQ_SCENE_VT, MINKQ_SCENE_EE, MINKQ_SCENE_VV and MINKQ_SCENE_EV";
    assert_eq!(create(&[ok.kinds(Kinds::empty())]), Error::InvalidArgument(kinds.into()));
    assert_eq!(
        create(&[ok.thickness(&[0.1, 0.2])]),
        Error::InvalidArgument(
            "geometry 0: thickness.count 2 is not the vertex count 3 (one thickness per vertex, or none)".into()
        )
    );
    assert_eq!(
        create(&[ok, ok.thickness(&[0.1, -0.5, 0.0])]),
        Error::InvalidArgument("geometry 1: thickness of vertex 1 is -0.5, negative".into())
    );
    assert_eq!(
        create(&[ok.thickness(&[0.1, 0.0, f32::INFINITY])]),
        Error::NonFinite("geometry 0: thickness of vertex 2 is inf, not finite".into())
    );
    let nan = [[0.0f32, 0.0, 0.0], [1.0, f32::NAN, 0.0], [0.0, 1.0, 0.0]];
    assert!(
        matches!(create(&[ok, GeometryDesc::mesh(&nan, &[])]), Error::NonFinite(m) if m.starts_with("geometry 1: vertex 1 "))
    );

    let mut scene = Scene::from_geometries(&device, &[ok, ok.kinds(Kinds::EE)]).unwrap();
    let out_of_range = Error::InvalidArgument("geometry 2 is out of range: the scene has 2 geometries".into());
    assert_eq!(scene.geometry_range(2, Element::Vertex), Err(out_of_range.clone()));
    assert_eq!(scene.refit_geometry(2, &tri), Err(out_of_range.clone()));
    assert_eq!(scene.rebuild_geometry_swept(2, &tri, &tri), Err(out_of_range));
    let err = scene.query(&Query::vv(Mode::Box, 0.1), &mut PairBuffer::new().unwrap()).unwrap_err();
    assert_eq!(err, Error::InvalidArgument("VV query on a scene created without MINKQ_SCENE_VV".into()));
    // Stream-ordered calls serve scenes of many geometries too: a whole-scene refit takes
    // every moving geometry's vertices, one after another.
    scene.reserve(Reserve::REFIT, 0).unwrap();
    let err = scene.refit_async(Buffer::from_slice(&tri), Stream::default()).unwrap_err();
    assert!(
        matches!(&err, Error::InvalidArgument(m) if m.contains("the scene's moving geometries have 6")),
        "{err:?}"
    );
}

#[test]
fn global_ids_map_back_to_geometries() {
    let device = Device::cpu().unwrap();
    let draped = Draped::new(5, 6);
    let particles = [[0.5f32, 0.5, 0.5], [0.6, 0.5, 0.5]];
    let rod = [[0.0f32, 0.0, 1.0], [1.0, 0.0, 1.0], [2.0, 0.0, 1.0]];
    let geometries = [
        draped.cloth_desc(),
        GeometryDesc::codim(&particles, &[]).kinds(Kinds::VV), // no triangles, no edges
        GeometryDesc::codim(&rod, &[[0, 1], [1, 2]]),
        draped.body_desc(),
    ];
    let scene = Scene::from_geometries(&device, &geometries).unwrap();
    assert_eq!(scene.geometry_count(), 4);
    let counts = [
        [draped.cloth.len(), draped.cloth_triangles.len(), scene.geometry_range(0, Element::Edge).unwrap().len()],
        [2, 0, 0],
        [3, 0, 2],
        [draped.body.len(), draped.body_triangles.len(), scene.geometry_range(3, Element::Edge).unwrap().len()],
    ];
    for (e, element) in [Element::Vertex, Element::Triangle, Element::Edge].into_iter().enumerate() {
        let mut next = 0;
        for (g, count) in counts.iter().enumerate() {
            let range = scene.geometry_range(g as u32, element).unwrap();
            assert_eq!(range, next..next + count[e], "geometry {g} {element:?}");
            for id in range.clone() {
                assert_eq!(scene.locate(element, id as i32), Some((g as u32, id - next)));
            }
            next = range.end;
        }
        assert_eq!(scene.locate(element, next as i32), None);
        assert_eq!(scene.locate(element, -1), None);
    }
    // The cloth's own edges are derived as a one-mesh scene derives them: 3 per cell and one
    // per border cell edge.
    assert_eq!(counts[0][2], 3 * 4 * 4 + 2 * 4);
    assert_eq!(scene.edge_count(), counts.iter().map(|c| c[2]).sum::<usize>());
    // A one-mesh scene is one geometry.
    let one = draped.concatenated(every_kind_flags()).0;
    assert_eq!(one.geometry_count(), 1);
    assert_eq!(one.geometry_range(0, Element::Triangle).unwrap(), 0..one.triangle_count());
    assert_eq!(one.locate_pair(QueryKind::Vt, [3, 1]), Some([(0, 3), (0, 1)]));
    assert_eq!(one.locate_pair(QueryKind::Vt, [3, one.triangle_count() as i32]), None);
    // Every pair of the mixed scene maps to geometries that take part in its kind.
    for kind in [QueryKind::Vv, QueryKind::Ee] {
        let pairs = pairs_of(&scene, &Query::new(kind, Mode::Box, 0.6));
        assert!(!pairs.is_empty());
        for [a, b] in located(&scene, kind, &pairs) {
            let takes = |g: u32| geometries[g as usize].kinds.contains(Kinds::from(kind));
            assert!(takes(a.0) && takes(b.0), "{kind}: {a:?} {b:?}");
        }
    }
}
