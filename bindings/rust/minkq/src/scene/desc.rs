//! What a [`Scene`](crate::Scene) is built from: [`SceneDesc`] (slices) and [`SceneBuffers`]
//! (strided host or device memory).
use crate::buffer::sealed::Precision;
use crate::buffer::{Buffer, Vertex};
use crate::query::SceneFlags;

/// The mesh and options a [`Scene`](crate::Scene) is built from (`minkq_scene_desc`).
///
/// The vertices are `[f32; 3]` ([`SceneDesc::new`], the default type) or `[f64; 3]`
/// ([`SceneDesc::new_f64`]: a [`SceneFlags::FLOAT64`] scene, implied by the vertex type).
///
/// ```
/// use minkq::{SceneDesc, SceneFlags};
/// let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
/// let triangles = [[0, 1, 2]];
/// let desc = SceneDesc::new(&vertices, &triangles).flags(SceneFlags::VT);
/// assert_eq!(desc.flags, SceneFlags::VT);
/// assert!(desc.edges.is_empty()); // derived from the triangles
/// let _: &[[f32; 3]] = desc.vertices; // unsuffixed literals: an f32 scene
/// ```
///
/// Codimensional elements (particles, rods, yarn) need no triangles: [`SceneDesc::codim`] takes
/// vertices and explicit edges, for [`SceneFlags::VV`] and [`SceneFlags::EV`] queries
/// ([`Query::vv`](crate::Query::vv), [`Query::ev`](crate::Query::ev)). An empty triangle slice
/// with [`SceneDesc::new`] and those flags is the same scene.
#[derive(Clone, Copy, Debug)]
pub struct SceneDesc<'a, V = [f32; 3]> {
    /// Vertex positions: `[f32; 3]`, or `[f64; 3]` for a [`SceneFlags::FLOAT64`] scene.
    pub vertices: &'a [V],
    /// Vertex indices of each triangle; may be empty (a scene of particles or rods).
    pub triangles: &'a [[i32; 3]],
    /// Vertex indices of each edge, or empty to derive them from the triangles: every distinct
    /// undirected triangle edge as (min, max), in lexicographic order.
    pub edges: &'a [[i32; 2]],
    /// Which trees to build (at least one of VT, EE, VV and EV) and whether to drop incident
    /// pairs.
    /// [`SceneFlags::FLOAT64`] follows from the vertex type: `[f64; 3]` vertices add it, and
    /// setting it with `[f32; 3]` vertices is
    /// [`Error::InvalidArgument`](crate::Error::InvalidArgument).
    pub flags: SceneFlags,
}

impl<'a> SceneDesc<'a> {
    /// A scene for VT and EE queries with incident pairs dropped (the cloth self-collision
    /// set-up), edges derived from the triangles.
    ///
    /// ```
    /// use minkq::{SceneDesc, SceneFlags};
    /// let desc = SceneDesc::new(&[[0.0; 3]; 3], &[[0, 1, 2]]);
    /// assert_eq!(desc.flags, SceneFlags::VT | SceneFlags::EE | SceneFlags::DROP_INCIDENT);
    /// ```
    pub fn new(vertices: &'a [[f32; 3]], triangles: &'a [[i32; 3]]) -> SceneDesc<'a> {
        SceneDesc {
            vertices,
            triangles,
            edges: &[],
            flags: SceneFlags::VT | SceneFlags::EE | SceneFlags::DROP_INCIDENT,
        }
    }
}

