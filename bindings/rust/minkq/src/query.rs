use std::fmt;
use std::ops::{BitOr, BitOrAssign};
use std::str::FromStr;

use crate::error::Error;
use crate::geometry::Element;
use crate::sys;

/// What a mesh query pairs up: VT and EE for triangle meshes, VV and EV for codimensional
/// elements (particles, rods, yarn). Each needs the scene flag of the same name
/// ([`SceneFlags::VT`], [`SceneFlags::EE`], [`SceneFlags::VV`], [`SceneFlags::EV`]).
///
/// ```
/// use minkq::QueryKind;
/// assert_eq!("ee".parse::<QueryKind>()?, QueryKind::Ee);
/// assert_eq!(QueryKind::Vt.name(), "vt");
/// assert_eq!(QueryKind::ALL.map(|k| k.name()), ["vt", "ee", "vv", "ev"]);
/// # Ok::<(), minkq::Error>(())
/// ```
///
/// Non-exhaustive: kinds may be added (VV and EV came after VT and EE), so a `match` on a
/// kind needs a wildcard arm.
///
/// ```compile_fail
/// fn pairs_up(kind: minkq::QueryKind) -> &'static str {
///     match kind {
///         minkq::QueryKind::Vt | minkq::QueryKind::Vv | minkq::QueryKind::Ev => "a vertex and an element",
///         minkq::QueryKind::Ee => "two edges",
///     } // error: non-exhaustive patterns
/// }
/// ```
#[non_exhaustive]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum QueryKind {
    /// Pairs (vertex, triangle): the vertex lies within r of the triangle (a sphere query).
    Vt,
    /// Pairs (e, f) with e < f: edge e lies within r of edge f (a capsule query).
    Ee,
    /// Pairs (v, w) with v < w: vertex v lies within r of vertex w (a sphere query; each pair
    /// once). Vertices sharing an edge are pairs too: [`SceneFlags::DROP_INCIDENT`] drops none.
    Vv,
    /// Pairs (vertex, edge): the vertex lies within r of the edge (a sphere query). With
    /// [`SceneFlags::DROP_INCIDENT`], a vertex is not paired with its own edges.
    Ev,
}

/// The node test, from fast to tight. For every finite input the pairs nest:
/// true contacts ⊆ `CapsuleExact` ⊆ `CapsuleRay` ⊆ `Box` (EE) and
/// true contacts ⊆ `Sphere` ⊆ `Box` (VT, VV, EV); [`QueryFlags::LEAF_EXACT`] keeps, of any
/// mode's pairs, the true contacts (use it with `Box`). Points are zero-length capsules: for
/// VT, VV and EV, `CapsuleRay` is the box test and `CapsuleExact` the sphere test.
///
/// ```
/// use minkq::Mode;
/// assert_eq!("capsule_exact".parse::<Mode>()?, Mode::CapsuleExact);
/// assert_eq!(Mode::ALL.map(|m| m.name()), ["box", "sphere", "capsule_ray", "capsule_exact"]);
/// # Ok::<(), minkq::Error>(())
/// ```
///
/// Non-exhaustive: modes may be added, so a `match` on a mode needs a wildcard arm.
///
/// ```compile_fail
/// fn tight(mode: minkq::Mode) -> bool {
///     match mode {
///         minkq::Mode::Box | minkq::Mode::CapsuleRay => false,
///         minkq::Mode::Sphere | minkq::Mode::CapsuleExact => true,
///     } // error: non-exhaustive patterns
/// }
/// ```
#[non_exhaustive]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Mode {
    /// The r-padded box of the query element against node boxes.
    Box,
    /// Point–box distance (point queries only: VT, VV, EV and spheres).
    Sphere,
    /// Segment against the r-inflated box (slab test).
    CapsuleRay,
    /// Segment–box distance.
    CapsuleExact,
}

impl QueryKind {
    /// Every kind, in the C enum's order.
    ///
    /// ```
    /// assert_eq!(minkq::QueryKind::ALL.len(), 4);
    /// ```
    pub const ALL: [QueryKind; 4] = [QueryKind::Vt, QueryKind::Ee, QueryKind::Vv, QueryKind::Ev];

