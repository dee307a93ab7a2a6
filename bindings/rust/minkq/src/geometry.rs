//! What a scene of many geometries is built from ([`Scene::from_geometries`]): a
//! [`GeometryDesc`] per triangle mesh, edge set or vertex set, with its [`Kinds`] and
//! [`GeometryFlags`]; and the [`Element`]s its global numbering counts.
//!
//! [`Scene::from_geometries`]: crate::Scene::from_geometries
use std::mem::MaybeUninit;
use std::ops::{BitOr, BitOrAssign};

use crate::buffer::{Buffer, Vertex};
use crate::query::{flags, QueryKind};
use crate::sys;

flags! {
    /// The pairs a geometry takes part in (`kinds` of `minkq_geometry_desc`: the
    /// `MINKQ_SCENE_VT`, `_EE`, `_VV` and `_EV` bits), at least one. A cross pair of a kind
    /// needs the kind on both geometries; a scene answers the queries of every kind one of its
    /// geometries has.
    ///
    /// ```
    /// use minkq::Kinds;
    /// let cloth = Kinds::VT | Kinds::EE;
    /// assert!(cloth.contains(Kinds::EE) && !cloth.contains(Kinds::VV));
    /// ```
    Kinds {
        /// Vertex–triangle pairs (both ways between two geometries).
        VT = sys::MINKQ_SCENE_VT;
        /// Edge–edge pairs.
        EE = sys::MINKQ_SCENE_EE;
        /// Vertex–vertex pairs.
        VV = sys::MINKQ_SCENE_VV;
        /// Vertex–edge pairs (both ways between two geometries).
        EV = sys::MINKQ_SCENE_EV;
    }
}

flags! {
    /// How a geometry takes part in its scene (`minkq_geometry_flags`).
    ///
    /// ```
    /// use minkq::GeometryFlags;
    /// let collider = GeometryFlags::STATIC; // no self pairs, built once
    /// assert!(!collider.contains(GeometryFlags::SELF));
    /// ```
    GeometryFlags {
        /// Report pairs of two elements of this geometry (self pairs), as a one-mesh scene of
        /// it alone would.
        SELF = sys::MINKQ_GEOMETRY_SELF;
        /// Self pairs drop incident ones: (v, t) with v a vertex of t, edges sharing a vertex,
        /// (v, e) with v a vertex of e (as [`SceneFlags::DROP_INCIDENT`]).
        ///
        /// [`SceneFlags::DROP_INCIDENT`]: crate::SceneFlags::DROP_INCIDENT
        DROP_INCIDENT = sys::MINKQ_GEOMETRY_DROP_INCIDENT;
        /// The vertices are 3 doubles each, at creation and in every move of the geometry (as
        /// [`SceneFlags::FLOAT64`]). `[f64; 3]` slices imply it; a raw [`Buffer`] of doubles
        /// needs it, and a `[f32; 3]` slice with it is refused.
        ///
        /// [`SceneFlags::FLOAT64`]: crate::SceneFlags::FLOAT64
        FLOAT64 = sys::MINKQ_GEOMETRY_FLOAT64;
        /// Never moves: built once, skipped by whole-scene refits and rebuilds (whose vertices
        /// are those of the moving geometries only), refused by the per-geometry ones.
        STATIC = sys::MINKQ_GEOMETRY_STATIC;
    }
}

/// The kind of a query's pairs.
///
/// ```
/// use minkq::{Kinds, QueryKind};
/// assert_eq!(Kinds::from(QueryKind::Ev), Kinds::EV);
/// ```
impl From<QueryKind> for Kinds {
    fn from(kind: QueryKind) -> Kinds {
        match kind {
            QueryKind::Vt => Kinds::VT,
            QueryKind::Ee => Kinds::EE,
            QueryKind::Vv => Kinds::VV,
            QueryKind::Ev => Kinds::EV,
        }
    }
}

/// The elements a scene numbers (`minkq_element`): every geometry's vertices, triangles and
/// edges, each numbered globally as the geometries concatenated in order.
///
/// ```
/// assert_ne!(minkq::Element::Vertex, minkq::Element::Edge);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Element {
    /// Vertices.
    Vertex,
    /// Triangles.
    Triangle,
    /// Edges: given, or derived from the triangles as a one-mesh scene derives them.
    Edge,
}

impl Element {
    /// Every element, in the C enum's order.
    pub(crate) const ALL: [Element; 3] = [Element::Vertex, Element::Triangle, Element::Edge];

    /// The position in [`Element::ALL`].
    pub(crate) fn index(self) -> usize {
        match self {
            Element::Vertex => 0,
            Element::Triangle => 1,
            Element::Edge => 2,
        }
    }

