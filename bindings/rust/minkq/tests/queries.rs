//! The safe crate's queries against a brute-force double-precision oracle (common::oracle):
//! zero false negatives and the containment chain of every mode, VT and EE; scenes built with
//! explicit edges and scene flags; BVH sphere, capsule and box queries against brute force.
mod common;
use common::oracle::{assert_subset, check_scene, pairs_of, Pairs};
use common::sheets::crumpled_sheet;
use common::Rng;

use minkq::{Aabb, Bvh, BvhQuery, Device, Error, Mode, PairBuffer, Query, QueryFlags, Scene, SceneDesc, SceneFlags};

#[test]
fn every_mode_contains_the_true_contacts_and_the_chain_holds() {
    let device = Device::cpu().unwrap();
    for (seed, n, r) in [(1u64, 12, 0.04f32), (2, 16, 0.02), (3, 9, 0.1)] {
        let mesh = crumpled_sheet(n, seed);
        let scene = Scene::new(&device, &SceneDesc::new(&mesh.vertices, &mesh.triangles)).unwrap();
        check_scene(&scene, &mesh, r);
    }
}

#[test]
fn explicit_edges_and_scene_flags() {
    let device = Device::cpu().unwrap();
    let mesh = crumpled_sheet(8, 5);
    let derived = Scene::new(&device, &SceneDesc::new(&mesh.vertices, &mesh.triangles)).unwrap();
    let edges = derived.edges().unwrap();
    let explicit = Scene::new(
        &device,
        &SceneDesc::new(&mesh.vertices, &mesh.triangles)
            .edges(&edges)
            .flags(SceneFlags::EE | SceneFlags::DROP_INCIDENT),
    )
    .unwrap();
    let q = Query::ee(Mode::CapsuleExact, 0.05).with_flags(QueryFlags::DIGEST);
    let (mut a, mut b) = (PairBuffer::new().unwrap(), PairBuffer::new().unwrap());
    derived.query(&q, &mut a).unwrap();
    explicit.query(&q, &mut b).unwrap();
    assert_eq!(a.pairs(), b.pairs());
    assert_eq!(a.digest(), b.digest());
    // A scene built for EE only answers no VT query.
    assert!(matches!(explicit.query(&Query::vt(Mode::Sphere, 0.05), &mut b), Err(Error::InvalidArgument(_))));
    // Without DROP_INCIDENT, a vertex is within any r of its own triangles.
    let keep = Scene::new(&device, &SceneDesc::new(&mesh.vertices, &mesh.triangles).flags(SceneFlags::VT)).unwrap();
    let all = pairs_of(&keep, Query::vt(Mode::Sphere, 0.0).with_flags(QueryFlags::LEAF_EXACT));
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for &v in tri {
            assert!(all.contains(&(v, t as i32)));
        }
    }
}

