//! The safe crate against a brute-force double-precision oracle written here: zero false
//! negatives and the containment chain of every mode, before and after refit and rebuild
//! (whose pairs are the same); tree growth; buffers and capacity; digests against an
//! independent xxHash64; errors; threads.
mod common;
use common::{grid_triangles, Rng};

use std::collections::BTreeSet;
use std::sync::{Arc, Mutex};
use std::thread;

use minkq::{
    Aabb, Buffer, Bvh, BvhBufferQuery, BvhQuery, Device, Error, Memory, Mode, PairBuffer, PairsOut, Query, QueryFlags,
    QueryKind, Scene, SceneBuffers, SceneDesc, SceneFlags,
};

type V = [f64; 3];
type Pairs = BTreeSet<(i32, i32)>;

fn sub(a: V, b: V) -> V {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: V, b: V) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: V, b: V) -> V {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
fn axpy(a: V, d: V, t: f64) -> V {
    [a[0] + d[0] * t, a[1] + d[1] * t, a[2] + d[2] * t]
}

fn point_segment_sq(p: V, a: V, b: V) -> f64 {
    let d = sub(b, a);
    let dd = dot(d, d);
    let t = if dd > 0.0 { (dot(sub(p, a), d) / dd).clamp(0.0, 1.0) } else { 0.0 };
    let c = sub(p, axpy(a, d, t));
    dot(c, c)
}

/// Minimum over the three edges, and the plane distance when the projection is strictly inside.
fn point_triangle_sq(p: V, a: V, b: V, c: V) -> f64 {
    let mut best = point_segment_sq(p, a, b).min(point_segment_sq(p, b, c)).min(point_segment_sq(p, c, a));
    let n = cross(sub(b, a), sub(c, a));
    let nn = dot(n, n);
    if nn > 0.0 {
        let inside = dot(cross(sub(b, a), sub(p, a)), n) > 0.0
            && dot(cross(sub(c, b), sub(p, b)), n) > 0.0
            && dot(cross(sub(a, c), sub(p, c)), n) > 0.0;
        if inside {
            let h = dot(sub(p, a), n);
            best = best.min(h * h / nn);
        }
    }
    best
}

/// Minimum over the four endpoint–segment distances, and the interior minimum when both
/// parameters lie strictly inside.
fn segment_segment_sq(p0: V, p1: V, q0: V, q1: V) -> f64 {
    let mut best = point_segment_sq(p0, q0, q1)
        .min(point_segment_sq(p1, q0, q1))
        .min(point_segment_sq(q0, p0, p1))
        .min(point_segment_sq(q1, p0, p1));
    let (d1, d2, r) = (sub(p1, p0), sub(q1, q0), sub(p0, q0));
    let (a, e, b, c, f) = (dot(d1, d1), dot(d2, d2), dot(d1, d2), dot(d1, r), dot(d2, r));
    let denom = a * e - b * b;
    if denom > 0.0 {
        let s = (b * f - c * e) / denom;
        let t = (a * f - b * c) / denom;
        if s > 0.0 && s < 1.0 && t > 0.0 && t < 1.0 {
            let w = sub(axpy(p0, d1, s), axpy(q0, d2, t));
            best = best.min(dot(w, w));
        }
    }
    best
}

struct Mesh {
    vertices: Vec<[f32; 3]>,
    triangles: Vec<[i32; 3]>,
}

impl Mesh {
    fn v(&self, i: i32) -> V {
        let p = self.vertices[i as usize];
        [p[0] as f64, p[1] as f64, p[2] as f64]
    }

    fn vt_contacts(&self, r: f64) -> Pairs {
        let mut out = Pairs::new();
        for p in 0..self.vertices.len() as i32 {
            for (t, tri) in self.triangles.iter().enumerate() {
                if !tri.contains(&p)
                    && point_triangle_sq(self.v(p), self.v(tri[0]), self.v(tri[1]), self.v(tri[2])) <= r * r
                {
                    out.insert((p, t as i32));
                }
            }
        }
        out
    }

    fn ee_contacts(&self, edges: &[[i32; 2]], r: f64) -> Pairs {
        let mut out = Pairs::new();
        for (e, a) in edges.iter().enumerate() {
            for (f, b) in edges.iter().enumerate().skip(e + 1) {
                let incident = a[0] == b[0] || a[0] == b[1] || a[1] == b[0] || a[1] == b[1];
                if !incident && segment_segment_sq(self.v(a[0]), self.v(a[1]), self.v(b[0]), self.v(b[1])) <= r * r {
                    out.insert((e as i32, f as i32));
                }
            }
        }
        out
    }
}

/// A crumpled n x n sheet folded over itself, so that it comes close to itself in many places.
fn crumpled_sheet(n: i32, seed: u64) -> Mesh {
    let mut rng = Rng(seed);
    let mut vertices = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let (u, v) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
            let angle = 9.0 * u; // rolled up: ~1.4 turns, the layers ~0.035 apart
            let radius = 0.2 + 0.05 * u;
            vertices.push([
                (radius * angle.cos() + 0.02 * (rng.uniform() - 0.5)) as f32,
                (v + 0.02 * (rng.uniform() - 0.5)) as f32,
                (radius * angle.sin() + 0.02 * (rng.uniform() - 0.5)) as f32,
            ]);
        }
    }
    Mesh { vertices, triangles: grid_triangles(n) }
}

