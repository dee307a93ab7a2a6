//! Refit and rebuild through the safe crate, against the oracle (common::oracle): a refit
//! after moving vertices equals a fresh build; a rebuild gives the pairs of a refit (scenes
//! and BVHs) and resets the tree growth, which is scale-free; a failed rebuild names rebuild
//! and keeps the positions and trees.
mod common;
use common::oracle::{assert_same_pairs, check_scene, pairs_of, Mesh};
use common::sheets::{crumpled_sheet, flat_grid, rolled_and_twisted, scaled};
use common::Rng;

use minkq::{Aabb, Buffer, Bvh, BvhQuery, Device, Error, Memory, Mode, Query, QueryFlags, QueryKind, Scene, SceneDesc};

#[test]
fn refit_after_moving_vertices_equals_a_fresh_build() {
    let device = Device::cpu().unwrap();
    let mut mesh = crumpled_sheet(12, 7);
    let mut scene = Scene::new(&device, &SceneDesc::new(&mesh.vertices, &mesh.triangles)).unwrap();
    let mut rng = Rng(99);
    for _step in 0..3 {
        for v in &mut mesh.vertices {
            // Squash towards the axis: contacts change from step to step.
            v[0] *= 0.9;
            v[2] = v[2] * 0.9 + 0.01 * (rng.uniform() as f32 - 0.5);
        }
        scene.refit(&mesh.vertices).unwrap();
        check_scene(&scene, &mesh, 0.03);
        let fresh = Scene::new(&device, &SceneDesc::new(&mesh.vertices, &mesh.triangles)).unwrap();
        for kind in [QueryKind::Vt, QueryKind::Ee] {
            for mode in Mode::ALL {
                if kind == QueryKind::Ee && mode == Mode::Sphere {
                    continue;
                }
                for flags in [QueryFlags::empty(), QueryFlags::LEAF_EXACT] {
                    let q = Query::new(kind, mode, 0.03).with_flags(flags);
                    assert_eq!(pairs_of(&scene, q), pairs_of(&fresh, q), "{kind} {mode} {flags:?} after refit");
                }
            }
        }
    }
}

#[test]
fn rebuild_gives_the_pairs_of_refit_and_resets_the_tree_growth() {
    let device = Device::cpu().unwrap();
    let flat = flat_grid(16);
    let r = 0.04;
    let desc = SceneDesc::new(&flat.vertices, &flat.triangles);
    let mut refitted = Scene::new(&device, &desc).unwrap();
    let mut rebuilt = Scene::new(&device, &desc).unwrap();
    assert_eq!(refitted.tree_growth().unwrap(), 1.0, "right after create");
    // Built flat, moved to a rolled sheet whose layers come within r of each other, then
    // twisted further: the refitted trees keep the flat sheet's grouping.
    let mut growths = Vec::new();
    for twist in [0.0, 2.0] {
        let moved = Mesh { vertices: rolled_and_twisted(&flat.vertices, twist), triangles: flat.triangles.clone() };
        refitted.refit(&moved.vertices).unwrap();
        rebuilt.rebuild(&moved.vertices).unwrap();
        assert_eq!(rebuilt.tree_growth().unwrap(), 1.0, "right after rebuild (twist {twist})");
        let growth = refitted.tree_growth().unwrap();
        eprintln!("twist {twist}: tree growth after refit {growth}");
        growths.push(growth);
        assert!(growth > 1.2, "rolling a flat sheet up should degrade the refitted trees: {growth}");
        check_scene(&rebuilt, &moved, r);
        assert_same_pairs(&refitted, &rebuilt, r, &format!("twist {twist}"));
        let fresh = Scene::new(&device, &SceneDesc::new(&moved.vertices, &moved.triangles)).unwrap();
        assert_same_pairs(&rebuilt, &fresh, r, &format!("twist {twist}, rebuilt against created"));
        assert_eq!(fresh.tree_growth().unwrap(), 1.0);
    }
    // Scale-free: the same meshes scaled by 1024 (exact in floating point) grow alike.
    let mut large = Scene::new(&device, &SceneDesc::new(&scaled(&flat.vertices, 1024.0), &flat.triangles)).unwrap();
    for (twist, growth) in [0.0, 2.0].into_iter().zip(growths) {
        large.refit(&scaled(&rolled_and_twisted(&flat.vertices, twist), 1024.0)).unwrap();
        let large_growth = large.tree_growth().unwrap();
        assert!((large_growth - growth).abs() <= 1e-12 * growth, "twist {twist}: {large_growth} vs {growth}");
    }
    // A refit of the rebuilt scene back to the flat sheet: growth measured against the
    // rebuilt trees now, and the pairs those of the refitted scene.
    rebuilt.refit(&flat.vertices).unwrap();
    refitted.refit(&flat.vertices).unwrap();
    assert_eq!(refitted.tree_growth().unwrap(), 1.0, "back to the positions of its build");
    assert!(rebuilt.tree_growth().unwrap() != 1.0);
    let q = Query::vt(Mode::Sphere, r).with_flags(QueryFlags::LEAF_EXACT);
    assert_eq!(pairs_of(&rebuilt, q), pairs_of(&refitted, q));
}

