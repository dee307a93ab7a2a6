//! Codimensional elements (`Query::vv`, `Query::ev`, `SceneDesc::codim`) through the safe
//! crate: rods and loose particles with no triangles against a brute-force double-precision
//! oracle written here, at three scales: every mode contains the true contacts, leaf-exact
//! pairs are the true contacts within the float slack, the modes nest (points: capsule_ray ==
//! box, capsule_exact == sphere); VV pairs once as (v, w), v < w; EV drops a vertex's own edges
//! with DROP_INCIDENT and keeps them without; refit and rebuild give a fresh scene's pairs;
//! float64 scenes find what rounding to float pulls apart, and keep the double truth; swept
//! steps contain the contacts sampled at 17 times of the step in every mode (float and
//! float64), refuse leaf-exact, and give the static pairs at rest; VV and EV beside triangles
//! equal a triangle-less scene; every blocking and stream-ordered entry point takes the new
//! kinds; kinds a scene was built without are refused with the library's message.
mod common;
use common::oracle::{assert_subset, dot, point_segment_sq, sub, V};
use common::{grid_triangles, Rng};

use minkq::{
    CountOut, Device, Error, Mode, PairBuffer, PairsOut, Query, QueryFlags, QueryKind, Scene, SceneDesc, SceneFlags,
    Stream,
};

type Pairs = Vec<[i32; 2]>;

const LEAF_FLAGS: [QueryFlags; 2] = [QueryFlags::empty(), QueryFlags::LEAF_EXACT];

/// `SceneDesc::codim`'s flags.
fn codim_flags() -> SceneFlags {
    SceneFlags::VV | SceneFlags::EV | SceneFlags::DROP_INCIDENT
}

/// Every (v, w), v < w, within r: brute force in double.
fn vv_truth(points: &[V], r: f64) -> Pairs {
    let mut out = Pairs::new();
    for v in 0..points.len() {
        for w in v + 1..points.len() {
            let d = sub(points[v], points[w]);
            if dot(d, d) <= r * r {
                out.push([v as i32, w as i32]);
            }
        }
    }
    out
}

/// Every (vertex, edge) within r, without a vertex's own edges when `drop_incident`.
fn ev_truth(points: &[V], edges: &[[i32; 2]], r: f64, drop_incident: bool) -> Pairs {
    let mut out = Pairs::new();
    for (v, &p) in points.iter().enumerate() {
        for (e, &[a, b]) in edges.iter().enumerate() {
            if drop_incident && (a == v as i32 || b == v as i32) {
                continue;
            }
            if point_segment_sq(p, points[a as usize], points[b as usize]) <= r * r {
                out.push([v as i32, e as i32]);
            }
        }
    }
    out
}

/// `rods` polylines of `per_rod` vertices (random walks, consecutive vertices joined by an edge)
/// and `loose` particles, in [offset, offset + scale]^3.
struct Codim {
    vertices: Vec<V>,
    edges: Vec<[i32; 2]>,
}

fn rods_and_particles(seed: u64, rods: usize, per_rod: usize, loose: usize, scale: f64, offset: f64) -> Codim {
    let mut rng = Rng(seed);
    let (mut vertices, mut edges) = (Vec::new(), Vec::new());
    for _ in 0..rods {
        let mut p = [rng.uniform(), rng.uniform(), rng.uniform()];
        for i in 0..per_rod {
            if i > 0 {
                let v = vertices.len() as i32;
                edges.push([v - 1, v]);
            }
            for c in &mut p {
                *c += 0.08 * (rng.uniform() - 0.5);
            }
            vertices.push(p);
        }
    }
    for _ in 0..loose {
        vertices.push([rng.uniform(), rng.uniform(), rng.uniform()]);
    }
    let vertices = vertices.iter().map(|p| p.map(|c| c * scale + offset)).collect();
    Codim { vertices, edges }
}