impl<'a, V> SceneDesc<'a, V> {
    /// A scene of codimensional elements: vertices and explicit edges, no triangles, for VV
    /// and EV queries with incident pairs dropped (flags
    /// `VV | EV | DROP_INCIDENT`). `[f32; 3]` or `[f64; 3]` vertices (the latter a
    /// [`SceneFlags::FLOAT64`] scene). Edges may be empty for loose particles (then ask for
    /// [`SceneFlags::VV`] alone: an EV scene without edges has nothing to pair); EE queries
    /// between the edges need [`SceneFlags::EE`] added.
    ///
    /// A rod (a polyline of 5 vertices along x) and two particles: one 0.05 above the rod's
    /// vertex 2, one 0.03 from that particle.
    ///
    /// ```
    /// use minkq::{Device, Mode, PairBuffer, Query, QueryFlags, Scene, SceneDesc, SceneFlags};
    /// let mut vertices: Vec<[f32; 3]> = (0..5).map(|i| [i as f32 * 0.1, 0.0, 0.0]).collect();
    /// vertices.push([0.2, 0.05, 0.0]); // particle 5
    /// vertices.push([0.2, 0.08, 0.0]); // particle 6
    /// let edges: Vec<[i32; 2]> = (0..4).map(|i| [i, i + 1]).collect();
    /// let desc = SceneDesc::codim(&vertices, &edges);
    /// assert_eq!(desc.flags, SceneFlags::VV | SceneFlags::EV | SceneFlags::DROP_INCIDENT);
    /// assert!(desc.triangles.is_empty());
    /// let scene = Scene::new(&Device::cpu()?, &desc)?;
    /// assert_eq!((scene.vertex_count(), scene.triangle_count(), scene.edge_count()), (7, 0, 4));
    ///
    /// let contacts = QueryFlags::LEAF_EXACT | QueryFlags::CANONICAL;
    /// let mut pairs = PairBuffer::new()?;
    /// // VV, (v, w) with v < w: the particles with each other and 5 with the rod's vertex 2.
    /// // Neighbouring rod vertices are 0.1 apart, beyond r; closer ones would pair too.
    /// assert_eq!(scene.query(&Query::vv(Mode::Sphere, 0.06).with_flags(contacts), &mut pairs)?, &[[2, 5], [5, 6]]);
    /// // EV, (vertex, edge): particle 5 near edges 1 and 2 (both end at vertex 2); the rod's
    /// // own vertices are not paired with the edges they end.
    /// assert_eq!(scene.query(&Query::ev(Mode::Box, 0.06).with_flags(contacts), &mut pairs)?, &[[5, 1], [5, 2]]);
    ///
    /// // The same scene from SceneDesc::new with no triangles; a VT query is refused.
    /// let same = SceneDesc::new(&vertices, &[]).edges(&edges).flags(desc.flags);
    /// let scene = Scene::new(&Device::cpu()?, &same)?;
    /// assert_eq!(scene.query(&Query::ev(Mode::Box, 0.06).with_flags(contacts), &mut pairs)?, &[[5, 1], [5, 2]]);
    /// let err = scene.query(&Query::vt(Mode::Box, 0.06), &mut pairs).unwrap_err();
    /// assert_eq!(err, minkq::Error::InvalidArgument("VT query on a scene created without MINKQ_SCENE_VT".into()));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn codim(vertices: &'a [V], edges: &'a [[i32; 2]]) -> SceneDesc<'a, V> {
        SceneDesc {
            vertices,
            triangles: &[],
            edges,
            flags: SceneFlags::VV | SceneFlags::EV | SceneFlags::DROP_INCIDENT,
        }
    }
}

impl<'a> SceneDesc<'a, [f64; 3]> {
    /// [`SceneDesc::new`] with `[f64; 3]` vertices: a [`SceneFlags::FLOAT64`] scene, which
    /// rounds them to float and widens its query radii by twice the farthest that rounding
    /// moved a vertex, so that every pair within r in double is reported (see
    /// [`SceneFlags::FLOAT64`]). Its refits and rebuilds take `[f64; 3]` too
    /// ([`Scene::refit_f64`](crate::Scene::refit_f64),
    /// [`Scene::rebuild_f64`](crate::Scene::rebuild_f64)).
    ///
    /// A vertex 0.95e-3 in front of a triangle near x = 20000, where floats lie 2^-9 (about
    /// 1.95e-3) apart: rounded to float they are 2^-9 apart, beyond r = 1e-3, and a float scene
    /// of the rounded positions loses the pair; the float64 scene finds it.
    ///
    /// ```
    /// use minkq::{Device, Mode, PairBuffer, Query, QueryFlags, Scene, SceneDesc, SceneFlags};
    /// let (plane, point) = (20000.0009, 20000.00185);
    /// let vertices = [[plane, -1.0, -1.0], [plane, 2.0, -1.0], [plane, -1.0, 2.0], [point, 0.0, 0.0]];
    /// let triangles = [[0, 1, 2]];
    /// let r = 1e-3f32;
    /// assert!(point - plane <= f64::from(r)); // within r in double...
    /// assert!(point as f32 - plane as f32 > r); // ...but not once rounded to float
    ///
    /// let device = Device::cpu()?;
    /// let query = Query::vt(Mode::Box, r).with_flags(QueryFlags::LEAF_EXACT);
    /// let mut pairs = PairBuffer::new()?;
    /// let rounded: Vec<[f32; 3]> = vertices.iter().map(|v| v.map(|x| x as f32)).collect();
    /// let float_scene = Scene::new(&device, &SceneDesc::new(&rounded, &triangles))?;
    /// assert!(float_scene.query(&query, &mut pairs)?.is_empty());
    ///
    /// let desc = SceneDesc::new_f64(&vertices, &triangles);
    /// assert_eq!(desc.flags, SceneFlags::VT | SceneFlags::EE | SceneFlags::DROP_INCIDENT);
    /// let scene = Scene::new(&device, &desc)?;
    /// assert!(scene.is_float64());
    /// assert_eq!(scene.query(&query, &mut pairs)?, &[[3, 0]]); // (vertex, triangle)
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn new_f64(vertices: &'a [[f64; 3]], triangles: &'a [[i32; 3]]) -> SceneDesc<'a, [f64; 3]> {
        SceneDesc {
            vertices,
            triangles,
            edges: &[],
            flags: SceneFlags::VT | SceneFlags::EE | SceneFlags::DROP_INCIDENT,
        }
    }
}