    pub(crate) fn raw(self) -> sys::minkq_element {
        match self {
            Element::Vertex => sys::MINKQ_ELEMENT_VERTEX,
            Element::Triangle => sys::MINKQ_ELEMENT_TRIANGLE,
            Element::Edge => sys::MINKQ_ELEMENT_EDGE,
        }
    }
}

/// One geometry of a scene of many (`minkq_geometry_desc`): a triangle mesh
/// ([`GeometryDesc::mesh`]), an edge or vertex set ([`GeometryDesc::codim`]), or the same over
/// [`Buffer`]s ([`GeometryDesc::from_buffers`], or any field set to a buffer: strided or
/// device memory). The defaults are the C library's (`minkq_geometry_desc_init`): kinds
/// `VT | EE`, flags `SELF | DROP_INCIDENT`, world 0, group 1, every mask bit, no thickness.
///
/// Built by its constructors and changed by its builder methods or fields; later versions may
/// add fields (with defaults), so it cannot be written as a struct literal.
///
/// ```
/// use minkq::{GeometryDesc, GeometryFlags, Kinds};
/// let vertices = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
/// let desc = GeometryDesc::mesh(&vertices, &[[0, 1, 2]]);
/// assert_eq!((desc.kinds, desc.flags), (Kinds::VT | Kinds::EE, GeometryFlags::SELF | GeometryFlags::DROP_INCIDENT));
/// assert_eq!((desc.world, desc.group, desc.mask), (Some(0), 1, u32::MAX));
/// let body = desc.flags(GeometryFlags::STATIC).world(None).group(2);
/// assert_eq!((body.world, body.group), (None, 2));
/// ```
#[derive(Clone, Copy, Debug)]
#[non_exhaustive]
pub struct GeometryDesc<'a> {
    /// Vertex positions, at least one: 3 floats per record, or 3 doubles with
    /// [`GeometryFlags::FLOAT64`] (implied by a slice of `[f64; 3]`).
    pub vertices: Buffer<'a>,
    /// 3 int32 indices into this geometry's vertices per triangle; may be empty.
    pub triangles: Buffer<'a>,
    /// 2 int32 indices per edge, or empty to derive them from the triangles (for EE and EV):
    /// every distinct undirected triangle edge as (min, max), in lexicographic order.
    pub edges: Buffer<'a>,
    /// Empty, or one `f32` per vertex, finite and >= 0. An element's thickness is its
    /// vertices' largest; a pair of elements a, b is within reach when its distance is at
    /// most r + t(a) + t(b).
    pub thickness: Buffer<'a>,
    /// The pairs it takes part in.
    pub kinds: Kinds,
    /// Self pairs, incident pairs dropped, doubles, static.
    pub flags: GeometryFlags,
    /// Its world (at most `i32::MAX`), or `None`: part of every world. Geometries of two
    /// different worlds never pair.
    pub world: Option<u32>,
    /// Collision group bits: geometries a and b pair when `a.group & b.mask != 0` and
    /// `b.group & a.mask != 0`.
    pub group: u32,
    /// The groups it pairs with (see [`GeometryDesc::group`]).
    pub mask: u32,
}