fn floats(vertices: &[V]) -> Vec<[f32; 3]> {
    vertices.iter().map(|v| v.map(|c| c as f32)).collect()
}
fn widened(vertices: &[[f32; 3]]) -> Vec<V> {
    vertices.iter().map(|v| v.map(f64::from)).collect()
}

/// A query's pairs, sorted.
fn pairs(scene: &Scene, query: Query) -> Pairs {
    let mut out = Vec::new();
    scene.query_into(&query.with_flags(query.flags | QueryFlags::CANONICAL), &mut out).unwrap();
    out
}

/// Zero false negatives in every mode, leaf-exact pairs within [truth(r), truth(r + slack)],
/// the modes' chain, VV pairs ordered, no incident EV pair; `points` are the positions the
/// truth is taken on (the floats of a float scene, the doubles of a float64 scene).
fn check_codim(scene: &Scene, points: &[V], edges: &[[i32; 2]], r: f32, slack: f64, what: &str) {
    let r64 = f64::from(r);
    let (vv, ev) = (vv_truth(points, r64), ev_truth(points, edges, r64, true));
    assert!(vv.len() > 20 && ev.len() > 20, "{what}: the scene needs contacts: {} VV, {} EV", vv.len(), ev.len());
    let (vv_loose, ev_loose) = (vv_truth(points, r64 + slack), ev_truth(points, edges, r64 + slack, true));
    for (kind, truth, loose) in [(QueryKind::Vv, &vv, &vv_loose), (QueryKind::Ev, &ev, &ev_loose)] {
        for mode in Mode::ALL {
            let got = pairs(scene, Query::new(kind, mode, r));
            assert_subset(truth, &got, &format!("{what}: {kind} {mode} contains the truth"));
            let leaf = pairs(scene, Query::new(kind, mode, r).with_flags(QueryFlags::LEAF_EXACT));
            assert_subset(truth, &leaf, &format!("{what}: {kind} {mode} leaf_exact contains the truth"));
            assert_subset(&leaf, loose, &format!("{what}: {kind} {mode} leaf_exact within r + slack"));
            assert_subset(&leaf, &got, &format!("{what}: {kind} {mode} leaf_exact in the mode's pairs"));
            for &[a, b] in &got {
                match kind {
                    QueryKind::Vv => assert!(a < b, "{what}: VV pair ({a}, {b}) out of order"),
                    _ => assert!(!edges[b as usize].contains(&a), "{what}: EV pair ({a}, {b}) is incident"),
                }
            }
        }
        let at = |mode| pairs(scene, Query::new(kind, mode, r));
        let (sphere, boxed) = (at(Mode::Sphere), at(Mode::Box));
        assert_subset(&sphere, &boxed, &format!("{what}: {kind} sphere in box"));
        assert_eq!(at(Mode::CapsuleRay), boxed, "{what}: {kind} capsule_ray is box for points");
        assert_eq!(at(Mode::CapsuleExact), sphere, "{what}: {kind} capsule_exact is sphere for points");
        assert!(sphere.len() < boxed.len(), "{what}: {kind} the sphere test should prune something");
    }
}

#[test]
fn rods_and_particles_lose_no_pair_in_any_mode_at_any_scale() {
    let device = Device::cpu().unwrap();
    for (seed, scale) in [(1u64, 1e-3), (2, 1.0), (3, 1e3)] {
        let mesh = rods_and_particles(seed, 12, 20, 80, scale, 0.25 * scale);
        let vertices = floats(&mesh.vertices);
        let scene = Scene::new(&device, &SceneDesc::codim(&vertices, &mesh.edges)).unwrap();
        assert_eq!((scene.vertex_count(), scene.triangle_count(), scene.edge_count()), (320, 0, 228));
        assert_eq!(scene.edges().unwrap(), mesh.edges);
        let r = (0.05 * scale) as f32;
        check_codim(&scene, &widened(&vertices), &mesh.edges, r, 1e-5 * scale, &format!("scale {scale}"));
    }
}