    /// `"vt"`, `"ee"`, `"vv"` or `"ev"`.
    ///
    /// ```
    /// assert_eq!(minkq::QueryKind::Ee.name(), "ee");
    /// assert_eq!(minkq::QueryKind::Ev.to_string(), "ev");
    /// ```
    pub fn name(self) -> &'static str {
        match self {
            QueryKind::Vt => "vt",
            QueryKind::Ee => "ee",
            QueryKind::Vv => "vv",
            QueryKind::Ev => "ev",
        }
    }

    /// The scene flag a query of this kind needs.
    ///
    /// ```
    /// use minkq::{QueryKind, SceneFlags};
    /// assert_eq!(QueryKind::Ev.scene_flag(), SceneFlags::EV);
    /// ```
    pub fn scene_flag(self) -> SceneFlags {
        match self {
            QueryKind::Vt => SceneFlags::VT,
            QueryKind::Ee => SceneFlags::EE,
            QueryKind::Vv => SceneFlags::VV,
            QueryKind::Ev => SceneFlags::EV,
        }
    }

    /// The elements a pair of this kind joins, in the pair's order: (vertex, triangle) for
    /// VT, (edge, edge) for EE, (vertex, vertex) for VV, (vertex, edge) for EV. With
    /// [`Scene::locate_pair`](crate::Scene::locate_pair) it maps a pair's global ids back to
    /// geometries.
    ///
    /// ```
    /// use minkq::{Element, QueryKind};
    /// assert_eq!(QueryKind::Vt.elements(), [Element::Vertex, Element::Triangle]);
    /// assert_eq!(QueryKind::Ev.elements(), [Element::Vertex, Element::Edge]);
    /// ```
    pub fn elements(self) -> [Element; 2] {
        match self {
            QueryKind::Vt => [Element::Vertex, Element::Triangle],
            QueryKind::Ee => [Element::Edge, Element::Edge],
            QueryKind::Vv => [Element::Vertex, Element::Vertex],
            QueryKind::Ev => [Element::Vertex, Element::Edge],
        }
    }

    pub(crate) fn raw(self) -> sys::minkq_query_kind {
        match self {
            QueryKind::Vt => sys::MINKQ_QUERY_VT,
            QueryKind::Ee => sys::MINKQ_QUERY_EE,
            QueryKind::Vv => sys::MINKQ_QUERY_VV,
            QueryKind::Ev => sys::MINKQ_QUERY_EV,
        }
    }
}

impl Mode {
    /// Every mode, from fast to tight.
    ///
    /// ```
    /// assert_eq!(minkq::Mode::ALL.len(), 4);
    /// ```
    pub const ALL: [Mode; 4] = [Mode::Box, Mode::Sphere, Mode::CapsuleRay, Mode::CapsuleExact];

    /// `"box"`, `"sphere"`, `"capsule_ray"` or `"capsule_exact"`.
    ///
    /// ```
    /// assert_eq!(minkq::Mode::CapsuleRay.name(), "capsule_ray");
    /// ```
    pub fn name(self) -> &'static str {
        match self {
            Mode::Box => "box",
            Mode::Sphere => "sphere",
            Mode::CapsuleRay => "capsule_ray",
            Mode::CapsuleExact => "capsule_exact",
        }
    }

    pub(crate) fn raw(self) -> sys::minkq_mode {
        match self {
            Mode::Box => sys::MINKQ_MODE_BOX,
            Mode::Sphere => sys::MINKQ_MODE_SPHERE,
            Mode::CapsuleRay => sys::MINKQ_MODE_CAPSULE_RAY,
            Mode::CapsuleExact => sys::MINKQ_MODE_CAPSULE_EXACT,
        }
    }
}

impl FromStr for QueryKind {
    type Err = Error;
    /// Parses a kind's [`name`](QueryKind::name).
    fn from_str(s: &str) -> Result<Self, Error> {
        QueryKind::ALL.into_iter().find(|k| k.name() == s).ok_or_else(|| {
            Error::InvalidArgument(format!("unknown query kind {s:?} (use \"vt\", \"ee\", \"vv\" or \"ev\")"))
        })
    }
}

