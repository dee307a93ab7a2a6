//! Which pairs a scene of many geometries (`Scene::from_geometries`) reports, through the safe
//! crate: a cloth over a static body gives exactly the cross and cloth-self pairs of the two
//! meshes concatenated into one mesh, in every kind and mode, with and without leaf-exact; self
//! flags, groups and masks, and worlds choose which geometries pair (each against a control
//! where they do); thickness is a larger reach (uniform thickness t is radius r + 2t) and
//! per-vertex thickness keeps zero false negatives against a brute-force double oracle.
//! Moving geometries, float64, errors and the numbering: geometry_moves.rs.
mod common;
use common::draped::{
    all_kinds, between, cloth, concatenated, every_kind_flags, located, pairs_of, queries, query_kind, renamed,
    without_body_own, Draped, Pairs, ALL_KINDS,
};
use common::oracle::{assert_subset, point_triangle_sq, segment_segment_sq, V};
use common::Rng;

use minkq::{
    Device, Error, GeometryDesc, GeometryFlags, Mode, Query, QueryFlags, QueryKind, Scene, SceneDesc, SceneFlags,
};

#[test]
fn cloth_over_a_static_body_gives_the_concatenated_mesh_pairs_but_the_body_own() {
    // Grids fine enough for each to come within r of itself past its incident elements.
    let draped = Draped::new(24, 24);
    let scene = draped.scene();
    let (whole, _, _) = draped.concatenated(every_kind_flags());
    assert_eq!((scene.vertex_count(), scene.triangle_count()), (whole.vertex_count(), whole.triangle_count()));
    assert_eq!(scene.edges().unwrap(), whole.edges().unwrap(), "edges numbered as the concatenated mesh's");
    let r = 0.04;
    for kind in ALL_KINDS.map(query_kind) {
        for query in queries(kind, r) {
            let got = pairs_of(&scene, &query);
            assert_eq!(got, without_body_own(&scene, kind, pairs_of(&whole, &query)), "{kind} {query:?}");
            let by_geometry = located(&scene, kind, &got);
            let cross = between(&by_geometry, 0, 1).len();
            let cloth_self = between(&by_geometry, 0, 0).len();
            assert!(between(&by_geometry, 1, 1).is_empty(), "{kind}: the body has no self pairs");
            assert_eq!(cross + cloth_self, got.len());
            assert!(cross > 5 && cloth_self > 5, "{kind} {query:?}: {cross} cross, {cloth_self} cloth-self pairs");
        }
    }
}

#[test]
fn self_flags_choose_which_geometries_pair_with_themselves() {
    let draped = Draped::new(24, 28); // body vertices closer than r: VV self pairs too
    let device = Device::cpu().unwrap();
    let r = 0.04;
    // The cloth without self pairs, the body (static) with them.
    let scene = Scene::from_geometries(
        &device,
        &[
            draped.cloth_desc().flags(GeometryFlags::empty()),
            draped.body_desc().flags(GeometryFlags::STATIC | GeometryFlags::SELF | GeometryFlags::DROP_INCIDENT),
        ],
    )
    .unwrap();
    let both = draped.scene();
    let body_alone =
        Scene::new(&device, &SceneDesc::new(&draped.body, &draped.body_triangles).flags(every_kind_flags())).unwrap();
    // The cloth's self pairs with incident ones kept, as a one-mesh scene without DROP_INCIDENT.
    let incident = Scene::from_geometries(&device, &[draped.cloth_desc().flags(GeometryFlags::SELF)]).unwrap();
    let cloth_alone = Scene::new(
        &device,
        &SceneDesc::new(&draped.cloth, &draped.cloth_triangles)
            .flags(SceneFlags::VT | SceneFlags::EE | SceneFlags::VV | SceneFlags::EV),
    )
    .unwrap();
    for kind in ALL_KINDS.map(query_kind) {
        let query = Query::new(kind, Mode::Box, r).with_flags(QueryFlags::LEAF_EXACT);
        let got = located(&scene, kind, &pairs_of(&scene, &query));
        assert!(between(&got, 0, 0).is_empty(), "{kind}: the cloth asked for no self pairs");
        let body_self = between(&got, 1, 1);
        let expected = renamed(&located(&body_alone, kind, &pairs_of(&body_alone, &query)), |_| 1);
        assert_eq!(body_self, expected, "{kind}: the body's self pairs are those of the body alone");
        assert!(!body_self.is_empty(), "{kind}: the body comes near itself");
        let reference = located(&both, kind, &pairs_of(&both, &query));
        assert_eq!(between(&got, 0, 1), between(&reference, 0, 1), "{kind}: the self flags change no cross pair");
        assert_eq!(pairs_of(&incident, &query), pairs_of(&cloth_alone, &query), "{kind}: SELF without DROP_INCIDENT");
    }
}