fn pairs_of(scene: &Scene, query: Query) -> Pairs {
    let mut out = PairBuffer::new().unwrap();
    scene.query(&query, &mut out).unwrap().iter().map(|p| (p[0], p[1])).collect()
}

fn assert_subset(small: &Pairs, large: &Pairs, what: &str) {
    let missing: Vec<_> = small.difference(large).take(5).collect();
    assert!(missing.is_empty(), "{what}: {} pairs missing, e.g. {missing:?}", small.difference(large).count());
}

/// Zero false negatives and the containment chain of every mode, for VT and EE.
fn check_scene(scene: &Scene, mesh: &Mesh, r: f32) {
    let edges = scene.edges().unwrap();
    let leaf = QueryFlags::LEAF_EXACT;
    let truth_vt = mesh.vt_contacts(r as f64);
    let truth_ee = mesh.ee_contacts(&edges, r as f64);
    assert!(
        truth_vt.len() > 5 && truth_ee.len() > 5,
        "the test scene must have contacts: {} VT, {} EE",
        truth_vt.len(),
        truth_ee.len()
    );
    eprintln!("r {r}: {} VT and {} EE true contacts", truth_vt.len(), truth_ee.len());
    // Leaf-exact pairs lie within r + 2^-19 S; S is at most a few units here.
    let loose = r as f64 + 1e-5;

    let vt_leaf = pairs_of(scene, Query::vt(Mode::Sphere, r).with_flags(leaf));
    let vt_sphere = pairs_of(scene, Query::vt(Mode::Sphere, r));
    let vt_box = pairs_of(scene, Query::vt(Mode::Box, r));
    assert_subset(&truth_vt, &vt_leaf, "VT true contacts in leaf_exact");
    assert_subset(&vt_leaf, &mesh.vt_contacts(loose), "VT leaf_exact within r + tolerance");
    assert_subset(&vt_leaf, &vt_sphere, "VT leaf_exact in sphere");
    assert_subset(&vt_sphere, &vt_box, "VT sphere in box");
    // Points are zero-length capsules.
    assert_eq!(pairs_of(scene, Query::vt(Mode::CapsuleRay, r)), vt_box);
    assert_eq!(pairs_of(scene, Query::vt(Mode::CapsuleExact, r)), vt_sphere);
    assert_eq!(pairs_of(scene, Query::vt(Mode::Box, r).with_flags(leaf)), vt_leaf);

    let ee_leaf = pairs_of(scene, Query::ee(Mode::CapsuleExact, r).with_flags(leaf));
    let ee_exact = pairs_of(scene, Query::ee(Mode::CapsuleExact, r));
    let ee_ray = pairs_of(scene, Query::ee(Mode::CapsuleRay, r));
    let ee_box = pairs_of(scene, Query::ee(Mode::Box, r));
    assert_subset(&truth_ee, &ee_leaf, "EE true contacts in leaf_exact");
    assert_subset(&ee_leaf, &mesh.ee_contacts(&edges, loose), "EE leaf_exact within r + tolerance");
    assert_subset(&ee_leaf, &ee_exact, "EE leaf_exact in capsule_exact");
    assert_subset(&ee_exact, &ee_ray, "EE capsule_exact in capsule_ray");
    assert_subset(&ee_ray, &ee_box, "EE capsule_ray in box");
    assert!(ee_exact.len() < ee_box.len(), "the exact test should prune something here");
}

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

