//! The scenes of the geometry tests: a wavy cloth over a bumpy static body, as two geometries
//! of one scene and as one concatenated mesh; and the pairs of such scenes by geometry.
use std::collections::BTreeSet;

use super::{grid_triangles, Rng};
use minkq::{
    Device, GeometryDesc, GeometryFlags, Kinds, Mode, PairBuffer, Query, QueryFlags, QueryKind, Scene, SceneDesc,
    SceneFlags,
};

pub type Pairs = BTreeSet<[i32; 2]>;
/// A pair as ((geometry, local id), (geometry, local id)).
pub type Located = BTreeSet<[(u32, usize); 2]>;

pub const ALL_KINDS: [Kinds; 4] = [Kinds::VT, Kinds::EE, Kinds::VV, Kinds::EV];

pub fn all_kinds() -> Kinds {
    Kinds::VT | Kinds::EE | Kinds::VV | Kinds::EV
}

/// A grid of n x n vertices over [lo, hi]^2 at height `z(u, v)` (u, v in [0, 1]), jittered by
/// `jitter` in every coordinate.
pub fn sheet(n: i32, lo: f64, hi: f64, seed: u64, jitter: f64, z: impl Fn(f64, f64) -> f64) -> Vec<[f32; 3]> {
    let mut rng = Rng(seed);
    let mut out = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let (u, v) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
            let mut p = [lo + (hi - lo) * u, lo + (hi - lo) * v, z(u, v)];
            for c in &mut p {
                *c += jitter * (rng.uniform() - 0.5);
            }
            out.push(p.map(|c| c as f32));
        }
    }
    out
}

/// A wavy cloth over [0.1, 0.9]^2 that dips to the body in places.
pub fn cloth(n: i32, seed: u64) -> Vec<[f32; 3]> {
    sheet(n, 0.1, 0.9, seed, 0.01, |u, v| 0.06 + 0.04 * (7.0 * u).sin() * (5.0 * v).cos())
}

/// A bumpy body surface over [0, 1]^2.
pub fn body(n: i32) -> Vec<[f32; 3]> {
    sheet(n, 0.0, 1.0, 99, 0.0, |u, v| 0.02 * (9.0 * u + 1.0).sin() * (8.0 * v).sin())
}

/// A mesh's vertices and triangles.
pub type MeshSlices<'a> = (&'a [[f32; 3]], &'a [[i32; 3]]);

/// The meshes concatenated, as the global numbering orders them.
pub fn concatenated(parts: &[MeshSlices<'_>]) -> (Vec<[f32; 3]>, Vec<[i32; 3]>) {
    let (mut vertices, mut triangles) = (Vec::new(), Vec::new());
    for (v, t) in parts {
        let offset = vertices.len() as i32;
        triangles.extend(t.iter().map(|tri| tri.map(|i| i + offset)));
        vertices.extend_from_slice(v);
    }
    (vertices, triangles)
}

pub fn query_kind(kind: Kinds) -> QueryKind {
    QueryKind::ALL.into_iter().find(|&k| Kinds::from(k) == kind).unwrap()
}

/// Every query of `kind` worth comparing: each mode it takes, with and without leaf-exact.
pub fn queries(kind: QueryKind, r: f32) -> Vec<Query> {
    let mut out = Vec::new();
    for mode in Mode::ALL {
        if kind == QueryKind::Ee && mode == Mode::Sphere {
            continue;
        }
        for flags in [QueryFlags::empty(), QueryFlags::LEAF_EXACT] {
            out.push(Query::new(kind, mode, r).with_flags(flags));
        }
    }
    out
}

pub fn pairs_of(scene: &Scene, query: &Query) -> Pairs {
    scene.query(query, &mut PairBuffer::new().unwrap()).unwrap().iter().copied().collect()
}

pub fn located(scene: &Scene, kind: QueryKind, pairs: &Pairs) -> Located {
    pairs.iter().map(|&p| scene.locate_pair(kind, p).unwrap_or_else(|| panic!("{p:?} out of range"))).collect()
}

/// The pairs between geometries a and b (a == b: self pairs), as (geometry, local id) each.
pub fn between(all: &Located, a: u32, b: u32) -> Located {
    all.iter().filter(|[x, y]| (x.0 == a && y.0 == b) || (x.0 == b && y.0 == a)).copied().collect()
}

/// The same pairs with geometry ids renamed by `rename`.
pub fn renamed(pairs: &Located, rename: impl Fn(u32) -> u32) -> Located {
    pairs.iter().map(|[x, y]| [(rename(x.0), x.1), (rename(y.0), y.1)]).collect()
}

/// The cloth (n x n) and the body (m x m), and the cloth-over-static-body scene of them.
pub struct Draped {
    pub cloth: Vec<[f32; 3]>,
    pub cloth_triangles: Vec<[i32; 3]>,
    pub body: Vec<[f32; 3]>,
    pub body_triangles: Vec<[i32; 3]>,
}

impl Draped {
    pub fn new(n: i32, m: i32) -> Draped {
        Draped {
            cloth: cloth(n, 7),
            cloth_triangles: grid_triangles(n),
            body: body(m),
            body_triangles: grid_triangles(m),
        }
    }

    pub fn cloth_desc(&self) -> GeometryDesc<'_> {
        GeometryDesc::mesh(&self.cloth, &self.cloth_triangles).kinds(all_kinds())
    }

    pub fn body_desc(&self) -> GeometryDesc<'_> {
        GeometryDesc::mesh(&self.body, &self.body_triangles).kinds(all_kinds()).flags(GeometryFlags::STATIC)
    }

    pub fn scene(&self) -> Scene {
        Scene::from_geometries(&Device::cpu().unwrap(), &[self.cloth_desc(), self.body_desc()]).unwrap()
    }

    /// The one-mesh scene of cloth then body.
    pub fn concatenated(&self, flags: SceneFlags) -> (Scene, Vec<[f32; 3]>, Vec<[i32; 3]>) {
        let (vertices, triangles) =
            concatenated(&[(&self.cloth, &self.cloth_triangles), (&self.body, &self.body_triangles)]);
        let scene = Scene::new(&Device::cpu().unwrap(), &SceneDesc::new(&vertices, &triangles).flags(flags)).unwrap();
        (scene, vertices, triangles)
    }
}

/// The pairs of `kind` of the concatenated mesh of `draped`'s geometries, less those of two
/// body elements: what the draped scene (a static body without self pairs) reports.
pub fn without_body_own(draped: &Scene, kind: QueryKind, concatenated: Pairs) -> Pairs {
    let cloth_ends = kind.elements().map(|e| draped.geometry_range(0, e).unwrap().end as i32);
    concatenated.into_iter().filter(|p| p[0] < cloth_ends[0] || p[1] < cloth_ends[1]).collect()
}

/// The one-mesh flags of every kind, incident pairs dropped.
pub fn every_kind_flags() -> SceneFlags {
    SceneFlags::VT | SceneFlags::EE | SceneFlags::VV | SceneFlags::EV | SceneFlags::DROP_INCIDENT
}
