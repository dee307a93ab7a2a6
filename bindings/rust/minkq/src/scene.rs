use std::fmt;
use std::ptr::{self, NonNull};
use std::sync::Arc;

use crate::buffer::{Buffer, Memory, PairsOut};
use crate::device::{Device, DeviceHandle};
use crate::error::{check, Error, Result};
use crate::pairs::{query_vec, PairBuffer};
use crate::query::{Query, QueryFlags, QueryInfo, Reserve, SceneFlags, WorkStats};
use crate::stream::{CountOut, Stream};
use crate::sys;

/// The mesh and options a [`Scene`] is built from (`minkq_scene_desc`).
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

/// A triangle mesh on a device with the BVHs its flags ask for, answering VT and EE queries
/// (`minkq_scene`). Released when dropped; keeps its device alive.
///
/// Threads: `Send` but not `Sync`. The C API says one scene must not be used by two threads at
/// the same time, so a `&Scene` may not cross threads (its queries would then run
/// concurrently); moving the scene to another thread is allowed. Wrap it in a `Mutex` to share
/// it.
///
/// ```
/// use minkq::{Device, Mode, PairBuffer, Query, QueryFlags, Scene, SceneDesc};
/// let device = Device::cpu()?;
/// // Two triangles, one 0.1 above the other.
/// let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0],
///                 [0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]];
/// let triangles = [[0, 1, 2], [3, 4, 5]];
/// let scene = Scene::new(&device, &SceneDesc::new(&vertices, &triangles))?;
/// let mut pairs = PairBuffer::new()?;
/// let vt = scene.query(&Query::vt(Mode::Box, 0.2).with_flags(QueryFlags::LEAF_EXACT), &mut pairs)?;
/// assert_eq!(vt.len(), 6); // each vertex against the other triangle
/// # Ok::<(), minkq::Error>(())
/// ```
///
/// ```compile_fail
/// fn shared_between_threads<T: Sync>() {}
/// shared_between_threads::<minkq::Scene>(); // Scene is not Sync
/// ```
pub struct Scene {
    raw: NonNull<sys::minkq_scene>,
    _device: Arc<DeviceHandle>,
}

// SAFETY: the C API allows an object to be used from any thread, one thread at a time. A
// `Scene` is not `Sync`, so only its owner (or a `&mut`) can call into it; its device may be
// shared by scenes on other threads (documented by the C API).
unsafe impl Send for Scene {}