#[test]
fn bvh_queries_match_brute_force() {
    let device = Device::cpu().unwrap();
    let mut rng = Rng(21);
    let mut point = |s: f64| [rng.uniform() as f32 * s as f32, rng.uniform() as f32, rng.uniform() as f32];
    let boxes: Vec<Aabb> = (0..200)
        .map(|_| {
            let c = point(1.0);
            Aabb::new([c[0] - 0.02, c[1] - 0.03, c[2] - 0.01], [c[0] + 0.02, c[1] + 0.01, c[2] + 0.04])
        })
        .collect();
    let mut bvh = Bvh::new(&device, &boxes).unwrap();
    let centres: Vec<[f32; 3]> = (0..100).map(|_| point(1.0)).collect();
    let r = 0.05f32;
    let box_distance_sq = |p: [f32; 3], b: &Aabb| -> f64 {
        (0..3)
            .map(|k| {
                let d = (b.lo[k] as f64 - p[k] as f64).max(0.0).max(p[k] as f64 - b.hi[k] as f64);
                d * d
            })
            .sum()
    };
    let brute: Pairs = centres
        .iter()
        .enumerate()
        .flat_map(|(q, &c)| {
            boxes
                .iter()
                .enumerate()
                .filter(move |(_, b)| box_distance_sq(c, b) <= (r * r) as f64)
                .map(move |(i, _)| (q as i32, i as i32))
        })
        .collect();
    let mut out = Vec::new();
    bvh.query_into(&BvhQuery::spheres(&centres, Mode::Sphere, r), &mut out).unwrap();
    let sphere: Pairs = out.iter().map(|p| (p[0], p[1])).collect();
    bvh.query_into(&BvhQuery::spheres(&centres, Mode::Box, r), &mut out).unwrap();
    let padded: Pairs = out.iter().map(|p| (p[0], p[1])).collect();
    assert_subset(&brute, &sphere, "spheres");
    assert_subset(&sphere, &padded, "sphere in box");

    let segments: Vec<[[f32; 3]; 2]> = centres.iter().map(|&c| [c, [c[0] + 0.1, c[1], c[2] + 0.05]]).collect();
    let capsules = |mode| {
        let mut out = Vec::new();
        bvh.query_into(&BvhQuery::capsules(&segments, mode, r), &mut out).unwrap();
        out.iter().map(|p| (p[0], p[1])).collect::<Pairs>()
    };
    let (exact, ray, padded) = (capsules(Mode::CapsuleExact), capsules(Mode::CapsuleRay), capsules(Mode::Box));
    // Sampled segment points: every box within r of one of them must be reported.
    for (q, s) in segments.iter().enumerate() {
        for k in 0..=20 {
            let t = k as f32 / 20.0;
            let p = [
                s[0][0] + (s[1][0] - s[0][0]) * t,
                s[0][1] + (s[1][1] - s[0][1]) * t,
                s[0][2] + (s[1][2] - s[0][2]) * t,
            ];
            for (i, b) in boxes.iter().enumerate() {
                if box_distance_sq(p, b) <= (r as f64) * (r as f64) * 0.999 {
                    assert!(exact.contains(&(q as i32, i as i32)), "capsule {q} misses box {i}");
                }
            }
        }
    }
    assert_subset(&exact, &ray, "capsule_exact in capsule_ray");
    assert_subset(&ray, &padded, "capsule_ray in box");

    // Box queries, after a refit that shifts every box.
    let shifted: Vec<Aabb> =
        boxes.iter().map(|b| Aabb::new([b.lo[0] + 1.0, b.lo[1], b.lo[2]], [b.hi[0] + 1.0, b.hi[1], b.hi[2]])).collect();
    bvh.refit(&shifted).unwrap();
    let queries: Vec<Aabb> =
        centres.iter().map(|c| Aabb::new([c[0] + 1.0, c[1], c[2]], [c[0] + 1.05, c[1] + 0.05, c[2] + 0.05])).collect();
    bvh.query_into(&BvhQuery::boxes(&queries).with_flags(QueryFlags::CANONICAL), &mut out).unwrap();
    let overlaps = |a: &Aabb, b: &Aabb| (0..3).all(|k| a.lo[k] <= b.hi[k] && b.lo[k] <= a.hi[k]);
    let expected: Vec<[i32; 2]> = queries
        .iter()
        .enumerate()
        .flat_map(|(q, a)| {
            shifted.iter().enumerate().filter(move |(_, b)| overlaps(a, b)).map(move |(i, _)| [q as i32, i as i32])
        })
        .collect();
    assert_eq!(out, expected);
    assert!(matches!(bvh.refit(&shifted[1..]), Err(Error::InvalidArgument(_))));
    let err = bvh.query_into(&BvhQuery::boxes(&queries).with_flags(QueryFlags::LEAF_EXACT), &mut out).unwrap_err();
    assert!(matches!(err, Error::InvalidArgument(_)), "{err}");
}