#[test]
fn vv_pairs_once_in_order_and_ev_drops_incident_edges_only_when_asked() {
    let device = Device::cpu().unwrap();
    let mesh = rods_and_particles(4, 6, 30, 20, 1.0, 0.0);
    let vertices = floats(&mesh.vertices);
    let points = widened(&vertices);
    let r = 0.04;
    let keep =
        Scene::new(&device, &SceneDesc::codim(&vertices, &mesh.edges).flags(SceneFlags::VV | SceneFlags::EV)).unwrap();
    let drop = Scene::new(&device, &SceneDesc::codim(&vertices, &mesh.edges)).unwrap();
    for mode in Mode::ALL {
        for flags in LEAF_FLAGS {
            // VV: each pair once, lower id first; DROP_INCIDENT drops none (rod neighbours within
            // r pair too).
            let mut buffer = PairBuffer::new().unwrap();
            let raw = drop.query(&Query::vv(mode, r).with_flags(flags), &mut buffer).unwrap().to_vec();
            let mut sorted = raw.clone();
            sorted.sort_unstable();
            sorted.dedup();
            assert_eq!(sorted.len(), raw.len(), "{mode} {flags:?}: VV pairs reported twice");
            assert!(raw.iter().all(|&[v, w]| v < w), "{mode} {flags:?}: VV pair out of order");
            assert_eq!(pairs(&keep, Query::vv(mode, r).with_flags(flags)), sorted, "{mode} {flags:?}");
            let neighbours = sorted.iter().filter(|p| mesh.edges.contains(p)).count();
            assert!(neighbours > 10, "{mode} {flags:?}: {neighbours} rod neighbours");

            // EV: without DROP_INCIDENT every vertex pairs with its own edges (distance 0).
            let kept = pairs(&keep, Query::ev(mode, r).with_flags(flags));
            let dropped = pairs(&drop, Query::ev(mode, r).with_flags(flags));
            let incident: Pairs = kept.iter().copied().filter(|&[v, e]| mesh.edges[e as usize].contains(&v)).collect();
            assert_eq!(incident.len(), 2 * mesh.edges.len(), "{mode} {flags:?}");
            let rest: Pairs = kept.iter().copied().filter(|p| !incident.contains(p)).collect();
            assert_eq!(dropped, rest, "{mode} {flags:?}: DROP_INCIDENT drops exactly the incident pairs");
            if flags == QueryFlags::LEAF_EXACT {
                assert_subset(&ev_truth(&points, &mesh.edges, 0.04, false), &kept, "EV truth with incident");
                assert_subset(&ev_truth(&points, &mesh.edges, 0.04, true), &dropped, "EV truth without");
            }
        }
    }
}

#[test]
fn refit_and_rebuild_give_a_fresh_scenes_pairs() {
    let device = Device::cpu().unwrap();
    let mesh = rods_and_particles(5, 10, 20, 60, 1.0, 0.0);
    let moved = rods_and_particles(6, 10, 20, 60, 1.0, 0.0); // same topology, other positions
    assert_eq!(mesh.edges, moved.edges);
    let (before, after) = (floats(&mesh.vertices), floats(&moved.vertices));
    let fresh = Scene::new(&device, &SceneDesc::codim(&after, &mesh.edges)).unwrap();
    for rebuild in [false, true] {
        let mut scene = Scene::new(&device, &SceneDesc::codim(&before, &mesh.edges)).unwrap();
        if rebuild {
            scene.rebuild(&after).unwrap();
            assert_eq!(scene.tree_growth().unwrap(), 1.0);
        } else {
            scene.refit(&after).unwrap();
        }
        for kind in [QueryKind::Vv, QueryKind::Ev] {
            for mode in Mode::ALL {
                for flags in LEAF_FLAGS {
                    let q = Query::new(kind, mode, 0.05).with_flags(flags);
                    let got = pairs(&scene, q);
                    assert!(!got.is_empty());
                    assert_eq!(got, pairs(&fresh, q), "rebuild {rebuild}: {kind} {mode} {flags:?}");
                }
            }
        }
    }
}

