//! The names the generic calls replaced (issue 54) still work for one release: each
//! deprecated forward gives the scene, BVH and pairs its replacement gives.
#![allow(deprecated)]
mod common;
use common::sheets::crumpled_sheet;

use minkq::{
    Aabb, Buffer, Bvh, BvhBufferQuery, BvhQuery, Device, Error, GeometryDesc, Mode, PairsOut, Query, QueryFlags, Scene,
    SceneDesc,
};

fn canonical(scene: &Scene) -> Vec<[i32; 2]> {
    let mut pairs = Vec::new();
    scene.query_into(&Query::ee(Mode::Box, 0.05).with_flags(QueryFlags::CANONICAL), &mut pairs).unwrap();
    pairs
}

/// Scene `a` moved by the old name and `b` by the new one hold the same pairs, which moved.
fn assert_same_moves(a: &Scene, b: &Scene, before: &[[i32; 2]], what: &str) {
    let moved = canonical(b);
    assert_ne!(moved, before, "{what}: the vertices did not move the pairs");
    assert_eq!(canonical(a), moved, "{what}");
    assert_eq!(a.is_swept(), b.is_swept(), "{what}");
}

#[test]
fn old_refit_and_rebuild_names_forward_to_the_generic_calls() {
    let device = Device::cpu().unwrap();
    let mesh = crumpled_sheet(8, 5);
    let moved: Vec<[f32; 3]> = mesh.vertices.iter().map(|v| [v[0] * 0.7, v[1], v[2] * 1.3]).collect();
    let doubles: Vec<[f64; 3]> = mesh.vertices.iter().map(|v| v.map(f64::from)).collect();
    let moved64: Vec<[f64; 3]> = moved.iter().map(|v| v.map(f64::from)).collect();
    let float = || Scene::new(&device, &SceneDesc::new(&mesh.vertices, &mesh.triangles)).unwrap();
    let double = || Scene::new(&device, &SceneDesc::new_f64(&doubles, &mesh.triangles)).unwrap();
    let before = canonical(&float());
    let (x0, x1) = (Buffer::from_slice(&mesh.vertices), Buffer::from_slice(&moved));
    let (d0, d1) = (&doubles[..], &moved64[..]);

    type Move<'m> = (&'m str, fn() -> bool, Box<dyn Fn(&mut Scene) -> minkq::Result<()> + 'm>);
    let cases: Vec<(Move<'_>, Move<'_>)> = vec![
        (("refit_buffer", || false, Box::new(|s| s.refit_buffer(x1))), ("refit", || false, Box::new(|s| s.refit(x1)))),
        (("refit_f64", || true, Box::new(|s| s.refit_f64(d1))), ("refit", || true, Box::new(|s| s.refit(d1)))),
        (
            ("rebuild_buffer", || false, Box::new(|s| s.rebuild_buffer(x1))),
            ("rebuild", || false, Box::new(|s| s.rebuild(x1))),
        ),
        (("rebuild_f64", || true, Box::new(|s| s.rebuild_f64(d1))), ("rebuild", || true, Box::new(|s| s.rebuild(d1)))),
        (
            ("refit_swept_buffers", || false, Box::new(|s| s.refit_swept_buffers(x0, x1))),
            ("refit_swept", || false, Box::new(|s| s.refit_swept(x0, x1))),
        ),
        (
            ("refit_swept_f64", || true, Box::new(|s| s.refit_swept_f64(d0, d1))),
            ("refit_swept", || true, Box::new(|s| s.refit_swept(d0, d1))),
        ),
        (
            ("rebuild_swept_buffers", || false, Box::new(|s| s.rebuild_swept_buffers(x0, x1))),
            ("rebuild_swept", || false, Box::new(|s| s.rebuild_swept(x0, x1))),
        ),
        (
            ("rebuild_swept_f64", || true, Box::new(|s| s.rebuild_swept_f64(d0, d1))),
            ("rebuild_swept", || true, Box::new(|s| s.rebuild_swept(d0, d1))),
        ),
        (
            ("refit_geometry_buffer", || false, Box::new(|s| s.refit_geometry_buffer(0, x1))),
            ("refit_geometry", || false, Box::new(|s| s.refit_geometry(0, x1))),
        ),
        (
            ("rebuild_geometry_buffer", || false, Box::new(|s| s.rebuild_geometry_buffer(0, x1))),
            ("rebuild_geometry", || false, Box::new(|s| s.rebuild_geometry(0, x1))),
        ),
        (
            ("refit_geometry_swept_buffers", || false, Box::new(|s| s.refit_geometry_swept_buffers(0, x0, x1))),
            ("refit_geometry_swept", || false, Box::new(|s| s.refit_geometry_swept(0, x0, x1))),
        ),
        (
            ("rebuild_geometry_swept_buffers", || false, Box::new(|s| s.rebuild_geometry_swept_buffers(0, x0, x1))),
            ("rebuild_geometry_swept", || false, Box::new(|s| s.rebuild_geometry_swept(0, x0, x1))),
        ),
    ];
    for ((old, old_f64, old_move), (new, new_f64, new_move)) in &cases {
        assert_eq!(old_f64(), new_f64());
        let (mut a, mut b) = if old_f64() { (double(), double()) } else { (float(), float()) };
        old_move(&mut a).unwrap();
        new_move(&mut b).unwrap();
        assert_same_moves(&a, &b, &before, &format!("{old} -> {new}"));
        // The old name refuses vertices of the other precision as the new one does.
        let mut other = if old_f64() { float() } else { double() };
        let (err_old, err_new) = (old_move(&mut other).unwrap_err(), new_move(&mut other).unwrap_err());
        assert_eq!(err_old, err_new, "{old}");
        assert!(matches!(err_old, Error::InvalidArgument(_)), "{old}: {err_old:?}");
    }
    // Geometry moves also reach scenes of geometries.
    let mut geometries =
        Scene::from_geometries(&device, &[GeometryDesc::mesh(&mesh.vertices, &mesh.triangles)]).unwrap();
    geometries.refit_geometry_buffer(0, x1).unwrap();
    let mut plain = float();
    plain.refit(&moved).unwrap();
    assert_eq!(canonical(&geometries), canonical(&plain));
}