/// A flat n x n grid over the unit square (z = 0), triangulated by `grid_triangles`.
fn flat_grid(n: i32) -> Mesh {
    let step = 1.0 / (n - 1) as f32;
    let vertices = (0..n * n).map(|k| [(k % n) as f32 * step, (k / n) as f32 * step, 0.0]).collect();
    Mesh { vertices, triangles: grid_triangles(n) }
}

/// The flat grid's vertices (x = u, y = v) rolled up about the y axis as `crumpled_sheet`
/// rolls its sheet (~1.4 turns, the layers ~0.035 apart), each row then turned about the y
/// axis by `twist` v radians: far from the positions the trees were built for.
fn rolled_and_twisted(flat: &[[f32; 3]], twist: f64) -> Vec<[f32; 3]> {
    flat.iter()
        .map(|p| {
            let (u, v) = (p[0] as f64, p[1] as f64);
            let (angle, radius) = (9.0 * u, 0.2 + 0.05 * u);
            let (x, z) = (radius * angle.cos(), radius * angle.sin());
            let (c, s) = ((twist * v).cos(), (twist * v).sin());
            [(c * x - s * z) as f32, v as f32, (s * x + c * z) as f32]
        })
        .collect()
}

fn scaled(vertices: &[[f32; 3]], factor: f32) -> Vec<[f32; 3]> {
    vertices.iter().map(|p| [p[0] * factor, p[1] * factor, p[2] * factor]).collect()
}