/// The float spacing at x > 0.
fn ulp(x: f32) -> f64 {
    f64::from(f32::from_bits(x.to_bits() + 1)) - f64::from(x)
}

#[test]
fn float64_scenes_find_pairs_that_rounding_pulls_apart() {
    // Near x = 20000 floats lie 2^-9 (about 1.95e-3) apart: two points 0.95e-3 apart in double
    // round to floats 2^-9 apart, beyond r = 1e-3.
    let device = Device::cpu().unwrap();
    let r = 1e-3f32;
    let u = ulp(20000.0);
    let (plane, point) = (0..64)
        .map(|k| {
            let plane = 20000.0 + (k as f64 / 64.0 - 0.5) * u;
            (plane, plane + 0.95 * f64::from(r))
        })
        .find(|&(plane, point)| point as f32 - plane as f32 > r)
        .unwrap();
    // Particles 0 and 1 (VV); particle 4 facing edge 0, from vertex 2 to 3 along y (EV).
    let vertices = [[plane, 0.0, 0.0], [point, 0.0, 0.0], [plane, -1.0, 5.0], [plane, 1.0, 5.0], [point, 0.0, 5.0]];
    let edges = [[2, 3]];
    let scene = Scene::new(&device, &SceneDesc::codim(&vertices, &edges)).unwrap();
    assert!(scene.is_float64());
    let rounded = floats(&vertices);
    let float_scene = Scene::new(&device, &SceneDesc::codim(&rounded, &edges)).unwrap();
    for mode in Mode::ALL {
        for flags in LEAF_FLAGS {
            let (vv, ev) = (Query::vv(mode, r).with_flags(flags), Query::ev(mode, r).with_flags(flags));
            assert_eq!(pairs(&scene, vv), [[0, 1]], "{mode} {flags:?}");
            assert_eq!(pairs(&scene, ev), [[4, 0]], "{mode} {flags:?}");
            if flags == QueryFlags::LEAF_EXACT {
                assert!(pairs(&float_scene, vv).is_empty(), "{mode}: rounded, VV is lost");
                assert!(pairs(&float_scene, ev).is_empty(), "{mode}: rounded, EV is lost");
            }
        }
    }
    // Floats are refused by a float64 scene's refit.
    let mut scene = scene;
    assert!(matches!(scene.refit(&rounded), Err(Error::InvalidArgument(_))));
    scene.refit(&vertices).unwrap();
    assert_eq!(pairs(&scene, Query::vv(Mode::Sphere, r)), [[0, 1]]);
}

#[test]
fn float64_rods_keep_the_double_truth() {
    // Coordinates off the floats near 1000 + [0, 1]: the truth in double, leaf-exact extras
    // within r + 2 rho (rho <= sqrt(3)/2 ulp) plus the float slack.
    let device = Device::cpu().unwrap();
    let mut rng = Rng(11);
    let mut mesh = rods_and_particles(7, 12, 20, 80, 1.0, 1000.0);
    for v in &mut mesh.vertices {
        for c in v.iter_mut() {
            *c += ulp(*c as f32) * (rng.uniform() - 0.5);
        }
    }
    let scene = Scene::new(&device, &SceneDesc::codim(&mesh.vertices, &mesh.edges)).unwrap();
    assert!(scene.is_float64());
    let slack = 3f64.sqrt() * ulp(1001.0) + 1e-5;
    check_codim(&scene, &mesh.vertices, &mesh.edges, 0.05, slack, "float64");
    let mut scene = scene;
    scene.rebuild(&mesh.vertices).unwrap();
    check_codim(&scene, &mesh.vertices, &mesh.edges, 0.05, slack, "float64 rebuilt");
}