#[test]
fn old_query_names_forward_to_query_into() {
    let device = Device::cpu().unwrap();
    let mesh = crumpled_sheet(8, 5);
    let scene = Scene::new(&device, &SceneDesc::new(&mesh.vertices, &mesh.triangles)).unwrap();
    let query = Query::ee(Mode::Box, 0.05).with_flags(QueryFlags::CANONICAL | QueryFlags::DIGEST);
    let want = canonical(&scene);
    assert!(want.len() > 10);
    let mut grown = Vec::new();
    let info = scene.query_vec(&query, &mut grown).unwrap();
    assert_eq!((info.count as usize, &grown), (want.len(), &want));
    let mut fixed = vec![[0; 2]; want.len()];
    assert_eq!(scene.query_to(&query, PairsOut::from_slice(&mut fixed)).unwrap(), info);
    assert_eq!(fixed, want);
    let short = scene.query_to(&query, PairsOut::from_slice(&mut fixed[1..]));
    assert!(matches!(short, Err(Error::Capacity { needed, .. }) if needed as usize == want.len()));

    let boxes: Vec<Aabb> = (0..8).map(|i| Aabb::new([i as f32; 3], [i as f32 + 1.5; 3])).collect();
    let mut bvh = Bvh::new(&device, &boxes).unwrap();
    let centres = [[2.0f32; 3], [6.2; 3]];
    let spheres = BvhQuery::spheres(&centres, Mode::Sphere, 0.1).with_flags(QueryFlags::CANONICAL);
    let mut new = Vec::new();
    bvh.query_into(&spheres, &mut new).unwrap();
    assert_eq!(new, [[0, 1], [0, 2], [1, 5], [1, 6]]);
    let mut old = Vec::new();
    bvh.query_vec(&spheres, &mut old).unwrap();
    assert_eq!(old, new);
    let mut out = [[0; 2]; 4];
    bvh.query_to(&BvhBufferQuery::from(&spheres), PairsOut::from_slice(&mut out)).unwrap();
    assert_eq!(out.to_vec(), new);
    let shifted: Vec<Aabb> = boxes.iter().map(|b| Aabb::new(b.lo.map(|x| x + 4.0), b.hi.map(|x| x + 4.0))).collect();
    bvh.refit_buffer(Buffer::from_slice(&shifted)).unwrap();
    bvh.query_into(&spheres, &mut old).unwrap();
    assert_eq!(old, [[1, 1], [1, 2]]);
    bvh.rebuild_buffer(Buffer::from_slice(&boxes)).unwrap();
    bvh.query_into(&spheres, &mut old).unwrap();
    assert_eq!(old, new);
}