/// Every kind, mode and flag set gives the same pairs (and digests) on both scenes.
fn assert_same_pairs(a: &Scene, b: &Scene, r: f32, what: &str) {
    let mut nonempty = 0;
    for kind in [QueryKind::Vt, QueryKind::Ee] {
        for mode in Mode::ALL {
            if kind == QueryKind::Ee && mode == Mode::Sphere {
                continue;
            }
            for flags in [QueryFlags::empty(), QueryFlags::LEAF_EXACT, QueryFlags::DIGEST] {
                let q = Query::new(kind, mode, r).with_flags(flags);
                let (mut pa, mut pb) = (PairBuffer::new().unwrap(), PairBuffer::new().unwrap());
                let (got_a, got_b) = (a.query(&q, &mut pa).unwrap(), b.query(&q, &mut pb).unwrap());
                let (set_a, set_b): (Pairs, Pairs) =
                    (got_a.iter().map(|p| (p[0], p[1])).collect(), got_b.iter().map(|p| (p[0], p[1])).collect());
                assert_eq!(set_a, set_b, "{what}: {kind} {mode} {flags:?}");
                if flags == QueryFlags::DIGEST {
                    assert_eq!(got_a, got_b, "{what}: {kind} {mode} canonical order");
                    assert_eq!(pa.digest(), pb.digest(), "{what}: {kind} {mode} digest");
                }
                nonempty += !set_a.is_empty() as usize;
            }
        }
    }
    assert_eq!(nonempty, 21, "{what}: every query should find pairs here");
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
        let info_a = refitted.query_vec(&query, &mut a).unwrap();
        let info_b = rebuilt.query_vec(&query, &mut b).unwrap();
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
    assert!(matches!(scene.rebuild_buffer(on_gpu), Err(Error::InvalidArgument(m)) if m.contains("device memory")));
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
    bvh.query_vec(&BvhQuery::spheres(&[[2.5; 3]], Mode::Sphere, 0.0), &mut out).unwrap();
    assert_eq!(out, vec![[0, 1]], "a failed rebuild keeps the boxes");
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
        let info = strided.query_to(&query, PairsOut::from_slice(&mut storage)).unwrap();
        let got: Pairs = storage[..info.count as usize].iter().map(|p| (p[0], p[1])).collect();
        assert_eq!(got, expected, "{:?}", query.kind);
    }
    // Refit from strided records: lift every vertex; the pairs stay those of a packed refit.
    let lifted: Vec<[f32; 4]> = vec4.iter().map(|v| [v[0] * 0.5, v[1], v[2] * 0.5, 0.0]).collect();
    // SAFETY: as above.
    strided
        .refit_buffer(unsafe { Buffer::from_raw_parts(lifted.as_ptr().cast(), 16, lifted.len(), Memory::Host) })
        .unwrap();
    let mut packed = packed;
    packed.refit(&lifted.iter().map(|v| [v[0], v[1], v[2]]).collect::<Vec<_>>()).unwrap();
    let query = Query::ee(Mode::CapsuleExact, r).with_flags(QueryFlags::LEAF_EXACT);
    assert_eq!(pairs_of(&strided, query), pairs_of(&packed, query));
    // Device memory on the CPU backend: refused, the scene unchanged.
    // SAFETY: never read: the CPU device rejects device memory before reading.
    let on_gpu = unsafe { Buffer::from_raw_parts(vec4.as_ptr().cast(), 16, vec4.len(), Memory::Device) };
    assert!(matches!(strided.refit_buffer(on_gpu), Err(Error::InvalidArgument(m)) if m.contains("device memory")));
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
    bvh.query_vec(&query, &mut expected).unwrap();
    assert!(!expected.is_empty());
    let starts: Vec<[f32; 3]> = segments.iter().map(|s| s[0]).collect();
    let ends: Vec<[f32; 3]> = segments.iter().map(|s| s[1]).collect();
    let split =
        BvhBufferQuery::capsules(Buffer::from_slice(&starts), Buffer::from_slice(&ends), Mode::CapsuleExact, 0.05)
            .with_flags(QueryFlags::CANONICAL);
    let mut out = vec![[0; 2]; expected.len()];
    let info = bvh.query_to(&split, PairsOut::from_slice(&mut out)).unwrap();
    assert_eq!((info.count as usize, out), (expected.len(), expected.clone()));
    let mut small = vec![[0; 2]; 1];
    match bvh.query_to(&split, PairsOut::from_slice(&mut small)) {
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
    let info = scene.query_vec(&q, &mut all).unwrap();
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
    scene.query_vec(&q, &mut reused).unwrap();
    assert_eq!(reused, all);
}