/// Positions at time t of the step x0 -> x1, in double.
fn lerp(x0: &[V], x1: &[V], t: f64) -> Vec<V> {
    x0.iter().zip(x1).map(|(a, b)| [0, 1, 2].map(|k| a[k] + t * (b[k] - a[k]))).collect()
}

fn merge(all: &mut Pairs, more: Pairs) {
    all.extend(more);
    all.sort_unstable();
    all.dedup();
}

#[test]
fn swept_steps_contain_every_sampled_contact_in_every_mode() {
    let device = Device::cpu().unwrap();
    let r = 0.03f32;
    for float64 in [false, true] {
        let mesh = rods_and_particles(8, 8, 16, 40, 1.0, if float64 { 300.0 } else { 0.0 });
        let mut x1 = mesh.vertices.clone();
        for (v, p) in x1.iter_mut().enumerate() {
            for (k, c) in p.iter_mut().enumerate() {
                *c += 0.1 * (0.7 * v as f64 + 2.1 * k as f64).sin();
            }
        }
        // The truth is taken on the positions the scene reads: floats, or the doubles.
        let (x0, x1) = if float64 {
            (mesh.vertices.clone(), x1)
        } else {
            (widened(&floats(&mesh.vertices)), widened(&floats(&x1)))
        };
        let (mut vv, mut ev) = (Pairs::new(), Pairs::new());
        for k in 0..=16 {
            let at = lerp(&x0, &x1, k as f64 / 16.0);
            merge(&mut vv, vv_truth(&at, f64::from(r)));
            merge(&mut ev, ev_truth(&at, &mesh.edges, f64::from(r), true));
        }
        let static_vv = vv_truth(&x0, f64::from(r));
        assert!(vv.len() > static_vv.len() + 5, "float64 {float64}: the step must add VV contacts");
        for rebuild in [false, true] {
            let what = format!("float64 {float64} rebuild {rebuild}");
            let mut scene = if float64 {
                let mut scene = Scene::new(&device, &SceneDesc::codim(&x0, &mesh.edges)).unwrap();
                if rebuild {
                    scene.rebuild_swept(&x0, &x1).unwrap();
                } else {
                    scene.refit_swept(&x0, &x1).unwrap();
                }
                scene
            } else {
                let (f0, f1) = (floats(&x0), floats(&x1));
                let mut scene = Scene::new(&device, &SceneDesc::codim(&f0, &mesh.edges)).unwrap();
                if rebuild {
                    scene.rebuild_swept(&f0, &f1).unwrap();
                } else {
                    scene.refit_swept(&f0, &f1).unwrap();
                }
                scene
            };
            assert!(scene.is_swept());
            for mode in Mode::ALL {
                let got_vv = pairs(&scene, Query::vv(mode, r));
                let got_ev = pairs(&scene, Query::ev(mode, r));
                assert_subset(&vv, &got_vv, &format!("{what}: swept VV {mode}"));
                assert_subset(&ev, &got_ev, &format!("{what}: swept EV {mode}"));
                assert!(got_vv.iter().all(|&[v, w]| v < w), "{what}: VV order");
                assert!(got_ev.iter().all(|&[v, e]| !mesh.edges[e as usize].contains(&v)), "{what}: EV incident");
            }
            // Sphere is capsule_exact (the sphere swept along the path); the modes nest.
            for kind in [QueryKind::Vv, QueryKind::Ev] {
                let at = |mode| pairs(&scene, Query::new(kind, mode, r));
                assert_eq!(at(Mode::Sphere), at(Mode::CapsuleExact), "{what}: {kind}");
                assert_subset(&at(Mode::CapsuleExact), &at(Mode::CapsuleRay), &format!("{what}: {kind} exact in ray"));
                assert_subset(&at(Mode::CapsuleRay), &at(Mode::Box), &format!("{what}: {kind} ray in box"));
                let leaf = Query::new(kind, Mode::Box, r).with_flags(QueryFlags::LEAF_EXACT);
                let err = scene.query(&leaf, &mut PairBuffer::new().unwrap()).unwrap_err();
                assert!(matches!(err, Error::Unsupported(_)), "{what}: {kind} leaf_exact swept: {err:?}");
            }
            // A plain refit makes the scene static again: leaf-exact runs and finds the truth at x0.
            if float64 {
                scene.refit(&x0).unwrap();
            } else {
                scene.refit(&floats(&x0)).unwrap();
            }
            assert!(!scene.is_swept());
            let leaf = Query::vv(Mode::Box, r).with_flags(QueryFlags::LEAF_EXACT);
            assert_subset(&static_vv, &pairs(&scene, leaf), &format!("{what}: static again"));
        }
    }
}