#[test]
fn groups_and_masks_filter_cross_pairs_both_ways() {
    let draped = Draped::new(10, 12);
    let other = cloth(10, 8); // a second cloth in the same place: it pairs with the first everywhere
    let device = Device::cpu().unwrap();
    let second = GeometryDesc::mesh(&other, &draped.cloth_triangles).kinds(all_kinds()).group(2);
    let query = Query::vt(Mode::Box, 0.03).with_flags(QueryFlags::LEAF_EXACT);
    let cloths_pairs = |first: GeometryDesc<'_>, second: GeometryDesc<'_>| {
        let scene = Scene::from_geometries(&device, &[first, second, draped.body_desc().group(4)]).unwrap();
        let all = located(&scene, QueryKind::Vt, &pairs_of(&scene, &query));
        (between(&all, 0, 1), between(&all, 0, 2), between(&all, 1, 2))
    };
    let open = cloths_pairs(draped.cloth_desc(), second);
    assert!(!open.0.is_empty() && !open.1.is_empty() && !open.2.is_empty());
    // The first cloth's mask leaves out group 2: no pair between the cloths, though the
    // second's mask takes the first's group; the body still pairs with both.
    let masked = cloths_pairs(draped.cloth_desc().mask(!2), second);
    assert!(masked.0.is_empty());
    assert_eq!((&masked.1, &masked.2), (&open.1, &open.2));
    // The same from the other side.
    let masked = cloths_pairs(draped.cloth_desc(), second.mask(!1));
    assert!(masked.0.is_empty());
    assert_eq!((&masked.1, &masked.2), (&open.1, &open.2));
    // A body whose mask takes group 1 only pairs with the first cloth alone.
    let scene =
        Scene::from_geometries(&device, &[draped.cloth_desc(), second, draped.body_desc().group(4).mask(1)]).unwrap();
    let all = located(&scene, QueryKind::Vt, &pairs_of(&scene, &query));
    assert_eq!((between(&all, 0, 2), between(&all, 1, 2).len()), (open.1.clone(), 0));
}

#[test]
fn worlds_never_pair_across_and_none_is_every_world() {
    let draped = Draped::new(10, 12);
    let device = Device::cpu().unwrap();
    let query = Query::ee(Mode::Box, 0.03).with_flags(QueryFlags::LEAF_EXACT);
    let world_pairs = |w0: Option<u32>, w1: Option<u32>, body: Option<u32>| {
        let geometries = [draped.cloth_desc().world(w0), draped.cloth_desc().world(w1), draped.body_desc().world(body)];
        let scene = Scene::from_geometries(&device, &geometries).unwrap();
        let all = located(&scene, QueryKind::Ee, &pairs_of(&scene, &query));
        (between(&all, 0, 1), between(&all, 0, 2), between(&all, 1, 2), between(&all, 0, 0), between(&all, 1, 1))
    };
    // Two copies of the cloth in one place: in one world they pair everywhere.
    let same = world_pairs(Some(0), Some(0), Some(0));
    assert!(!same.0.is_empty() && !same.1.is_empty());
    assert_eq!(same.2, renamed(&same.1, |g| if g == 0 { 1 } else { g }));
    // In two worlds they never pair; the body of every world pairs with each, as each one's
    // own self pairs stay.
    let apart = world_pairs(Some(0), Some(1), None);
    assert!(apart.0.is_empty());
    assert_eq!((&apart.1, &apart.2, &apart.3, &apart.4), (&same.1, &same.2, &same.3, &same.4));
    // A body of world 1 pairs with world 1's cloth only; a cloth of every world with both.
    let one = world_pairs(Some(0), Some(1), Some(1));
    assert!(one.1.is_empty() && one.2 == same.2 && one.0.is_empty());
    let every = world_pairs(None, Some(1), Some(0));
    assert_eq!((&every.0, &every.1), (&same.0, &same.1));
    assert!(every.2.is_empty());
    // World ids are int32 in the C API.
    let err = Scene::from_geometries(&device, &[draped.cloth_desc().world(u32::MAX)]).unwrap_err();
    assert_eq!(
        err,
        Error::InvalidArgument("geometry 0: world 4294967295 is over i32::MAX, the largest world id".into())
    );
    Scene::from_geometries(&device, &[draped.cloth_desc().world(i32::MAX as u32)]).unwrap();
}

