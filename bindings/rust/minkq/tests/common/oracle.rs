//! The brute-force double-precision oracle: point–segment, point–triangle and segment–segment
//! distances, a mesh's true VT and EE contacts within r; and the checks of scenes against it
//! (zero false negatives, the containment chain of every mode) and against each other. Its
//! vector helpers, distances and `assert_subset` serve the other tests' own oracles too.

use std::collections::BTreeSet;
use std::fmt::Debug;

use minkq::{Mode, PairBuffer, Query, QueryFlags, QueryKind, Scene};

pub type V = [f64; 3];
pub type Pairs = BTreeSet<(i32, i32)>;

pub fn sub(a: V, b: V) -> V {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub fn dot(a: V, b: V) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
pub fn cross(a: V, b: V) -> V {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
fn axpy(a: V, d: V, t: f64) -> V {
    [a[0] + d[0] * t, a[1] + d[1] * t, a[2] + d[2] * t]
}

pub fn point_segment_sq(p: V, a: V, b: V) -> f64 {
    let d = sub(b, a);
    let dd = dot(d, d);
    let t = if dd > 0.0 { (dot(sub(p, a), d) / dd).clamp(0.0, 1.0) } else { 0.0 };
    let c = sub(p, axpy(a, d, t));
    dot(c, c)
}

/// Minimum over the three edges, and the plane distance when the projection is strictly inside.
pub fn point_triangle_sq(p: V, a: V, b: V, c: V) -> f64 {
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
pub fn segment_segment_sq(p0: V, p1: V, q0: V, q1: V) -> f64 {
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

pub struct Mesh {
    pub vertices: Vec<[f32; 3]>,
    pub triangles: Vec<[i32; 3]>,
}

impl Mesh {
    fn v(&self, i: i32) -> V {
        let p = self.vertices[i as usize];
        [p[0] as f64, p[1] as f64, p[2] as f64]
    }

    pub fn vt_contacts(&self, r: f64) -> Pairs {
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

    pub fn ee_contacts(&self, edges: &[[i32; 2]], r: f64) -> Pairs {
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

pub fn pairs_of(scene: &Scene, query: Query) -> Pairs {
    let mut out = PairBuffer::new().unwrap();
    scene.query(&query, &mut out).unwrap().iter().map(|p| (p[0], p[1])).collect()
}

/// Every pair of `small` is in `large` (a `Pairs` or a `Vec` of pairs); else fails, naming how
/// many are missing and up to five.
pub fn assert_subset<'a, P: Ord + Debug + 'a>(
    small: impl IntoIterator<Item = &'a P>,
    large: impl IntoIterator<Item = &'a P>,
    what: &str,
) {
    let (small, large): (Vec<&P>, BTreeSet<&P>) = (small.into_iter().collect(), large.into_iter().collect());
    let lost: Vec<_> = small.iter().filter(|p| !large.contains(*p)).collect();
    assert!(
        lost.is_empty(),
        "{what}: {} of {} missing, e.g. {:?}",
        lost.len(),
        small.len(),
        &lost[..lost.len().min(5)]
    );
}

/// Zero false negatives and the containment chain of every mode, for VT and EE.
pub fn check_scene(scene: &Scene, mesh: &Mesh, r: f32) {
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

/// Every kind, mode and flag set gives the same pairs (and digests) on both scenes.
pub fn assert_same_pairs(a: &Scene, b: &Scene, r: f32, what: &str) {
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