#[test]
fn swept_steps_at_rest_give_the_static_pairs() {
    let device = Device::cpu().unwrap();
    let mesh = rods_and_particles(9, 8, 16, 40, 1.0, 0.0);
    let x = floats(&mesh.vertices);
    let fixed = Scene::new(&device, &SceneDesc::codim(&x, &mesh.edges)).unwrap();
    let mut still = Scene::new(&device, &SceneDesc::codim(&x, &mesh.edges)).unwrap();
    still.rebuild_swept(&x, &x).unwrap();
    let r = 0.04;
    for kind in [QueryKind::Vv, QueryKind::Ev] {
        for (mode, static_mode) in [
            (Mode::Box, Mode::Box),
            (Mode::CapsuleRay, Mode::Box),
            (Mode::Sphere, Mode::Sphere),
            (Mode::CapsuleExact, Mode::Sphere),
        ] {
            let want = pairs(&fixed, Query::new(kind, static_mode, r));
            assert!(!want.is_empty());
            assert_eq!(pairs(&still, Query::new(kind, mode, r)), want, "{kind} swept {mode} at rest");
        }
    }
}

#[test]
fn vv_and_ev_beside_triangles_equal_a_scene_without_them() {
    // A wavy 10 x 10 sheet: its derived edges and vertices as a triangle-less scene.
    let device = Device::cpu().unwrap();
    let n = 10;
    let vertices: Vec<[f32; 3]> = (0..n * n)
        .map(|k| {
            let (u, v) = ((k % n) as f32 / (n - 1) as f32, (k / n) as f32 / (n - 1) as f32);
            [u, v, 0.1 * (9.0 * u).sin() * (7.0 * v).cos()]
        })
        .collect();
    let triangles = grid_triangles(n);
    let mesh_flags = SceneFlags::VT | SceneFlags::EE | SceneFlags::DROP_INCIDENT;
    let all = Scene::new(&device, &SceneDesc::new(&vertices, &triangles).flags(mesh_flags | codim_flags())).unwrap();
    let mesh_only = Scene::new(&device, &SceneDesc::new(&vertices, &triangles)).unwrap();
    let edges = all.edges().unwrap();
    assert_eq!(edges, mesh_only.edges().unwrap());
    let codim = Scene::new(&device, &SceneDesc::codim(&vertices, &edges)).unwrap();
    // EV alone derives the edges from the triangles, as EE does.
    let ev_only =
        Scene::new(&device, &SceneDesc::new(&vertices, &triangles).flags(SceneFlags::EV | SceneFlags::DROP_INCIDENT))
            .unwrap();
    assert_eq!(ev_only.edges().unwrap(), edges);
    let r = 0.13; // beyond the grid spacing (1/9): neighbours pair
    for mode in Mode::ALL {
        for flags in LEAF_FLAGS {
            let (vv, ev) = (Query::vv(mode, r).with_flags(flags), Query::ev(mode, r).with_flags(flags));
            let want_ev = pairs(&codim, ev);
            assert!(!want_ev.is_empty() && !pairs(&codim, vv).is_empty());
            assert_eq!(pairs(&all, vv), pairs(&codim, vv), "VV {mode} {flags:?}");
            assert_eq!(pairs(&all, ev), want_ev, "EV {mode} {flags:?}");
            assert_eq!(pairs(&ev_only, ev), want_ev, "EV-only {mode} {flags:?}");
            assert_eq!(
                pairs(&all, Query::vt(mode, r).with_flags(flags)),
                pairs(&mesh_only, Query::vt(mode, r).with_flags(flags))
            );
            if mode != Mode::Sphere {
                let ee = Query::ee(mode, r).with_flags(flags);
                assert_eq!(pairs(&all, ee), pairs(&mesh_only, ee), "EE {mode} {flags:?}");
            }
        }
    }
}