impl<'a, V> SceneDesc<'a, V> {
    /// The same description with explicit edges.
    ///
    /// ```
    /// let edges = [[0, 1], [1, 2]];
    /// let desc = minkq::SceneDesc::new(&[[0.0; 3]; 3], &[[0, 1, 2]]).edges(&edges);
    /// assert_eq!(desc.edges.len(), 2);
    /// ```
    pub fn edges(mut self, edges: &'a [[i32; 2]]) -> SceneDesc<'a, V> {
        self.edges = edges;
        self
    }

    /// The same description with other flags.
    ///
    /// ```
    /// use minkq::SceneFlags;
    /// let desc = minkq::SceneDesc::new(&[[0.0; 3]; 3], &[[0, 1, 2]]).flags(SceneFlags::EE);
    /// assert_eq!(desc.flags, SceneFlags::EE);
    /// ```
    pub fn flags(mut self, flags: SceneFlags) -> SceneDesc<'a, V> {
        self.flags = flags;
        self
    }
}

/// A [`SceneDesc`] over [`Buffer`]s instead of slices: strided records, host or CUDA device
/// memory (`minkq_scene_desc`). Build it from a `SceneDesc` with `From`, or from buffers.
/// Double vertices need [`SceneFlags::FLOAT64`] in `flags` (see [`SceneBuffers::flags`]).
///
/// ```
/// use minkq::{Buffer, SceneBuffers, SceneDesc, SceneFlags};
/// let vertices = [[0.0f32; 3]; 3];
/// let triangles = [[0, 1, 2]];
/// let desc = SceneBuffers::new(Buffer::from_slice(&vertices), Buffer::from_slice(&triangles));
/// assert_eq!(desc.flags, SceneFlags::VT | SceneFlags::EE | SceneFlags::DROP_INCIDENT);
/// let same = SceneBuffers::from(&SceneDesc::new(&vertices, &triangles));
/// assert_eq!(same.vertices.data(), desc.vertices.data());
/// ```
#[derive(Clone, Copy, Debug)]
pub struct SceneBuffers<'a> {
    /// Vertex positions: 3 floats per record (byte stride >= 12), or with
    /// [`SceneFlags::FLOAT64`] 3 doubles (byte stride >= 24). A buffer made from a slice of
    /// the other precision is refused; a raw buffer is read as the flag says.
    pub vertices: Buffer<'a>,
    /// Triangles: 3 int32 vertex indices per record (byte stride >= 12); may be empty.
    pub triangles: Buffer<'a>,
    /// Edges: 2 int32 vertex indices per record (byte stride >= 8), or empty to derive them.
    pub edges: Buffer<'a>,
    /// Which trees to build (at least one of VT, EE, VV and EV), whether to drop incident
    /// pairs, and whether the vertices are doubles ([`SceneFlags::FLOAT64`]).
    pub flags: SceneFlags,
}

