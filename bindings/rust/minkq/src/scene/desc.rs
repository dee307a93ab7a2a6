//! What a [`Scene`](crate::Scene) is built from: [`SceneDesc`] (slices) and [`SceneBuffers`]
//! (strided host or device memory).
use crate::buffer::Buffer;
use crate::query::SceneFlags;

/// The mesh and options a [`Scene`](crate::Scene) is built from (`minkq_scene_desc`).
///
/// ```
/// use minkq::{SceneDesc, SceneFlags};
/// let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
/// let triangles = [[0, 1, 2]];
/// let desc = SceneDesc::new(&vertices, &triangles).flags(SceneFlags::VT);
/// assert_eq!(desc.flags, SceneFlags::VT);
/// assert!(desc.edges.is_empty()); // derived from the triangles
/// ```
#[derive(Clone, Copy, Debug)]
pub struct SceneDesc<'a> {
    /// Vertex positions.
    pub vertices: &'a [[f32; 3]],
    /// Vertex indices of each triangle.
    pub triangles: &'a [[i32; 3]],
    /// Vertex indices of each edge, or empty to derive them from the triangles: every distinct
    /// undirected triangle edge as (min, max), in lexicographic order.
    pub edges: &'a [[i32; 2]],
    /// Which trees to build (at least one of VT and EE) and whether to drop incident pairs.
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

    /// The same description with explicit edges.
    ///
    /// ```
    /// let edges = [[0, 1], [1, 2]];
    /// let desc = minkq::SceneDesc::new(&[[0.0; 3]; 3], &[[0, 1, 2]]).edges(&edges);
    /// assert_eq!(desc.edges.len(), 2);
    /// ```
    pub fn edges(mut self, edges: &'a [[i32; 2]]) -> SceneDesc<'a> {
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
    pub fn flags(mut self, flags: SceneFlags) -> SceneDesc<'a> {
        self.flags = flags;
        self
    }
}

/// A [`SceneDesc`] over [`Buffer`]s instead of slices: strided records, host or CUDA device
/// memory (`minkq_scene_desc`). Build it from a `SceneDesc` with `From`, or from buffers.
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
    /// Vertex positions: 3 floats per record (byte stride >= 12).
    pub vertices: Buffer<'a>,
    /// Triangles: 3 int32 vertex indices per record (byte stride >= 12).
    pub triangles: Buffer<'a>,
    /// Edges: 2 int32 vertex indices per record (byte stride >= 8), or empty to derive them.
    pub edges: Buffer<'a>,
    /// Which trees to build (at least one of VT and EE) and whether to drop incident pairs.
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

    /// The same description with other flags.
    ///
    /// ```
    /// use minkq::{Buffer, SceneBuffers, SceneFlags};
    /// let desc = SceneBuffers::new(Buffer::empty(), Buffer::empty()).flags(SceneFlags::VT);
    /// assert_eq!(desc.flags, SceneFlags::VT);
    /// ```
    pub fn flags(mut self, flags: SceneFlags) -> SceneBuffers<'a> {
        self.flags = flags;
        self
    }
}

impl<'a> From<&SceneDesc<'a>> for SceneBuffers<'a> {
    fn from(desc: &SceneDesc<'a>) -> SceneBuffers<'a> {
        SceneBuffers {
            vertices: Buffer::from_slice(desc.vertices),
            triangles: Buffer::from_slice(desc.triangles),
            edges: Buffer::from_slice(desc.edges),
            flags: desc.flags,
        }
    }
}