#[test]
fn every_entry_point_takes_vv_and_ev() {
    let device = Device::cpu().unwrap();
    let mesh = rods_and_particles(10, 8, 16, 40, 1.0, 0.0);
    let vertices = floats(&mesh.vertices);
    let mut scene = Scene::new(&device, &SceneDesc::codim(&vertices, &mesh.edges)).unwrap();
    scene.reserve(minkq::Reserve::REFIT, 4096).unwrap();
    for kind in [QueryKind::Vv, QueryKind::Ev] {
        assert_eq!(kind.name().parse::<QueryKind>().unwrap(), kind);
        let query = Query::new(kind, Mode::Box, 0.05).with_flags(QueryFlags::LEAF_EXACT);
        let want = pairs(&scene, query);
        let n = want.len();
        assert!(n > 10, "{kind}");

        // query_into: exact count on CAPACITY, then the pairs.
        let mut small = vec![[0; 2]; n - 1];
        match scene.query_into(&query, &mut small[..]) {
            Err(Error::Capacity { needed, .. }) => assert_eq!(needed, n as u64, "{kind}"),
            other => panic!("{kind}: {other:?}"),
        }
        let mut exact = vec![[0; 2]; n];
        let info = scene.query_into(&query.with_flags(QueryFlags::DIGEST), PairsOut::from_slice(&mut exact)).unwrap();
        assert_eq!((info.count, exact.clone()), (n as u64, want.clone()), "{kind}: digest implies canonical");
        let digest = info.digest.unwrap();
        let mut buffer = PairBuffer::new().unwrap();
        scene.query(&query.with_flags(QueryFlags::DIGEST), &mut buffer).unwrap();
        assert_eq!(buffer.digest(), digest, "{kind}");
        assert_eq!(scene.work(&query).unwrap().candidates, n as u64, "{kind}");

        // Stream-ordered (on the CPU: run to completion), canonical within the reservation.
        let mut out = vec![[0; 2]; 4096];
        let mut count = 0u64;
        let q = query.with_flags(QueryFlags::CANONICAL);
        scene.query_async(&q, PairsOut::from_slice(&mut out), CountOut::from_mut(&mut count), Stream::null()).unwrap();
        scene.async_status(Stream::null()).unwrap();
        assert_eq!(count, n as u64, "{kind}");
        assert_eq!(&out[..n], want.as_slice(), "{kind}: async");
    }
    // A stream-ordered refit, then the blocking pairs of the moved scene.
    let moved: Vec<[f32; 3]> = vertices.iter().map(|p| [p[0] + 0.01, p[1], p[2]]).collect();
    scene.refit_async(minkq::Buffer::from_slice(&moved), Stream::null()).unwrap();
    scene.async_status(Stream::null()).unwrap();
    let fresh = Scene::new(&device, &SceneDesc::codim(&moved, &mesh.edges)).unwrap();
    assert_eq!(pairs(&scene, Query::ev(Mode::Sphere, 0.05)), pairs(&fresh, Query::ev(Mode::Sphere, 0.05)));
    // The fused call stays VT + EE.
    let (mut a, mut b) = (PairBuffer::new().unwrap(), PairBuffer::new().unwrap());
    let err = scene.query_vt_ee(&Query::vv(Mode::Box, 0.05), &Query::ev(Mode::Box, 0.05), &mut a, &mut b).unwrap_err();
    assert!(matches!(err, Error::InvalidArgument(_)), "{err:?}");
}