#[test]
fn uniform_thickness_t_is_radius_r_plus_2t() {
    let draped = Draped::new(12, 16);
    let device = Device::cpu().unwrap();
    let (r, t) = (0.015625f32, 0.0078125f32); // sums exact in float
    let cloth_t = vec![t; draped.cloth.len()];
    let body_t = vec![t; draped.body.len()];
    let thick = Scene::from_geometries(
        &device,
        &[draped.cloth_desc().thickness(&cloth_t), draped.body_desc().thickness(&body_t)],
    )
    .unwrap();
    let thin = draped.scene();
    for kind in ALL_KINDS.map(query_kind) {
        for flags in [QueryFlags::empty(), QueryFlags::LEAF_EXACT] {
            let with_t = pairs_of(&thick, &Query::new(kind, Mode::Box, r).with_flags(flags));
            let wider = pairs_of(&thin, &Query::new(kind, Mode::Box, r + 2.0 * t).with_flags(flags));
            assert_eq!(with_t, wider, "{kind} {flags:?}");
            let without = pairs_of(&thin, &Query::new(kind, Mode::Box, r).with_flags(flags));
            assert!(without.len() < with_t.len(), "{kind} {flags:?}: thickness must reach further here");
        }
    }
}

/// The true contacts of the draped scene with thickness: cross pairs and the cloth's own
/// (incident ones dropped), reach r + t(a) + t(b), brute force in double; global ids.
struct Truth {
    vertices: Vec<V>,
    thickness: Vec<f64>,
    triangles: Vec<[i32; 3]>,
    edges: Vec<[i32; 2]>,
    cloth_vertices: i32,
}

impl Truth {
    fn reach<const N: usize>(&self, element: [i32; N]) -> f64 {
        element.iter().map(|&v| self.thickness[v as usize]).fold(0.0, f64::max)
    }

    /// Pairs of `a` and `b` are looked for: a cloth element on either side, not incident.
    fn wanted<const N: usize, const M: usize>(&self, a: [i32; N], b: [i32; M]) -> bool {
        let in_cloth = |e: &[i32]| e.iter().all(|&v| v < self.cloth_vertices);
        (in_cloth(&a) || in_cloth(&b)) && !a.iter().any(|v| b.contains(v))
    }

    fn v(&self, i: i32) -> V {
        self.vertices[i as usize]
    }

    fn vt(&self, r: f64) -> Pairs {
        let mut out = Pairs::new();
        for p in 0..self.vertices.len() as i32 {
            for (t, &tri) in self.triangles.iter().enumerate() {
                let reach = r + self.reach([p]) + self.reach(tri);
                if self.wanted([p], tri)
                    && point_triangle_sq(self.v(p), self.v(tri[0]), self.v(tri[1]), self.v(tri[2])) <= reach * reach
                {
                    out.insert([p, t as i32]);
                }
            }
        }
        out
    }

    fn ee(&self, r: f64) -> Pairs {
        let mut out = Pairs::new();
        for (e, &a) in self.edges.iter().enumerate() {
            for (f, &b) in self.edges.iter().enumerate().skip(e + 1) {
                let reach = r + self.reach(a) + self.reach(b);
                if self.wanted(a, b)
                    && segment_segment_sq(self.v(a[0]), self.v(a[1]), self.v(b[0]), self.v(b[1])) <= reach * reach
                {
                    out.insert([e as i32, f as i32]);
                }
            }
        }
        out
    }
}

#[test]
fn per_vertex_thickness_has_no_false_negatives_against_the_double_oracle() {
    let draped = Draped::new(9, 11);
    let r = 0.01f32;
    let mut rng = Rng(5);
    // From 0 to several r, on both geometries.
    let cloth_t: Vec<f32> = draped.cloth.iter().map(|_| (4.0 * r as f64 * rng.uniform()) as f32).collect();
    let body_t: Vec<f32> = draped.body.iter().map(|_| (2.0 * r as f64 * rng.uniform()) as f32).collect();
    let scene = Scene::from_geometries(
        &Device::cpu().unwrap(),
        &[draped.cloth_desc().thickness(&cloth_t), draped.body_desc().thickness(&body_t)],
    )
    .unwrap();
    let truth = Truth {
        vertices: draped.cloth.iter().chain(&draped.body).map(|p| p.map(f64::from)).collect(),
        thickness: cloth_t.iter().chain(&body_t).map(|&t| t as f64).collect(),
        triangles: concatenated(&[(&draped.cloth, &draped.cloth_triangles), (&draped.body, &draped.body_triangles)]).1,
        edges: scene.edges().unwrap(),
        cloth_vertices: draped.cloth.len() as i32,
    };
    for (kind, contacts, loose) in [
        (QueryKind::Vt, truth.vt(r as f64), truth.vt(r as f64 + 1e-5)),
        (QueryKind::Ee, truth.ee(r as f64), truth.ee(r as f64 + 1e-5)),
    ] {
        assert!(contacts.len() > 20, "{kind}: the scene must have contacts, has {}", contacts.len());
        for query in queries(kind, r) {
            let got = pairs_of(&scene, &query);
            assert_subset(&contacts, &got, &format!("{kind} {query:?}: true contacts"));
            if query.flags.contains(QueryFlags::LEAF_EXACT) {
                assert_subset(&got, &loose, &format!("{kind} {query:?}: leaf-exact pairs within reach"));
            }
        }
    }
}