#[test]
fn bvh_rebuild_gives_the_pairs_of_refit_and_resets_the_tree_growth() {
    let device = Device::cpu().unwrap();
    let flat = flat_grid(16);
    let boxes_of = |vertices: &[[f32; 3]]| -> Vec<Aabb> {
        flat.triangles
            .iter()
            .map(|t| {
                let p = t.map(|i| vertices[i as usize]);
                let lo = [0, 1, 2].map(|k| p[0][k].min(p[1][k]).min(p[2][k]));
                let hi = [0, 1, 2].map(|k| p[0][k].max(p[1][k]).max(p[2][k]));
                Aabb::new(lo, hi)
            })
            .collect()
    };
    let mut refitted = Bvh::new(&device, &boxes_of(&flat.vertices)).unwrap();
    let mut rebuilt = Bvh::new(&device, &boxes_of(&flat.vertices)).unwrap();
    assert_eq!(refitted.tree_growth().unwrap(), 1.0);
    let moved = rolled_and_twisted(&flat.vertices, 2.0);
    let boxes = boxes_of(&moved);
    refitted.refit(&boxes).unwrap();
    rebuilt.rebuild(&boxes).unwrap();
    assert_eq!(rebuilt.tree_growth().unwrap(), 1.0);
    let growth = refitted.tree_growth().unwrap();
    assert!(growth > 1.2, "{growth}");
    let mut large = Bvh::new(&device, &boxes_of(&scaled(&flat.vertices, 1024.0))).unwrap();
    large.refit(&boxes_of(&scaled(&moved, 1024.0))).unwrap();
    let large_growth = large.tree_growth().unwrap();
    assert!((large_growth - growth).abs() <= 1e-12 * growth, "{large_growth} vs {growth}");

    let segments: Vec<[[f32; 3]; 2]> = moved.iter().step_by(7).map(|&p| [p, [p[0] + 0.05, p[1], p[2]]]).collect();
    let queries = [
        BvhQuery::spheres(&moved, Mode::Sphere, 0.03),
        BvhQuery::spheres(&moved, Mode::Box, 0.03),
        BvhQuery::capsules(&segments, Mode::CapsuleExact, 0.03),
        BvhQuery::capsules(&segments, Mode::CapsuleRay, 0.03),
        BvhQuery::boxes(&boxes),
    ];
    for query in queries {
        let query = query.with_flags(QueryFlags::DIGEST);
        let (mut a, mut b) = (Vec::new(), Vec::new());
        let info_a = refitted.query_into(&query, &mut a).unwrap();
        let info_b = rebuilt.query_into(&query, &mut b).unwrap();
        assert!(!a.is_empty());
        assert_eq!((a, info_a.digest), (b, info_b.digest), "{:?} {:?}", query.mode, query.shapes);
    }
}

#[test]
fn a_failed_rebuild_names_rebuild_and_keeps_the_positions_and_trees() {
    let device = Device::cpu().unwrap();
    let flat = flat_grid(6);
    let mut scene = Scene::new(&device, &SceneDesc::new(&flat.vertices, &flat.triangles)).unwrap();
    let moved = rolled_and_twisted(&flat.vertices, 1.0);
    scene.refit(&moved).unwrap();
    let growth = scene.tree_growth().unwrap();
    let q = Query::ee(Mode::CapsuleExact, 0.1).with_flags(QueryFlags::DIGEST);
    let before = pairs_of(&scene, q);

    let err = scene.rebuild(&moved[1..]).unwrap_err();
    assert_eq!(err, Error::InvalidArgument("rebuild with 35 vertices but the scene has 36".into()));
    let err = scene.refit(&moved[1..]).unwrap_err();
    assert_eq!(err, Error::InvalidArgument("refit with 35 vertices but the scene has 36".into()));
    let mut bad = flat.vertices.clone();
    bad[7][2] = f32::NAN;
    let err = scene.rebuild(&bad).unwrap_err();
    assert!(matches!(&err, Error::NonFinite(m) if m.starts_with("vertex 7 has a non-finite coordinate")), "{err}");
    // SAFETY: never read: the CPU device rejects device memory before reading.
    let on_gpu = unsafe { Buffer::from_raw_parts(flat.vertices.as_ptr().cast(), 12, 36, Memory::Device) };
    assert!(matches!(scene.rebuild(on_gpu), Err(Error::InvalidArgument(m)) if m.contains("device memory")));
    assert_eq!(scene.tree_growth().unwrap(), growth, "a failed rebuild keeps the trees");
    assert_eq!(pairs_of(&scene, q), before, "a failed rebuild keeps the positions");

    let boxes = [Aabb::new([0.0; 3], [1.0; 3]), Aabb::new([2.0; 3], [3.0; 3])];
    let mut bvh = Bvh::new(&device, &boxes).unwrap();
    let err = bvh.rebuild(&boxes[..1]).unwrap_err();
    assert_eq!(err, Error::InvalidArgument("rebuild with 1 boxes but the bvh has 2".into()));
    let err = bvh.rebuild(&[boxes[0], Aabb::new([0.0, f32::INFINITY, 0.0], [1.0; 3])]).unwrap_err();
    assert!(matches!(&err, Error::NonFinite(m) if m.starts_with("box 1 ")), "{err}");
    let err = bvh.rebuild(&[boxes[0], Aabb::new([1.0; 3], [0.0; 3])]).unwrap_err();
    assert_eq!(err, Error::InvalidArgument("box 1 has lo > hi".into()));
    let mut out = Vec::new();
    bvh.query_into(&BvhQuery::spheres(&[[2.5; 3]], Mode::Sphere, 0.0), &mut out).unwrap();
    assert_eq!(out, vec![[0, 1]], "a failed rebuild keeps the boxes");
}