#[test]
fn kinds_a_scene_was_built_without_are_refused() {
    let device = Device::cpu().unwrap();
    let vertices = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.05, 0.05, 0.0]];
    let mut out = PairBuffer::new().unwrap();
    let refused = |scene: &Scene, kind: QueryKind, out: &mut PairBuffer| {
        let err = scene.query(&Query::new(kind, Mode::Box, 0.1), out).unwrap_err();
        let name = kind.name().to_uppercase();
        assert_eq!(err, Error::InvalidArgument(format!("{name} query on a scene created without MINKQ_SCENE_{name}")));
    };
    let mesh = Scene::new(&device, &SceneDesc::new(&vertices[..3], &[[0, 1, 2]])).unwrap();
    refused(&mesh, QueryKind::Vv, &mut out);
    refused(&mesh, QueryKind::Ev, &mut out);
    assert!(matches!(mesh.work(&Query::vv(Mode::Box, 0.1)), Err(Error::InvalidArgument(_))));

    // Loose particles: vertices only, VV alone.
    let particles = Scene::new(&device, &SceneDesc::codim(&vertices, &[]).flags(SceneFlags::VV)).unwrap();
    assert_eq!(particles.edge_count(), 0);
    let leaf = QueryFlags::LEAF_EXACT | QueryFlags::CANONICAL;
    assert_eq!(particles.query(&Query::vv(Mode::Sphere, 0.1).with_flags(leaf), &mut out).unwrap(), &[[0, 3]]);
    for kind in [QueryKind::Vt, QueryKind::Ee, QueryKind::Ev] {
        refused(&particles, kind, &mut out);
    }
    let rod = Scene::new(&device, &SceneDesc::codim(&vertices, &[[0, 1]]).flags(SceneFlags::EV)).unwrap();
    assert_eq!(rod.query(&Query::ev(Mode::Box, 0.1).with_flags(leaf), &mut out).unwrap(), &[[0, 0], [1, 0], [3, 0]]);
    refused(&rod, QueryKind::Vv, &mut out);
    refused(&rod, QueryKind::Vt, &mut out);

    // Creation: no kind at all, an edge past the vertices, a NaN; sphere mode stays EE's refusal.
    let none = SceneDesc::codim(&vertices, &[[0, 1]]).flags(SceneFlags::DROP_INCIDENT);
    assert!(matches!(Scene::new(&device, &none), Err(Error::InvalidArgument(m)) if m.contains("MINKQ_SCENE_VV")));
    let err = Scene::new(&device, &SceneDesc::codim(&vertices, &[[0, 4]])).unwrap_err();
    assert!(matches!(err, Error::IndexOutOfRange(_)), "{err:?}");
    let nan = [[0.0f32, 0.0, 0.0], [f32::NAN, 0.0, 0.0]];
    assert!(matches!(Scene::new(&device, &SceneDesc::codim(&nan, &[[0, 1]])), Err(Error::NonFinite(_))));
    let both =
        Scene::new(&device, &SceneDesc::codim(&vertices, &[[0, 1]]).flags(codim_flags() | SceneFlags::EE)).unwrap();
    assert!(matches!(both.query(&Query::ee(Mode::Sphere, 0.1), &mut out), Err(Error::InvalidArgument(_))));
    assert!(both.query(&Query::ev(Mode::Sphere, 0.1), &mut out).is_ok());
    assert!(matches!(both.query(&Query::vv(Mode::Box, -1.0), &mut out), Err(Error::InvalidArgument(_))));
    assert!(matches!(both.query(&Query::ev(Mode::Box, f32::NAN), &mut out), Err(Error::NonFinite(_))));
    assert!(matches!("ve".parse::<QueryKind>(), Err(Error::InvalidArgument(m)) if m.contains("\"vv\" or \"ev\"")));
}