impl Scene {
    /// Copies the mesh to the device and builds the trees `desc.flags` asks for.
    ///
    /// Errors: [`Error::NonFinite`] (`"vertex 12 has a non-finite coordinate (...)"`),
    /// [`Error::IndexOutOfRange`], [`Error::SizeOverflow`], [`Error::InvalidArgument`] (no
    /// query kind in the flags).
    ///
    /// ```
    /// use minkq::{Device, Error, Scene, SceneDesc};
    /// let device = Device::cpu()?;
    /// let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, f32::NAN, 0.0]];
    /// let err = Scene::new(&device, &SceneDesc::new(&vertices, &[[0, 1, 2]])).unwrap_err();
    /// assert!(matches!(&err, Error::NonFinite(m) if m.starts_with("vertex 2 ")));
    /// let err = Scene::new(&device, &SceneDesc::new(&vertices[..2], &[[0, 1, 2]])).unwrap_err();
    /// assert!(matches!(err, Error::IndexOutOfRange(_)));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn new(device: &Device, desc: &SceneDesc<'_>) -> Result<Scene> {
        Scene::from_buffers(device, &SceneBuffers::from(desc))
    }

    /// [`Scene::new`] over [`Buffer`]s: strided records in host or (on a CUDA device) device
    /// memory, read in place. The scene keeps its own copy; the buffers may change or go
    /// away once this returns. Device memory on a CPU device is [`Error::InvalidArgument`].
    ///
    /// ```
    /// use minkq::{Buffer, Device, Scene, SceneBuffers, SceneFlags};
    /// let vertices = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    /// let triangles = [[0, 1, 2]];
    /// let desc = SceneBuffers::new(Buffer::from_slice(&vertices), Buffer::from_slice(&triangles)).flags(SceneFlags::EE);
    /// let scene = Scene::from_buffers(&Device::cpu()?, &desc)?;
    /// assert_eq!(scene.edge_count(), 3);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn from_buffers(device: &Device, desc: &SceneBuffers<'_>) -> Result<Scene> {
        let raw_desc = sys::minkq_scene_desc {
            flags: desc.flags.bits(),
            vertices: desc.vertices.raw(),
            triangles: desc.triangles.raw(),
            edges: desc.edges.raw(),
        };
        let mut raw = ptr::null_mut();
        // SAFETY: the buffers' constructors promise readable records for their lifetime,
        // which outlives this call; the library copies them before returning.
        check(unsafe { sys::minkq_scene_create(device.handle.as_ptr(), &raw_desc, &mut raw) })?;
        let raw = NonNull::new(raw).ok_or_else(|| Error::Internal("minkq_scene_create returned NULL".into()))?;
        Ok(Scene { raw, _device: Arc::clone(&device.handle) })
    }

    /// Moves the vertices (same count) and refits the trees in place: the per-step call of a
    /// simulation. On error the scene keeps its previous positions. A refit keeps the grouping
    /// of the last build: after large deformations the boxes overlap more and queries visit
    /// more nodes ([`Scene::tree_growth`] measures it, [`Scene::rebuild`] resets it); the pairs
    /// found never change.
    ///
    /// ```
    /// # use minkq::*;
    /// # let device = Device::cpu()?;
    /// let mut vertices = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0],
    ///                         [0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]];
    /// let triangles = [[0, 1, 2], [3, 4, 5]];
    /// let mut scene = Scene::new(&device, &SceneDesc::new(&vertices, &triangles))?;
    /// let query = Query::vt(Mode::Sphere, 0.2).with_flags(QueryFlags::LEAF_EXACT);
    /// let mut pairs = PairBuffer::new()?;
    /// assert_eq!(scene.query(&query, &mut pairs)?.len(), 6);
    /// for v in &mut vertices[3..] {
    ///     v[2] = 1.0; // lift the upper triangle away
    /// }
    /// scene.refit(&vertices)?;
    /// assert!(scene.query(&query, &mut pairs)?.is_empty());
    /// assert!(matches!(scene.refit(&vertices[..5]), Err(Error::InvalidArgument(_))));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn refit(&mut self, vertices: &[[f32; 3]]) -> Result<()> {
        self.refit_buffer(Buffer::from_slice(vertices))
    }

    /// [`Scene::refit`] from a [`Buffer`]: strided records, host or (on a CUDA device) device
    /// memory, read in place on the device. On error the scene keeps its previous positions.
    ///
    /// ```
    /// # use minkq::*;
    /// let vertices = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    /// let mut scene = Scene::new(&Device::cpu()?, &SceneDesc::new(&vertices, &[[0, 1, 2]]))?;
    /// // x, y, z and a fourth float per vertex (16-byte records), as a vec4 array holds them.
    /// let moved = [[0.0f32, 0.0, 1.0, 0.0], [1.0, 0.0, 1.0, 0.0], [0.0, 1.0, 1.0, 0.0]];
    /// // SAFETY: three 16-byte records starting with x, y, z, borrowed from `moved`.
    /// scene.refit_buffer(unsafe { Buffer::from_raw_parts(moved.as_ptr().cast(), 16, 3, Memory::Host) })?;
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn refit_buffer(&mut self, vertices: Buffer<'_>) -> Result<()> {
        // SAFETY: a live scene; the buffer's constructor promised readable records.
        check(unsafe { sys::minkq_scene_refit(self.raw.as_ptr(), vertices.raw()) })
    }

    /// Moves the vertices (same count) like [`Scene::refit`] and builds the trees afresh for
    /// the new positions: the trees [`Scene::new`] would build there, with the same topology
    /// and edge numbering. The pairs are the same as after a refit; only the speed of later
    /// queries differs. Worth it once large motions have raised [`Scene::tree_growth`] (above
    /// about 1.5), and every so many steps when the mesh changes shape a lot. Same errors as
    /// [`Scene::refit`]; on error the scene keeps its positions and trees.
    ///
    /// ```
    /// # use minkq::*;
    /// # let device = Device::cpu()?;
    /// let mut vertices = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0],
    ///                         [0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]];
    /// let triangles = [[0, 1, 2], [3, 4, 5]];
    /// let mut scene = Scene::new(&device, &SceneDesc::new(&vertices, &triangles))?;
    /// let query = Query::vt(Mode::Sphere, 0.2).with_flags(QueryFlags::LEAF_EXACT);
    /// let mut pairs = PairBuffer::new()?;
    /// for v in &mut vertices[3..] {
    ///     v[2] = 1.0; // lift the upper triangle away
    /// }
    /// scene.rebuild(&vertices)?;
    /// assert!(scene.query(&query, &mut pairs)?.is_empty());
    /// assert_eq!(scene.tree_growth()?, 1.0);
    /// let err = scene.rebuild(&vertices[..5]).unwrap_err();
    /// assert_eq!(err, Error::InvalidArgument("rebuild with 5 vertices but the scene has 6".into()));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn rebuild(&mut self, vertices: &[[f32; 3]]) -> Result<()> {
        self.rebuild_buffer(Buffer::from_slice(vertices))
    }

    /// [`Scene::rebuild`] from a [`Buffer`]: strided records, host or (on a CUDA device)
    /// device memory, read in place on the device. On error the scene keeps its positions and
    /// trees.
    ///
    /// ```
    /// # use minkq::*;
    /// let vertices = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    /// let mut scene = Scene::new(&Device::cpu()?, &SceneDesc::new(&vertices, &[[0, 1, 2]]))?;
    /// // x, y, z and a fourth float per vertex (16-byte records), as a vec4 array holds them.
    /// let moved = [[0.0f32, 0.0, 1.0, 0.0], [1.0, 0.0, 1.0, 0.0], [0.0, f32::NAN, 1.0, 0.0]];
    /// // SAFETY: three 16-byte records starting with x, y, z, borrowed from `moved`.
    /// let err = scene.rebuild_buffer(unsafe { Buffer::from_raw_parts(moved.as_ptr().cast(), 16, 3, Memory::Host) });
    /// assert!(matches!(err, Err(Error::NonFinite(m)) if m.starts_with("vertex 2 ")));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn rebuild_buffer(&mut self, vertices: Buffer<'_>) -> Result<()> {
        // SAFETY: a live scene; the buffer's constructor promised readable records.
        check(unsafe { sys::minkq_scene_rebuild(self.raw.as_ptr(), vertices.raw()) })
    }

    /// How far the refits since the last build (creation or [`Scene::rebuild`]) have stretched
    /// the trees: their area cost (scale-free; it grows with the nodes a query visits) now over
    /// its value right after that build, the larger of the scene's trees. 1 after a build. It
    /// sees boxes that stretch, not a mesh folding or flattening into new neighbours (where a
    /// rebuild can still help). Rebuild when it passes about 1.5, and every so many steps when
    /// the mesh changes shape a lot (`minkq_scene_tree_growth` in `minkq.h`; what rebuilds
    /// bought on the benchmark scenes is in `bench/README.md`). A tree whose elements all lie
    /// on one line parallel to an axis (or at one point) has no area: 1 while it stays so,
    /// infinity once it has any.
    ///
    /// ```
    /// # use minkq::*;
    /// // A flat 8 x 8 grid of unit squares...
    /// let n = 9;
    /// let grid: Vec<[f32; 3]> = (0..n * n).map(|k| [(k % n) as f32, (k / n) as f32, 0.0]).collect();
    /// let mut triangles = Vec::new();
    /// for j in 0..n - 1 {
    ///     for i in 0..n - 1 {
    ///         let v = (j * n + i) as i32;
    ///         triangles.push([v, v + 1, v + n as i32 + 1]);
    ///         triangles.push([v, v + n as i32 + 1, v + n as i32]);
    ///     }
    /// }
    /// let mut scene = Scene::new(&Device::cpu()?, &SceneDesc::new(&grid, &triangles))?;
    /// assert_eq!(scene.tree_growth()?, 1.0);
    /// // ... rolled up into a tube: the boxes of the flat grid's grouping now overlap.
    /// let rolled: Vec<[f32; 3]> = grid
    ///     .iter()
    ///     .map(|p| {
    ///         let angle = p[0] * std::f32::consts::TAU / (n - 1) as f32;
    ///         [angle.cos(), p[1], angle.sin()]
    ///     })
    ///     .collect();
    /// scene.refit(&rolled)?;
    /// assert!(scene.tree_growth()? > 1.5);
    /// scene.rebuild(&rolled)?;
    /// assert_eq!(scene.tree_growth()?, 1.0);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn tree_growth(&self) -> Result<f64> {
        let mut growth = 0.0;
        // SAFETY: a live scene; `growth` is a writable double.
        check(unsafe { sys::minkq_scene_tree_growth(self.raw.as_ptr(), &mut growth) })?;
        Ok(growth)
    }

    /// The number of vertices.
    ///
    /// ```
    /// # use minkq::*;
    /// let scene = Scene::new(&Device::cpu()?, &SceneDesc::new(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], &[[0, 1, 2]]))?;
    /// assert_eq!(scene.vertex_count(), 3);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn vertex_count(&self) -> usize {
        // SAFETY: a live scene.
        unsafe { sys::minkq_scene_vertex_count(self.raw.as_ptr()) }
    }

    /// The number of triangles.
    ///
    /// ```
    /// # use minkq::*;
    /// let scene = Scene::new(&Device::cpu()?, &SceneDesc::new(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], &[[0, 1, 2]]))?;
    /// assert_eq!(scene.triangle_count(), 1);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn triangle_count(&self) -> usize {
        // SAFETY: a live scene.
        unsafe { sys::minkq_scene_triangle_count(self.raw.as_ptr()) }
    }

    /// The number of edges (given, or derived for an EE scene).
    ///
    /// ```
    /// # use minkq::*;
    /// let scene = Scene::new(&Device::cpu()?, &SceneDesc::new(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], &[[0, 1, 2]]))?;
    /// assert_eq!(scene.edge_count(), 3);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn edge_count(&self) -> usize {
        // SAFETY: a live scene.
        unsafe { sys::minkq_scene_edge_count(self.raw.as_ptr()) }
    }

    /// The scene's edges, numbered as EE pairs number them.
    ///
    /// ```
    /// # use minkq::*;
    /// let scene = Scene::new(&Device::cpu()?, &SceneDesc::new(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], &[[2, 1, 0]]))?;
    /// assert_eq!(scene.edges()?, vec![[0, 1], [0, 2], [1, 2]]);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn edges(&self) -> Result<Vec<[i32; 2]>> {
        let mut edges = vec![[0i32; 2]; self.edge_count()];
        // SAFETY: `edges` holds 2 * len int32.
        check(unsafe { sys::minkq_scene_edges(self.raw.as_ptr(), edges.as_mut_ptr().cast(), edges.len()) })?;
        Ok(edges)
    }

    /// Runs a query into a library-owned buffer that grows as needed; returns its pairs,
    /// (vertex, triangle) for VT and (e, f) with e < f for EE.
    ///
    /// Errors: [`Error::InvalidArgument`] (a VT query on a scene built without VT, sphere
    /// mode for EE, a negative radius), [`Error::NonFinite`] (radius).
    ///
    /// ```
    /// # use minkq::*;
    /// # let device = Device::cpu()?;
    /// # let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]];
    /// # let triangles = [[0, 1, 2], [3, 4, 5]];
    /// # let scene = Scene::new(&device, &SceneDesc::new(&vertices, &triangles))?;
    /// let mut pairs = PairBuffer::new()?;
    /// let ee = scene.query(&Query::ee(Mode::Box, 0.2).with_flags(QueryFlags::LEAF_EXACT), &mut pairs)?;
    /// assert_eq!(ee.len(), 9); // every lower edge against every upper edge
    /// assert!(ee.iter().all(|&[e, f]| e < f));
    /// let err = scene.query(&Query::ee(Mode::Sphere, 0.2), &mut pairs).unwrap_err();
    /// assert!(matches!(err, Error::InvalidArgument(_)));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn query<'r>(&self, query: &Query, out: &'r mut PairBuffer) -> Result<&'r [[i32; 2]]> {
        let desc = query.raw();
        // SAFETY: a live scene and result, a valid description.
        check(unsafe { sys::minkq_scene_query_result(self.raw.as_ptr(), &desc, out.as_ptr()) })?;
        Ok(out.pairs())
    }

    /// Runs a query into the caller's buffer. If more pairs exist than `out` holds, nothing is
    /// written past it and the error is [`Error::Capacity`] with the exact count needed.
    ///
    /// ```
    /// # use minkq::*;
    /// # let device = Device::cpu()?;
    /// # let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]];
    /// # let triangles = [[0, 1, 2], [3, 4, 5]];
    /// # let scene = Scene::new(&device, &SceneDesc::new(&vertices, &triangles))?;
    /// let query = Query::vt(Mode::Sphere, 0.2);
    /// let mut small = [[0; 2]; 4];
    /// match scene.query_into(&query, &mut small) {
    ///     Err(Error::Capacity { needed, .. }) => assert_eq!(needed, 6),
    ///     other => panic!("{other:?}"),
    /// }
    /// let mut enough = vec![[0; 2]; 6];
    /// assert_eq!(scene.query_into(&query, &mut enough)?.count, 6);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn query_into(&self, query: &Query, out: &mut [[i32; 2]]) -> Result<QueryInfo> {
        self.query_to(query, PairsOut::from_slice(out))
    }

    /// Runs a query into a [`PairsOut`]: host memory, or (on a CUDA device) device memory
    /// written in place, ready for any stream when this returns. [`Error::Capacity`] with the
    /// exact count when it is too small; nothing is written past it.
    ///
    /// ```
    /// # use minkq::*;
    /// # let device = Device::cpu()?;
    /// # let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]];
    /// # let triangles = [[0, 1, 2], [3, 4, 5]];
    /// # let scene = Scene::new(&device, &SceneDesc::new(&vertices, &triangles))?;
    /// let mut pairs = [[0; 2]; 8];
    /// let info = scene.query_to(&Query::vt(Mode::Sphere, 0.2).with_flags(QueryFlags::CANONICAL), PairsOut::from_slice(&mut pairs))?;
    /// assert_eq!(&pairs[..info.count as usize], &[[0, 1], [1, 1], [2, 1], [3, 0], [4, 0], [5, 0]]);
    /// // Device memory on a CPU device is refused before it is written.
    /// // SAFETY: never written: the CPU device rejects device memory.
    /// let on_gpu = unsafe { PairsOut::from_raw_parts(pairs.as_mut_ptr().cast(), 8, Memory::Device) };
    /// assert!(matches!(scene.query_to(&Query::vt(Mode::Sphere, 0.2), on_gpu), Err(Error::InvalidArgument(_))));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn query_to(&self, query: &Query, out: PairsOut<'_>) -> Result<QueryInfo> {
        self.query_raw(query, out.data(), out.capacity(), out.memory())
    }

    /// Runs a query into a `Vec`, growing it to the exact count when it is too small (the
    /// query then runs twice); on success the `Vec` holds exactly the pairs.
    ///
    /// ```
    /// # use minkq::*;
    /// # let device = Device::cpu()?;
    /// # let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]];
    /// # let triangles = [[0, 1, 2], [3, 4, 5]];
    /// # let scene = Scene::new(&device, &SceneDesc::new(&vertices, &triangles))?;
    /// let mut pairs = Vec::new();
    /// let info = scene.query_vec(&Query::ee(Mode::Box, 0.2).with_flags(QueryFlags::CANONICAL), &mut pairs)?;
    /// assert_eq!(info.count as usize, pairs.len());
    /// assert!(pairs.windows(2).all(|w| w[0] < w[1]));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn query_vec(&self, query: &Query, out: &mut Vec<[i32; 2]>) -> Result<QueryInfo> {
        query_vec(out, |pairs, capacity| self.query_raw(query, pairs, capacity, Memory::Host))
    }

    /// Runs a VT and an EE query in one pass (`minkq_scene_query_vt_ee`: one parallel loop on
    /// the CPU, one kernel launch and one count readback on CUDA) into two library-owned
    /// buffers that grow as needed; returns the VT and the EE pairs, each exactly what
    /// [`Scene::query`] gives it alone.
    ///
    /// Errors: as [`Scene::query`] for either query, and [`Error::InvalidArgument`] when `vt`
    /// is not a VT query or `ee` not an EE query.
    ///
    /// ```
    /// # use minkq::*;
    /// # let device = Device::cpu()?;
    /// # let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]];
    /// # let triangles = [[0, 1, 2], [3, 4, 5]];
    /// # let scene = Scene::new(&device, &SceneDesc::new(&vertices, &triangles))?;
    /// let (mut vt_pairs, mut ee_pairs) = (PairBuffer::new()?, PairBuffer::new()?);
    /// let contacts = QueryFlags::LEAF_EXACT | QueryFlags::CANONICAL;
    /// let (vt, ee) = scene.query_vt_ee(
    ///     &Query::vt(Mode::Box, 0.2).with_flags(contacts),
    ///     &Query::ee(Mode::Box, 0.2).with_flags(contacts),
    ///     &mut vt_pairs,
    ///     &mut ee_pairs,
    /// )?;
    /// assert_eq!(vt, &[[0, 1], [1, 1], [2, 1], [3, 0], [4, 0], [5, 0]]);
    /// assert_eq!(ee.len(), 9); // every lower edge against every upper edge
    /// let swapped = scene.query_vt_ee(&Query::ee(Mode::Box, 0.2), &Query::vt(Mode::Box, 0.2), &mut vt_pairs, &mut ee_pairs);
    /// assert!(matches!(swapped, Err(Error::InvalidArgument(_))));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn query_vt_ee<'r>(
        &self,
        vt: &Query,
        ee: &Query,
        vt_out: &'r mut PairBuffer,
        ee_out: &'r mut PairBuffer,
    ) -> Result<(&'r [[i32; 2]], &'r [[i32; 2]])> {
        let (vt_desc, ee_desc) = (vt.raw(), ee.raw());
        // SAFETY: a live scene, two distinct live results (two `&mut`), valid descriptions.
        check(unsafe {
            sys::minkq_scene_query_vt_ee_result(self.raw.as_ptr(), &vt_desc, &ee_desc, vt_out.as_ptr(), ee_out.as_ptr())
        })?;
        Ok((vt_out.pairs(), ee_out.pairs()))
    }

    /// Runs a VT and an EE query in one pass into two [`PairsOut`] in the same memory (host,
    /// or device memory on a CUDA device); returns the VT and the EE query's info. A query
    /// whose pairs fit is written in full; if either does not fit, the error is
    /// [`Error::Capacity`] with the exact count of the first that does not (VT before EE; the
    /// message names it), and nothing is written past either buffer.
    ///
    /// ```
    /// # use minkq::*;
    /// # let device = Device::cpu()?;
    /// # let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]];
    /// # let triangles = [[0, 1, 2], [3, 4, 5]];
    /// # let scene = Scene::new(&device, &SceneDesc::new(&vertices, &triangles))?;
    /// let (vt, ee) = (Query::vt(Mode::Sphere, 0.2), Query::ee(Mode::Box, 0.2));
    /// let (mut vt_pairs, mut ee_pairs) = ([[0; 2]; 8], [[0; 2]; 4]);
    /// let short = scene.query_vt_ee_to(&vt, &ee, PairsOut::from_slice(&mut vt_pairs), PairsOut::from_slice(&mut ee_pairs));
    /// assert!(matches!(short, Err(Error::Capacity { needed: 9, .. })));
    /// let mut ee_pairs = [[0; 2]; 9];
    /// let (vt_info, ee_info) = scene.query_vt_ee_to(&vt, &ee, PairsOut::from_slice(&mut vt_pairs), PairsOut::from_slice(&mut ee_pairs))?;
    /// assert_eq!((vt_info.count, ee_info.count), (6, 9));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn query_vt_ee_to(
        &self,
        vt: &Query,
        ee: &Query,
        vt_out: PairsOut<'_>,
        ee_out: PairsOut<'_>,
    ) -> Result<(QueryInfo, QueryInfo)> {
        if vt_out.memory() != ee_out.memory() {
            return Err(Error::InvalidArgument("vt_out and ee_out are in different memories".into()));
        }
        let (vt_desc, ee_desc) = (vt.raw(), ee.raw());
        let (mut vt_info, mut ee_info) = (QueryInfo::raw(), QueryInfo::raw());
        // SAFETY: each PairsOut holds 2 * capacity writable int32 in its memory (its
        // constructor promised it); the infos are distinct.
        let status = unsafe {
            sys::minkq_scene_query_vt_ee(
                self.raw.as_ptr(),
                &vt_desc,
                &ee_desc,
                vt_out.data(),
                vt_out.capacity(),
                ee_out.data(),
                ee_out.capacity(),
                vt_out.memory().raw(),
                &mut vt_info,
                &mut ee_info,
            )
        };
        match check(status) {
            Ok(()) => Ok((QueryInfo::from_raw(&vt_info, vt.flags), QueryInfo::from_raw(&ee_info, ee.flags))),
            Err(Error::Capacity { message, .. }) => {
                let needed = if vt_info.count > vt_out.capacity() as u64 { vt_info.count } else { ee_info.count };
                Err(Error::Capacity { needed, message })
            }
            Err(e) => Err(e),
        }
    }

    /// Counts a query's work ([`QueryFlags::STATS`] added) in one run that keeps no pairs:
    /// nodes visited, node tests, primitive tests and candidates (the pair count), the same on
    /// every backend.
    ///
    /// ```
    /// # use minkq::*;
    /// # let device = Device::cpu()?;
    /// # let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]];
    /// # let triangles = [[0, 1, 2], [3, 4, 5]];
    /// # let scene = Scene::new(&device, &SceneDesc::new(&vertices, &triangles))?;
    /// let work = scene.work(&Query::vt(Mode::Sphere, 0.2))?;
    /// assert_eq!(work.candidates, 6);
    /// assert!(work.primitive_tests >= work.candidates && work.node_tests >= work.primitive_tests);
    /// assert!(matches!(scene.work(&Query::ee(Mode::Sphere, 0.2)), Err(Error::InvalidArgument(_))));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn work(&self, query: &Query) -> Result<WorkStats> {
        let desc = query.with_flags(query.flags | QueryFlags::STATS).raw();
        let mut info = QueryInfo::raw();
        // SAFETY: capacity 0: nothing is written through the null pointer; the library fills
        // the stats also when it reports CAPACITY.
        let status = unsafe {
            sys::minkq_scene_query(self.raw.as_ptr(), &desc, ptr::null_mut(), 0, Memory::Host.raw(), &mut info)
        };
        match check(status) {
            Ok(()) | Err(Error::Capacity { .. }) => {
                Ok(QueryInfo::from_raw(&info, QueryFlags::STATS).stats.unwrap_or_default())
            }
            Err(e) => Err(e),
        }
    }

    /// Reserves, on the scene's device, the scratch its asynchronous calls use, so that they
    /// never allocate (`minkq_scene_reserve`): [`Reserve::REFIT`] for
    /// [`Scene::refit_async`], [`Reserve::REBUILD`] for [`Scene::rebuild_async`] (and
    /// refits), and `canonical_capacity` pairs for the sort of asynchronous queries with
    /// [`QueryFlags::CANONICAL`] (whose capacity may not exceed it). Queries without
    /// `CANONICAL` need no reservation. Reservations only grow and last as long as the scene.
    /// A blocking call (it may allocate and synchronise): make it before capturing a graph.
    ///
    /// Errors: [`Error::SizeOverflow`] (`canonical_capacity`), [`Error::OutOfMemory`],
    /// [`Error::Device`].
    ///
    /// ```
    /// # use minkq::*;
    /// # let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]];
    /// let mut scene = Scene::new(&Device::cpu()?, &SceneDesc::new(&vertices, &[[0, 1, 2], [3, 4, 5]]))?;
    /// // Without the reservation, an asynchronous refit is refused at once.
    /// assert!(matches!(scene.refit_async(Buffer::from_slice(&vertices), Stream::null()), Err(Error::InvalidArgument(_))));
    /// scene.reserve(Reserve::REFIT, 64)?;
    /// scene.refit_async(Buffer::from_slice(&vertices), Stream::null())?;
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn reserve(&mut self, flags: Reserve, canonical_capacity: usize) -> Result<()> {
        // SAFETY: a live scene.
        check(unsafe { sys::minkq_scene_reserve(self.raw.as_ptr(), flags.bits(), canonical_capacity) })
    }

    /// [`Scene::refit_buffer`], enqueued on `stream` (`minkq_scene_refit_async`): on a CUDA
    /// device the vertices are device memory, read by the work enqueued (so the promise of
    /// [`Buffer::from_raw_parts`] lasts until that work has run), and the call returns without
    /// waiting, allocating or synchronising, so that it can be captured into a CUDA graph. On
    /// the CPU the vertices are host memory and the refit has run when this returns. Needs
    /// [`Reserve::REFIT`].
    ///
    /// Non-finite coordinates are found where the data is read, on the device: such a refit
    /// leaves the scene's positions as they were and records the scene's pending error, which
    /// [`Scene::async_status`] returns (and clears). Errors at once: as
    /// [`Scene::refit_buffer`] except [`Error::NonFinite`]; [`Error::InvalidArgument`] without
    /// the reservation, or for host vertices on a CUDA device (device ones on the CPU).
    ///
    /// ```
    /// # use minkq::*;
    /// let mut vertices = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0],
    ///                         [0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]];
    /// let mut scene = Scene::new(&Device::cpu()?, &SceneDesc::new(&vertices, &[[0, 1, 2], [3, 4, 5]]))?;
    /// scene.reserve(Reserve::REFIT, 0)?;
    /// vertices[5][1] = f32::NAN;
    /// scene.refit_async(Buffer::from_slice(&vertices), Stream::null())?; // accepted at once...
    /// let err = scene.async_status(Stream::null()).unwrap_err(); // ...and reported here
    /// assert!(matches!(&err, Error::NonFinite(m) if m.contains("vertex 5")));
    /// scene.async_status(Stream::null())?; // cleared
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn refit_async(&mut self, vertices: Buffer<'_>, stream: Stream) -> Result<()> {
        // SAFETY: a live scene; the buffer's constructor promised records readable until the
        // enqueued work has run (host slices are read before this returns: CPU devices only);
        // the stream's constructor promised a stream of the scene's device.
        check(unsafe { sys::minkq_scene_refit_async(self.raw.as_ptr(), vertices.raw(), stream.as_raw()) })
    }

    /// [`Scene::rebuild_buffer`], enqueued on `stream` as [`Scene::refit_async`] is
    /// (`minkq_scene_rebuild_async`): the trees [`Scene::rebuild`] builds. Needs
    /// [`Reserve::REBUILD`]. Vertices with a NaN or infinity leave the positions as they were
    /// (the trees are then built for those) and are reported by [`Scene::async_status`].
    ///
    /// ```
    /// # use minkq::*;
    /// let mut vertices = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0],
    ///                         [0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]];
    /// let mut scene = Scene::new(&Device::cpu()?, &SceneDesc::new(&vertices, &[[0, 1, 2], [3, 4, 5]]))?;
    /// assert!(matches!(scene.rebuild_async(Buffer::from_slice(&vertices), Stream::null()), Err(Error::InvalidArgument(_))));
    /// scene.reserve(Reserve::REBUILD, 0)?;
    /// for v in &mut vertices[3..] {
    ///     v[2] = 1.0; // lift the upper triangle away
    /// }
    /// scene.rebuild_async(Buffer::from_slice(&vertices), Stream::null())?;
    /// scene.async_status(Stream::null())?;
    /// assert_eq!(scene.tree_growth()?, 1.0);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn rebuild_async(&mut self, vertices: Buffer<'_>, stream: Stream) -> Result<()> {
        // SAFETY: as in refit_async.
        check(unsafe { sys::minkq_scene_rebuild_async(self.raw.as_ptr(), vertices.raw(), stream.as_raw()) })
    }

    /// [`Scene::query_to`], enqueued on `stream` (`minkq_scene_query_async`): writes the exact
    /// number of pairs to `count`, also when it exceeds `out`'s capacity, and min(count,
    /// capacity) of the pairs to `out`, never past it (which ones, when they do not all fit, is
    /// unspecified, as is their order). Never [`Error::Capacity`]: a simulator reads the
    /// count and grows its buffer between steps. On a CUDA device `out` and `count` are device
    /// memory, written by the enqueued work after this returns (the promise of their
    /// `from_raw_parts` lasts until it has run); on the CPU they are host memory, written when
    /// this returns. [`QueryFlags::CANONICAL`] sorts the pairs when they fit and needs a
    /// capacity within [`Scene::reserve`]'s canonical capacity.
    ///
    /// Errors at once: as [`Scene::query_to`] for the query and buffers;
    /// [`Error::InvalidArgument`] for a canonical capacity over the reservation, or memory of
    /// the wrong kind for the device (host memory on CUDA, device memory on the CPU);
    /// [`Error::Unsupported`] for [`QueryFlags::DIGEST`] and [`QueryFlags::STATS`] (they need a
    /// host read).
    ///
    /// ```
    /// # use minkq::*;
    /// # let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]];
    /// let mut scene = Scene::new(&Device::cpu()?, &SceneDesc::new(&vertices, &[[0, 1, 2], [3, 4, 5]]))?;
    /// scene.reserve(Reserve::empty(), 8)?;
    /// let query = Query::vt(Mode::Sphere, 0.2).with_flags(QueryFlags::CANONICAL);
    /// let (mut pairs, mut count) = ([[-1; 2]; 8], 0u64);
    /// scene.query_async(&query, PairsOut::from_slice(&mut pairs), CountOut::from_mut(&mut count), Stream::null())?;
    /// assert_eq!(count, 6);
    /// assert_eq!(&pairs[..6], &[[0, 1], [1, 1], [2, 1], [3, 0], [4, 0], [5, 0]]);
    /// // Too small: the exact count, and no pair written past the buffer.
    /// scene.query_async(&query, PairsOut::from_slice(&mut pairs[..4]), CountOut::from_mut(&mut count), Stream::null())?;
    /// assert_eq!(count, 6);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn query_async(&self, query: &Query, out: PairsOut<'_>, count: CountOut<'_>, stream: Stream) -> Result<()> {
        self.check_async_memory("out", out.memory())?;
        self.check_async_memory("count", count.memory())?;
        let desc = query.raw();
        // SAFETY: a live scene; `out` holds 2 * capacity writable int32 and `count` one u64 in
        // the memory the device writes (checked above), until the enqueued work has run (the
        // promise of their constructors; host slices are written before this returns).
        check(unsafe {
            sys::minkq_scene_query_async(
                self.raw.as_ptr(),
                &desc,
                out.data(),
                out.capacity(),
                count.as_ptr(),
                stream.as_raw(),
            )
        })
    }

    /// [`Scene::query_vt_ee_to`], enqueued on `stream` (`minkq_scene_query_vt_ee_async`: one
    /// kernel launch for both queries on CUDA): each query's pairs and count as
    /// [`Scene::query_async`] gives it alone.
    ///
    /// Errors: those of [`Scene::query_async`] for either query, and
    /// [`Error::InvalidArgument`] when `vt` is not a VT query or `ee` not an EE query, or when
    /// the two counts are the same memory.
    ///
    /// ```
    /// # use minkq::*;
    /// # let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]];
    /// let scene = Scene::new(&Device::cpu()?, &SceneDesc::new(&vertices, &[[0, 1, 2], [3, 4, 5]]))?;
    /// let (mut vt_pairs, mut ee_pairs) = ([[0; 2]; 8], [[0; 2]; 4]);
    /// let (mut vt_count, mut ee_count) = (0, 0);
    /// scene.query_vt_ee_async(
    ///     &Query::vt(Mode::Sphere, 0.2),
    ///     &Query::ee(Mode::Box, 0.2),
    ///     PairsOut::from_slice(&mut vt_pairs),
    ///     CountOut::from_mut(&mut vt_count),
    ///     PairsOut::from_slice(&mut ee_pairs),
    ///     CountOut::from_mut(&mut ee_count),
    ///     Stream::null(),
    /// )?;
    /// assert_eq!((vt_count, ee_count), (6, 9)); // EE did not fit in 4: its exact count
    /// # Ok::<(), minkq::Error>(())
    /// ```
    #[allow(clippy::too_many_arguments)]
    pub fn query_vt_ee_async(
        &self,
        vt: &Query,
        ee: &Query,
        vt_out: PairsOut<'_>,
        vt_count: CountOut<'_>,
        ee_out: PairsOut<'_>,
        ee_count: CountOut<'_>,
        stream: Stream,
    ) -> Result<()> {
        self.check_async_memory("vt_out", vt_out.memory())?;
        self.check_async_memory("vt_count", vt_count.memory())?;
        self.check_async_memory("ee_out", ee_out.memory())?;
        self.check_async_memory("ee_count", ee_count.memory())?;
        let (vt_desc, ee_desc) = (vt.raw(), ee.raw());
        // SAFETY: as in query_async, for both queries' buffers.
        check(unsafe {
            sys::minkq_scene_query_vt_ee_async(
                self.raw.as_ptr(),
                &vt_desc,
                &ee_desc,
                vt_out.data(),
                vt_out.capacity(),
                vt_count.as_ptr(),
                ee_out.data(),
                ee_out.capacity(),
                ee_count.as_ptr(),
                stream.as_raw(),
            )
        })
    }

    /// Waits for the work enqueued on `stream` (CUDA), then returns the scene's pending error
    /// and clears it (`minkq_scene_async_status`): `Ok` when every asynchronous refit and
    /// rebuild since the last call (or the reservation) accepted its vertices, else the error
    /// of the first that did not, [`Error::NonFinite`] with a message naming the call and the
    /// vertex (`"minkq_scene_refit_async: vertex 12 has a non-finite coordinate; the scene
    /// kept its positions"`). A blocking call: after it, the counts and pairs of the queries
    /// enqueued on `stream` are ready. See [`Scene::refit_async`] for an example.
    pub fn async_status(&mut self, stream: Stream) -> Result<()> {
        // SAFETY: a live scene; the stream's constructor promised a stream of its device.
        check(unsafe { sys::minkq_scene_async_status(self.raw.as_ptr(), stream.as_raw()) })
    }

    /// The memory the asynchronous calls of this scene's device write: host on the CPU,
    /// device on CUDA (the C API cannot tell host from device pointers on the CPU).
    fn check_async_memory(&self, what: &str, memory: Memory) -> Result<()> {
        // SAFETY: the scene's live device.
        let cuda = unsafe { sys::minkq_device_backend(self._device.as_ptr()) } == sys::MINKQ_BACKEND_CUDA;
        let (wanted, device) = if cuda { (Memory::Device, "a CUDA") } else { (Memory::Host, "a CPU") };
        if memory == wanted {
            Ok(())
        } else {
            Err(Error::InvalidArgument(format!(
                "{what}: {} memory, but asynchronous queries on {device} device write {} memory",
                memory.name(),
                wanted.name()
            )))
        }
    }

    fn query_raw(&self, query: &Query, pairs: *mut i32, capacity: usize, memory: Memory) -> Result<QueryInfo> {
        let desc = query.raw();
        let mut info = QueryInfo::raw();
        // SAFETY: `pairs` holds 2 * capacity writable int32 in `memory` (a slice, a Vec's
        // spare capacity, or a PairsOut whose constructor promised it).
        let status =
            unsafe { sys::minkq_scene_query(self.raw.as_ptr(), &desc, pairs, capacity, memory.raw(), &mut info) };
        match check(status) {
            Ok(()) => Ok(QueryInfo::from_raw(&info, query.flags)),
            Err(Error::Capacity { message, .. }) => Err(Error::Capacity { needed: info.count, message }),
            Err(e) => Err(e),
        }
    }
}

impl Drop for Scene {
    fn drop(&mut self) {
        // SAFETY: created by minkq_scene_create and released once, before its device (whose
        // handle this scene still holds).
        unsafe { sys::minkq_scene_release(self.raw.as_ptr()) }
    }
}

impl fmt::Debug for Scene {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Scene")
            .field("vertices", &self.vertex_count())
            .field("triangles", &self.triangle_count())
            .field("edges", &self.edge_count())
            .finish()
    }
}