impl<'a> GeometryDesc<'a> {
    /// A triangle mesh with the defaults; `[f64; 3]` vertices make it
    /// [`GeometryFlags::FLOAT64`]. Edges are derived from the triangles unless given
    /// ([`GeometryDesc::edges`]).
    ///
    /// ```
    /// let doubles = [[0.0f64, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    /// let desc = minkq::GeometryDesc::mesh(&doubles, &[[0, 1, 2]]);
    /// assert_eq!(desc.vertices.byte_stride(), 24);
    /// ```
    pub fn mesh<V: Vertex>(vertices: &'a [V], triangles: &'a [[i32; 3]]) -> GeometryDesc<'a> {
        GeometryDesc::from_buffers(Buffer::from_slice(vertices), Buffer::from_slice(triangles))
    }

    /// Codimensional elements: vertices and edges (rods; no edges for loose particles), no
    /// triangles, kinds `VV | EV` (as [`SceneDesc::codim`]); the other defaults as
    /// [`GeometryDesc::mesh`].
    ///
    /// ```
    /// use minkq::{GeometryDesc, Kinds};
    /// let rod = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
    /// let desc = GeometryDesc::codim(&rod, &[[0, 1], [1, 2]]);
    /// assert_eq!((desc.kinds, desc.triangles.len(), desc.edges.len()), (Kinds::VV | Kinds::EV, 0, 2));
    /// ```
    ///
    /// [`SceneDesc::codim`]: crate::SceneDesc::codim
    pub fn codim<V: Vertex>(vertices: &'a [V], edges: &'a [[i32; 2]]) -> GeometryDesc<'a> {
        GeometryDesc::mesh(vertices, &[]).edges(edges).kinds(Kinds::VV | Kinds::EV)
    }

    /// [`GeometryDesc::mesh`] over [`Buffer`]s: strided records in host or (on a CUDA device)
    /// device memory. Double vertices from a raw buffer need [`GeometryFlags::FLOAT64`] in
    /// the flags.
    ///
    /// ```
    /// use minkq::{Buffer, GeometryDesc};
    /// let vertices = [[0.0f32; 3]; 3];
    /// let desc = GeometryDesc::from_buffers(Buffer::from_slice(&vertices), Buffer::empty());
    /// assert!(desc.triangles.is_empty() && desc.thickness.is_empty());
    /// ```
    pub fn from_buffers(vertices: Buffer<'a>, triangles: Buffer<'a>) -> GeometryDesc<'a> {
        let defaults = raw_defaults();
        GeometryDesc {
            vertices,
            triangles,
            edges: Buffer::empty(),
            thickness: Buffer::empty(),
            kinds: Kinds(defaults.kinds),
            flags: GeometryFlags(defaults.flags),
            world: u32::try_from(defaults.world).ok(),
            group: defaults.group,
            mask: defaults.mask,
        }
    }

    /// The same geometry with explicit edges.
    ///
    /// ```
    /// let desc = minkq::GeometryDesc::mesh(&[[0.0f32; 3]; 3], &[[0, 1, 2]]).edges(&[[0, 1]]);
    /// assert_eq!(desc.edges.len(), 1);
    /// ```
    pub fn edges(mut self, edges: &'a [[i32; 2]]) -> GeometryDesc<'a> {
        self.edges = Buffer::from_slice(edges);
        self
    }

    /// The same geometry with a thickness per vertex (finite, >= 0), or none (empty).
    ///
    /// ```
    /// let desc = minkq::GeometryDesc::mesh(&[[0.0f32; 3]; 3], &[[0, 1, 2]]).thickness(&[0.1, 0.0, 0.2]);
    /// assert_eq!(desc.thickness.len(), 3);
    /// ```
    pub fn thickness(mut self, thickness: &'a [f32]) -> GeometryDesc<'a> {
        self.thickness = Buffer::from_slice(thickness);
        self
    }

    /// The same geometry taking part in other kinds of pairs.
    ///
    /// ```
    /// use minkq::Kinds;
    /// let desc = minkq::GeometryDesc::mesh(&[[0.0f32; 3]; 3], &[[0, 1, 2]]).kinds(Kinds::VT);
    /// assert_eq!(desc.kinds, Kinds::VT);
    /// ```
    pub fn kinds(mut self, kinds: Kinds) -> GeometryDesc<'a> {
        self.kinds = kinds;
        self
    }

    /// The same geometry with other flags (all of them: `GeometryFlags::STATIC` alone is a
    /// static geometry without self pairs).
    ///
    /// ```
    /// use minkq::GeometryFlags;
    /// let desc = minkq::GeometryDesc::mesh(&[[0.0f32; 3]; 3], &[[0, 1, 2]]).flags(GeometryFlags::SELF);
    /// assert_eq!(desc.flags, GeometryFlags::SELF);
    /// ```
    pub fn flags(mut self, flags: GeometryFlags) -> GeometryDesc<'a> {
        self.flags = flags;
        self
    }

    /// The same geometry in another world: `Some(w)` (or `w`), or `None` for every world.
    ///
    /// ```
    /// let desc = minkq::GeometryDesc::mesh(&[[0.0f32; 3]; 3], &[[0, 1, 2]]);
    /// assert_eq!((desc.world(3).world, desc.world(None).world), (Some(3), None));
    /// ```
    pub fn world(mut self, world: impl Into<Option<u32>>) -> GeometryDesc<'a> {
        self.world = world.into();
        self
    }

    /// The same geometry in other collision groups.
    ///
    /// ```
    /// assert_eq!(minkq::GeometryDesc::mesh(&[[0.0f32; 3]; 3], &[]).group(4).group, 4);
    /// ```
    pub fn group(mut self, group: u32) -> GeometryDesc<'a> {
        self.group = group;
        self
    }

    /// The same geometry pairing with other groups.
    ///
    /// ```
    /// assert_eq!(minkq::GeometryDesc::mesh(&[[0.0f32; 3]; 3], &[]).mask(!4).mask, !4);
    /// ```
    pub fn mask(mut self, mask: u32) -> GeometryDesc<'a> {
        self.mask = mask;
        self
    }
}

/// The C library's defaults (`minkq_geometry_desc_init`), with this header's `struct_size`.
pub(crate) fn raw_defaults() -> sys::minkq_geometry_desc {
    let mut raw = MaybeUninit::<sys::minkq_geometry_desc>::zeroed();
    // SAFETY: a writable description; all zeros (null pointers, zero counts) is a valid value
    // of it, which the call then fills.
    unsafe {
        sys::minkq_geometry_desc_init(raw.as_mut_ptr());
        raw.assume_init()
    }
}