impl<'a> SceneBuffers<'a> {
    /// VT and EE with incident pairs dropped, edges derived: as [`SceneDesc::new`].
    ///
    /// ```
    /// use minkq::{Buffer, SceneBuffers};
    /// let desc = SceneBuffers::new(Buffer::from_slice(&[[0.0f32; 3]; 3]), Buffer::from_slice(&[[0, 1, 2]]));
    /// assert!(desc.edges.is_empty());
    /// ```
    pub fn new(vertices: Buffer<'a>, triangles: Buffer<'a>) -> SceneBuffers<'a> {
        SceneBuffers {
            vertices,
            triangles,
            edges: Buffer::empty(),
            flags: SceneFlags::VT | SceneFlags::EE | SceneFlags::DROP_INCIDENT,
        }
    }

    /// The same description with explicit edges, e.g. the last two columns of an (E, 4)
    /// edge table read in place with a byte stride of 16.
    ///
    /// ```
    /// use minkq::{Buffer, Device, Memory, Scene, SceneBuffers};
    /// let vertices = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    /// // (opposite vertex, opposite vertex, v0, v1) per edge, as Newton stores them.
    /// let table = [[-1, 2, 0, 1], [-1, 0, 1, 2]];
    /// // SAFETY: two 16-byte records whose last 8 bytes are the edge's vertices.
    /// let edges = unsafe { Buffer::from_raw_parts(table[0][2..].as_ptr().cast(), 16, 2, Memory::Host) };
    /// let desc = SceneBuffers::new(Buffer::from_slice(&vertices), Buffer::from_slice(&[[0, 1, 2]])).edges(edges);
    /// let scene = Scene::from_buffers(&Device::cpu()?, &desc)?;
    /// assert_eq!(scene.edges()?, vec![[0, 1], [1, 2]]);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn edges(mut self, edges: Buffer<'a>) -> SceneBuffers<'a> {
        self.edges = edges;
        self
    }

    /// The same description with other flags: [`SceneFlags::FLOAT64`] for double vertices,
    /// from a slice of `[f64; 3]` or a raw buffer of 3 doubles per record.
    ///
    /// ```
    /// use minkq::{Buffer, Device, Error, Memory, Scene, SceneBuffers, SceneFlags};
    /// let desc = SceneBuffers::new(Buffer::empty(), Buffer::empty()).flags(SceneFlags::VT);
    /// assert_eq!(desc.flags, SceneFlags::VT);
    ///
    /// // x, y, z and a fourth double per vertex (32-byte records), read in place.
    /// let padded = [[0.0f64, 0.0, 0.0, 9.0], [1.0, 0.0, 0.0, 9.0], [0.0, 1.0, 0.0, 9.0]];
    /// // SAFETY: three 32-byte records starting with 3 doubles, borrowed from `padded`.
    /// let vertices = unsafe { Buffer::from_raw_parts(padded.as_ptr().cast(), 32, 3, Memory::Host) };
    /// let triangles = [[0, 1, 2]];
    /// let desc = SceneBuffers::new(vertices, Buffer::from_slice(&triangles)).flags(SceneFlags::EE | SceneFlags::FLOAT64);
    /// let scene = Scene::from_buffers(&Device::cpu()?, &desc)?;
    /// assert!(scene.is_float64() && scene.edge_count() == 3);
    ///
    /// // A slice of the other precision is refused: [f32; 3] with FLOAT64, [f64; 3] without.
    /// let floats = [[0.0f32; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    /// let mixed = SceneBuffers::new(Buffer::from_slice(&floats), Buffer::from_slice(&triangles)).flags(desc.flags);
    /// assert!(matches!(Scene::from_buffers(&Device::cpu()?, &mixed), Err(Error::InvalidArgument(_))));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn flags(mut self, flags: SceneFlags) -> SceneBuffers<'a> {
        self.flags = flags;
        self
    }
}

/// The slices as packed host buffers; `[f64; 3]` vertices add [`SceneFlags::FLOAT64`].
impl<'a, V: Vertex> From<&SceneDesc<'a, V>> for SceneBuffers<'a> {
    fn from(desc: &SceneDesc<'a, V>) -> SceneBuffers<'a> {
        let mut flags = desc.flags;
        if V::PRECISION == Some(Precision::F64) {
            flags |= SceneFlags::FLOAT64;
        }
        SceneBuffers {
            vertices: Buffer::from_slice(desc.vertices),
            triangles: Buffer::from_slice(desc.triangles),
            edges: Buffer::from_slice(desc.edges),
            flags,
        }
    }
}