/// XXH64 (seed 0), written from the specification, to check the library's digest definition.
fn xxh64(data: &[u8]) -> u64 {
    const P1: u64 = 0x9E3779B185EBCA87;
    const P2: u64 = 0xC2B2AE3D27D4EB4F;
    const P3: u64 = 0x165667B19E3779F9;
    const P4: u64 = 0x85EBCA77C2B2AE63;
    const P5: u64 = 0x27D4EB2F165667C5;
    let round = |acc: u64, lane: u64| acc.wrapping_add(lane.wrapping_mul(P2)).rotate_left(31).wrapping_mul(P1);
    let merge = |acc: u64, v: u64| (acc ^ round(0, v)).wrapping_mul(P1).wrapping_add(P4);
    let u64_at = |i: usize| u64::from_le_bytes(data[i..i + 8].try_into().unwrap());
    let mut i = 0;
    let mut h = if data.len() >= 32 {
        let mut v = [P1.wrapping_add(P2), P2, 0, 0u64.wrapping_sub(P1)];
        while i + 32 <= data.len() {
            for (k, lane) in v.iter_mut().enumerate() {
                *lane = round(*lane, u64_at(i + 8 * k));
            }
            i += 32;
        }
        let mut h = v[0]
            .rotate_left(1)
            .wrapping_add(v[1].rotate_left(7))
            .wrapping_add(v[2].rotate_left(12))
            .wrapping_add(v[3].rotate_left(18));
        for lane in v {
            h = merge(h, lane);
        }
        h
    } else {
        P5
    };
    h = h.wrapping_add(data.len() as u64);
    while i + 8 <= data.len() {
        h = (h ^ round(0, u64_at(i))).rotate_left(27).wrapping_mul(P1).wrapping_add(P4);
        i += 8;
    }
    if i + 4 <= data.len() {
        let w = u32::from_le_bytes(data[i..i + 4].try_into().unwrap()) as u64;
        h = (h ^ w.wrapping_mul(P1)).rotate_left(23).wrapping_mul(P2).wrapping_add(P3);
        i += 4;
    }
    for &b in &data[i..] {
        h = (h ^ (b as u64).wrapping_mul(P5)).rotate_left(11).wrapping_mul(P1);
    }
    h ^= h >> 33;
    h = h.wrapping_mul(P2);
    h ^= h >> 29;
    h = h.wrapping_mul(P3);
    h ^ (h >> 32)
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
        assert_eq!(scene.query_vec(&q, &mut out).unwrap().digest, Some(buffer.digest()));
        // Without DIGEST, the info carries none.
        let plain = Query { flags: QueryFlags::empty(), ..q };
        assert_eq!(scene.query_vec(&plain, &mut out).unwrap().digest, None);
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
    bvh.query_vec(&BvhQuery::spheres(&centres, Mode::Sphere, r), &mut out).unwrap();
    let sphere: Pairs = out.iter().map(|p| (p[0], p[1])).collect();
    bvh.query_vec(&BvhQuery::spheres(&centres, Mode::Box, r), &mut out).unwrap();
    let padded: Pairs = out.iter().map(|p| (p[0], p[1])).collect();
    assert_subset(&brute, &sphere, "spheres");
    assert_subset(&sphere, &padded, "sphere in box");

    let segments: Vec<[[f32; 3]; 2]> = centres.iter().map(|&c| [c, [c[0] + 0.1, c[1], c[2] + 0.05]]).collect();
    let capsules = |mode| {
        let mut out = Vec::new();
        bvh.query_vec(&BvhQuery::capsules(&segments, mode, r), &mut out).unwrap();
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
    bvh.query_vec(&BvhQuery::boxes(&queries).with_flags(QueryFlags::CANONICAL), &mut out).unwrap();
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
    let err = bvh.query_vec(&BvhQuery::boxes(&queries).with_flags(QueryFlags::LEAF_EXACT), &mut out).unwrap_err();
    assert!(matches!(err, Error::InvalidArgument(_)), "{err}");
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
                (scene.query_vec(&q, &mut out).unwrap(), scene)
            })
        })
        .collect();
    let results: Vec<_> = handles.into_iter().map(|h| h.join().unwrap()).collect();
    drop(device); // the scenes keep the device alive
    for (seed, (info, scene)) in results.into_iter().enumerate() {
        // Moved back to this thread, still usable; the same answer as a fresh query.
        let moved = thread::spawn(move || {
            let q = Query::ee(Mode::CapsuleExact, 0.03).with_flags(QueryFlags::DIGEST);
            scene.query_vec(&q, &mut Vec::new()).unwrap()
        })
        .join()
        .unwrap();
        assert_eq!(info, moved, "seed {seed}");
    }
}