impl FromStr for Mode {
    type Err = Error;
    /// Parses a mode's [`name`](Mode::name).
    fn from_str(s: &str) -> Result<Self, Error> {
        Mode::ALL.into_iter().find(|m| m.name() == s).ok_or_else(|| {
            Error::InvalidArgument(format!(
                "unknown mode {s:?} (use \"box\", \"sphere\", \"capsule_ray\" or \"capsule_exact\")"
            ))
        })
    }
}

impl fmt::Display for QueryKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl fmt::Display for Mode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

macro_rules! flags {
    ($(#[$doc:meta])* $name:ident { $($(#[$fdoc:meta])* $flag:ident = $value:expr;)* }) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
        pub struct $name(u32);

        impl $name {
            $(
                $(#[$fdoc])*
                ///
                /// ```
                #[doc = concat!("assert_eq!(minkq::", stringify!($name), "::", stringify!($flag), ".bits(), minkq::", stringify!($value), ");")]
                /// ```
                pub const $flag: $name = $name($value as u32);
            )*

            /// No flag set.
            ///
            /// ```
            #[doc = concat!("assert_eq!(minkq::", stringify!($name), "::empty().bits(), 0);")]
            /// ```
            pub const fn empty() -> $name {
                $name(0)
            }

            /// The C bit mask.
            ///
            /// ```
            #[doc = concat!("let all = ", $("minkq::", stringify!($name), "::", stringify!($flag), " | ",)* "minkq::", stringify!($name), "::empty();")]
            #[doc = concat!("assert_eq!(all.bits(), 0", $(" | minkq::", stringify!($value),)* ");")]
            /// ```
            pub const fn bits(self) -> u32 {
                self.0
            }

            /// Whether every flag of `other` is set in `self`.
            ///
            /// ```
            #[doc = concat!("use minkq::", stringify!($name), ";")]
            #[doc = concat!("assert!(!", stringify!($name), "::empty().contains(", $(stringify!($name), "::", stringify!($flag), " | ",)* stringify!($name), "::empty()));")]
            /// ```
            pub const fn contains(self, other: $name) -> bool {
                self.0 & other.0 == other.0
            }
        }

        impl BitOr for $name {
            type Output = $name;
            fn bitor(self, other: $name) -> $name {
                $name(self.0 | other.0)
            }
        }

        impl BitOrAssign for $name {
            fn bitor_assign(&mut self, other: $name) {
                self.0 |= other.0;
            }
        }
    };
}
// The geometry flags and kinds (geometry.rs) are flag types of the same shape.
pub(crate) use flags;

flags! {
    /// What a scene is built for (`minkq_scene_flags`): at least one of `VT`, `EE`, `VV` and
    /// `EV`.
    ///
    /// ```
    /// use minkq::SceneFlags;
    /// let flags = SceneFlags::VT | SceneFlags::EE;
    /// assert!(flags.contains(SceneFlags::EE) && !flags.contains(SceneFlags::DROP_INCIDENT));
    /// let rods = SceneFlags::VV | SceneFlags::EV | SceneFlags::DROP_INCIDENT;
    /// assert!(rods.contains(SceneFlags::EV) && !rods.contains(SceneFlags::VT));
    /// ```
    SceneFlags {
        /// Build the triangle tree for vertex–triangle queries.
        VT = sys::MINKQ_SCENE_VT;
        /// Build the edge tree for edge–edge queries.
        EE = sys::MINKQ_SCENE_EE;
        /// Drop (v, t) with v a vertex of t, pairs of edges sharing a vertex, and (v, e) with
        /// v a vertex of e. VV pairs are never incident: it drops none of them.
        DROP_INCIDENT = sys::MINKQ_SCENE_DROP_INCIDENT;
        /// Vertices are 3 doubles (`[f64; 3]`, byte stride >= 24) at creation and in every
        /// refit and rebuild, blocking and stream-ordered. The scene rounds them to nearest
        /// float (the precision of its trees and tests) and widens every query radius by
        /// 2 rho, rho the farthest the rounding moved a vertex, so that every pair within r in
        /// double is reported, in every mode; extras lie within r + 2 rho (plus the float
        /// slack). A double beyond the float range (about 3.4e38) is
        /// [`Error::NonFinite`](crate::Error::NonFinite), as a NaN is.
        /// A [`SceneDesc`](crate::SceneDesc) of `[f64; 3]` vertices
        /// ([`SceneDesc::new_f64`](crate::SceneDesc::new_f64)) implies it;
        /// [`SceneBuffers`](crate::SceneBuffers) take it in their flags.
        FLOAT64 = sys::MINKQ_SCENE_FLOAT64;
        /// Build the vertex tree for vertex–vertex queries (codimensional elements: particles,
        /// rod and yarn vertices). A scene for VV alone needs vertices only.
        VV = sys::MINKQ_SCENE_VV;
        /// Build the edge tree for edge–vertex queries (rods, yarn): from the given edges, or,
        /// when none are given, those derived from the triangles.
        EV = sys::MINKQ_SCENE_EV;
    }
}

flags! {
    /// Query options (`minkq_query_flags`).
    ///
    /// ```
    /// use minkq::QueryFlags;
    /// let flags = QueryFlags::LEAF_EXACT | QueryFlags::DIGEST;
    /// assert_eq!(flags.bits(), 5);
    /// ```
    QueryFlags {
        /// Primitive distance test at the leaves: candidates are the true contacts (plus, at
        /// most, pairs within r + 2^-19 S). Mesh scenes only. Meant for [`Mode::Box`]: once the
        /// leaves test distances, the finer node tests cost more than they save (measured in
        /// `docs/design-notes.md`).
        LEAF_EXACT = sys::MINKQ_QUERY_LEAF_EXACT;
        /// Pairs sorted lexicographically.
        CANONICAL = sys::MINKQ_QUERY_CANONICAL;
        /// xxHash64 (seed 0) of the canonical little-endian int32 pairs; implies `CANONICAL`.
        DIGEST = sys::MINKQ_QUERY_DIGEST;
        /// Count the traversal's work into [`QueryInfo::stats`] (a separately compiled
        /// traversal: without the flag the counters cost nothing).
        STATS = sys::MINKQ_QUERY_STATS;
        /// Count the pairs only: [`QueryInfo::count`] is exact and nothing is written (the
        /// buffer is ignored, never [`Error::Capacity`](crate::Error::Capacity)); cheaper
        /// than storing them. Not with `CANONICAL` or `DIGEST`. [`Scene::count`](crate::Scene::count)
        /// and [`Bvh::count`](crate::Bvh::count) ask for it.
        COUNT = sys::MINKQ_QUERY_COUNT;
    }
}

flags! {
    /// The scratch [`Scene::reserve`](crate::Scene::reserve) reserves for a scene's
    /// asynchronous calls (`minkq_reserve_flags`), so that they never allocate.
    ///
    /// ```
    /// use minkq::Reserve;
    /// let both = Reserve::REFIT | Reserve::REBUILD;
    /// assert!(both.contains(Reserve::REBUILD) && !Reserve::REFIT.contains(Reserve::REBUILD));
    /// assert_eq!((Reserve::REFIT | Reserve::SWEPT).bits(), 5);
    /// ```
    Reserve {
        /// Scratch for [`Scene::refit_async`](crate::Scene::refit_async) (a copy of the
        /// vertices) and the pending error.
        REFIT = sys::MINKQ_RESERVE_REFIT;
        /// Also the tree builds' scratch (about the trees' size again), for
        /// [`Scene::rebuild_async`](crate::Scene::rebuild_async).
        REBUILD = sys::MINKQ_RESERVE_REBUILD;
        /// With `REFIT` or `REBUILD`: the swept calls' second positions and their staging (two
        /// more copies of the vertices), for
        /// [`Scene::refit_swept_async`](crate::Scene::refit_swept_async) (`REFIT | SWEPT`) and
        /// [`Scene::rebuild_swept_async`](crate::Scene::rebuild_swept_async)
        /// (`REBUILD | SWEPT`).
        SWEPT = sys::MINKQ_RESERVE_SWEPT;
    }
}

/// A mesh query: kind, mode, flags and radius (`minkq_query_desc`).
///
/// ```
/// use minkq::{Mode, Query, QueryFlags, QueryKind};
/// let q = Query::ee(Mode::CapsuleExact, 0.01).with_flags(QueryFlags::LEAF_EXACT);
/// assert_eq!((q.kind, q.mode, q.radius), (QueryKind::Ee, Mode::CapsuleExact, 0.01));
/// assert!(q.flags.contains(QueryFlags::LEAF_EXACT));
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Query {
    /// VT, EE, VV or EV.
    pub kind: QueryKind,
    /// The node test.
    pub mode: Mode,
    /// Leaf-exact, canonical order, digest.
    pub flags: QueryFlags,
    /// r: finite and >= 0.
    pub radius: f32,
}

impl Query {
    /// A query of `kind` in `mode` with radius `radius` and no flags.
    ///
    /// ```
    /// use minkq::{Mode, Query, QueryKind};
    /// assert_eq!(Query::new(QueryKind::Vt, Mode::Sphere, 0.5), Query::vt(Mode::Sphere, 0.5));
    /// ```
    pub fn new(kind: QueryKind, mode: Mode, radius: f32) -> Query {
        Query { kind, mode, flags: QueryFlags::empty(), radius }
    }

    /// A vertex–triangle query.
    ///
    /// ```
    /// let q = minkq::Query::vt(minkq::Mode::Sphere, 0.1);
    /// assert_eq!(q.kind, minkq::QueryKind::Vt);
    /// ```
    pub fn vt(mode: Mode, radius: f32) -> Query {
        Query::new(QueryKind::Vt, mode, radius)
    }

    /// An edge–edge query.
    ///
    /// ```
    /// let q = minkq::Query::ee(minkq::Mode::CapsuleRay, 0.1);
    /// assert_eq!(q.kind, minkq::QueryKind::Ee);
    /// ```
    pub fn ee(mode: Mode, radius: f32) -> Query {
        Query::new(QueryKind::Ee, mode, radius)
    }

    /// A vertex–vertex query: pairs (v, w), v < w, of vertices within r, on a scene built with
    /// [`SceneFlags::VV`]. Points are zero-length capsules: [`Mode::CapsuleRay`] is
    /// [`Mode::Box`] and [`Mode::CapsuleExact`] is [`Mode::Sphere`].
    ///
    /// ```
    /// use minkq::{Device, Mode, PairBuffer, Query, QueryFlags, Scene, SceneDesc, SceneFlags};
    /// // Three loose particles: a scene of vertices only.
    /// let particles = [[0.0, 0.0, 0.0], [0.05, 0.0, 0.0], [1.0, 1.0, 1.0]];
    /// let desc = SceneDesc::codim(&particles, &[]).flags(SceneFlags::VV);
    /// let scene = Scene::new(&Device::cpu()?, &desc)?;
    /// let q = Query::vv(Mode::Sphere, 0.1).with_flags(QueryFlags::LEAF_EXACT);
    /// assert_eq!(q.kind, minkq::QueryKind::Vv);
    /// assert_eq!(scene.query(&q, &mut PairBuffer::new()?)?, &[[0, 1]]);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn vv(mode: Mode, radius: f32) -> Query {
        Query::new(QueryKind::Vv, mode, radius)
    }

    /// An edge–vertex query: pairs (vertex, edge) of a vertex within r of an edge, on a scene
    /// built with [`SceneFlags::EV`] (without the vertex's own edges when it has
    /// [`SceneFlags::DROP_INCIDENT`]). Modes as for [`Query::vv`].
    ///
    /// ```
    /// use minkq::{Device, Mode, PairBuffer, Query, QueryFlags, Scene, SceneDesc};
    /// // A rod of two edges along x, and a particle 0.05 above its middle vertex.
    /// let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [1.0, 0.05, 0.0]];
    /// let edges = [[0, 1], [1, 2]];
    /// let scene = Scene::new(&Device::cpu()?, &SceneDesc::codim(&vertices, &edges))?;
    /// let q = Query::ev(Mode::Box, 0.1).with_flags(QueryFlags::LEAF_EXACT | QueryFlags::CANONICAL);
    /// assert_eq!(q.kind, minkq::QueryKind::Ev);
    /// // The particle near both edges; vertex 1 is on both, but they are its own (dropped).
    /// assert_eq!(scene.query(&q, &mut PairBuffer::new()?)?, &[[3, 0], [3, 1]]);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn ev(mode: Mode, radius: f32) -> Query {
        Query::new(QueryKind::Ev, mode, radius)
    }

    /// The same query with `flags` added.
    ///
    /// ```
    /// use minkq::{Mode, Query, QueryFlags};
    /// let q = Query::vt(Mode::Sphere, 0.1).with_flags(QueryFlags::CANONICAL).with_flags(QueryFlags::DIGEST);
    /// assert_eq!(q.flags, QueryFlags::CANONICAL | QueryFlags::DIGEST);
    /// ```
    pub fn with_flags(mut self, flags: QueryFlags) -> Query {
        self.flags |= flags;
        self
    }

    pub(crate) fn raw(&self) -> sys::minkq_query_desc {
        sys::minkq_query_desc {
            kind: self.kind.raw(),
            mode: self.mode.raw(),
            flags: self.flags.bits(),
            radius: self.radius,
        }
    }
}

/// What a query into a caller's buffer reports.
///
/// ```
/// # use minkq::*;
/// # let device = Device::cpu()?;
/// # let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]];
/// # let triangles = [[0, 1, 2], [3, 4, 5]];
/// # let scene = Scene::new(&device, &SceneDesc::new(&vertices, &triangles))?;
/// let mut pairs = [[0i32; 2]; 16];
/// let info = scene.query_into(&Query::vt(Mode::Sphere, 0.2).with_flags(QueryFlags::DIGEST), &mut pairs)?;
/// assert_eq!(info.count, 6);
/// assert!(info.digest.is_some());
/// # Ok::<(), minkq::Error>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct QueryInfo {
    /// The exact number of pairs written.
    pub count: u64,
    /// With [`QueryFlags::DIGEST`]: xxHash64 (seed 0) of the canonical little-endian pairs.
    pub digest: Option<u64>,
    /// With [`QueryFlags::STATS`]: the work the query did.
    pub stats: Option<WorkStats>,
}

/// The work of one query call (`minkq_query_stats`), asked for with [`QueryFlags::STATS`].
/// The counts depend only on the tree and the queries: CPU and CUDA report the same numbers.
///
/// ```
/// use minkq::{Device, Mode, Query, QueryFlags, Scene, SceneDesc};
/// let device = Device::cpu()?;
/// let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.2, 0.2, 0.1]];
/// let scene = Scene::new(&device, &SceneDesc::new(&vertices, &[[0, 1, 2]]))?;
/// let mut pairs = Vec::new();
/// let info = scene.query_vec(&Query::vt(Mode::Sphere, 0.2).with_flags(QueryFlags::STATS), &mut pairs)?;
/// let stats = info.stats.unwrap();
/// assert_eq!(stats.candidates, info.count);
/// assert!(stats.primitive_tests >= stats.candidates);
/// # Ok::<(), minkq::Error>(())
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WorkStats {
    /// Internal node records read.
    pub nodes_visited: u64,
    /// Child boxes tested against a query shape.
    pub node_tests: u64,
    /// Primitives whose box passed, handed to the leaf filter.
    pub primitive_tests: u64,
    /// Pairs emitted: equal to the pair count.
    pub candidates: u64,
}

impl QueryInfo {
    pub(crate) fn from_raw(info: &sys::minkq_query_info, flags: QueryFlags) -> QueryInfo {
        let s = &info.stats;
        QueryInfo {
            count: info.count,
            digest: flags.contains(QueryFlags::DIGEST).then_some(info.digest),
            stats: flags.contains(QueryFlags::STATS).then_some(WorkStats {
                nodes_visited: s.nodes_visited,
                node_tests: s.node_tests,
                primitive_tests: s.primitive_tests,
                candidates: s.candidates,
            }),
        }
    }

    /// A zeroed `minkq_query_info` for the C API to fill.
    pub(crate) fn raw() -> sys::minkq_query_info {
        let stats = sys::minkq_query_stats { nodes_visited: 0, node_tests: 0, primitive_tests: 0, candidates: 0 };
        sys::minkq_query_info { count: 0, digest: 0, stats }
    }
}
