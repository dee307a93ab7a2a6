//! Mesh scenes (`minkq_scene`): the [`Scene`] type, its creation, refit and rebuild, and its
//! counts. Its descriptions, scenes of many geometries, blocking queries, stream-ordered calls
//! and swept positions live in the submodules.
use std::fmt;
use std::ptr::{self, NonNull};
use std::sync::Arc;

use crate::buffer::sealed::Precision;
use crate::buffer::{Buffer, Vertex};
use crate::device::{Device, DeviceHandle};
use crate::error::{check, Error, Result};
use crate::geometry::GeometryFlags;
use crate::inputs::Vertices;
use crate::query::SceneFlags;
use crate::sys;

mod desc;
mod geometries;
mod geometry_moves;
mod queries;
mod stream_ordered;
mod swept;

pub use desc::{SceneBuffers, SceneDesc};
use geometries::Layout;

/// A triangle mesh, or codimensional elements (particles, rods: [`SceneDesc::codim`]), on a
/// device with the BVHs its flags ask for, answering VT, EE, VV and EV queries
/// (`minkq_scene`); or a scene of many such geometries ([`Scene::from_geometries`]), answering
/// the same queries with self and cross pairs. Released when dropped; keeps its device alive.
///
/// Threads: `Send` but not `Sync`. The C API says one scene must not be used by two threads at
/// the same time, so a `&Scene` may not cross threads (its queries would then run
/// concurrently); moving the scene to another thread is allowed. Wrap it in a `Mutex` to share
/// it.
///
/// Precision: a scene's vertices are `[f32; 3]` ([`SceneDesc::new`], [`Scene::refit`],
/// [`Scene::rebuild`]) or, for a [`SceneFlags::FLOAT64`] scene, `[f64; 3]`
/// ([`SceneDesc::new_f64`], [`Scene::refit`], [`Scene::rebuild`]); the scene remembers
/// which ([`Scene::is_float64`]) and refuses vertices of the other precision.
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
    /// Created with [`SceneFlags::FLOAT64`], or every moving geometry is float64: the vertex
    /// buffers of whole-scene calls hold 3 doubles per record.
    float64: bool,
    /// Each geometry's precision and first global ids (one geometry for a one-mesh scene).
    layout: Layout,
    _device: Arc<DeviceHandle>,
}

// SAFETY: the C API allows an object to be used from any thread, one thread at a time. A
// `Scene` is not `Sync`, so only its owner (or a `&mut`) can call into it; its device may be
// shared by scenes on other threads (documented by the C API).
unsafe impl Send for Scene {}

impl Scene {
    /// Copies the mesh to the device and builds the trees `desc.flags` asks for: a float
    /// scene for `[f32; 3]` vertices ([`SceneDesc::new`]), a [`SceneFlags::FLOAT64`] scene for
    /// `[f64; 3]` ones ([`SceneDesc::new_f64`], which has an example).
    ///
    /// Errors: [`Error::NonFinite`] (`"vertex 12 has a non-finite coordinate (...)"`; also a
    /// double beyond the float range), [`Error::IndexOutOfRange`], [`Error::SizeOverflow`],
    /// [`Error::InvalidArgument`] (no query kind in the flags, [`SceneFlags::FLOAT64`] with
    /// `[f32; 3]` vertices).
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
    pub fn new<V: Vertex>(device: &Device, desc: &SceneDesc<'_, V>) -> Result<Scene> {
        Scene::from_buffers(device, &SceneBuffers::from(desc))
    }

    /// [`Scene::new`] over [`Buffer`]s: strided records in host or (on a CUDA device) device
    /// memory, read in place. The scene keeps its own copy; the buffers may change or go
    /// away once this returns. Device memory on a CPU device is [`Error::InvalidArgument`],
    /// as is a vertex slice whose precision the flags contradict: `[f64; 3]` without
    /// [`SceneFlags::FLOAT64`], `[f32; 3]` with it (example at [`SceneBuffers::flags`]).
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
        let float64 = desc.flags.contains(SceneFlags::FLOAT64);
        let raw_desc = sys::minkq_scene_desc {
            flags: desc.flags.bits(),
            vertices: vertex_buffer("create", &desc.vertices, float64, Holder::Scene)?,
            triangles: desc.triangles.raw(),
            edges: desc.edges.raw(),
        };
        let mut raw = ptr::null_mut();
        // SAFETY: the buffers' constructors promise readable records for their lifetime,
        // which outlives this call; the library copies them before returning.
        check(unsafe { sys::minkq_scene_create(device.handle.as_ptr(), &raw_desc, &mut raw) })?;
        let raw = NonNull::new(raw).ok_or_else(|| Error::Internal("minkq_scene_create returned NULL".into()))?;
        let mut flags = GeometryFlags::SELF;
        if desc.flags.contains(SceneFlags::DROP_INCIDENT) {
            flags |= GeometryFlags::DROP_INCIDENT;
        }
        if float64 {
            flags |= GeometryFlags::FLOAT64;
        }
        Scene::from_raw(raw, device, vec![flags])
    }

    /// Owns a scene the library created from geometries of `flags` (FLOAT64 set where a
    /// geometry's vertices are doubles); releases it if its layout cannot be read.
    fn from_raw(raw: NonNull<sys::minkq_scene>, device: &Device, flags: Vec<GeometryFlags>) -> Result<Scene> {
        let layout = Layout::empty();
        let mut scene = Scene { raw, float64: false, layout, _device: Arc::clone(&device.handle) };
        scene.layout = Layout::read(&scene, flags)?;
        scene.float64 = scene.layout.moving_float64();
        Ok(scene)
    }

    /// Moves the vertices (same count) and refits the trees in place: the per-step call of a
    /// simulation. On error the scene keeps its previous positions. A refit keeps the grouping
    /// of the last build: after large deformations the boxes overlap more and queries visit
    /// more nodes ([`Scene::tree_growth`] measures it, [`Scene::rebuild`] resets it); the pairs
    /// found never change.
    ///
    /// The vertices are any [`Vertices`]: `[f32; 3]`, or `[f64; 3]` for a
    /// [`SceneFlags::FLOAT64`] scene (rounded to float, the query radii widened by twice the
    /// farthest the rounding moved a vertex, so that every pair within r in double is
    /// reported), as a slice, `Vec`, array or [`Buffer`] (strided records, host or, on a CUDA
    /// device, device memory read in place). Vertices of the other precision are
    /// [`Error::InvalidArgument`] (a raw buffer is read as the scene's flag says); a double
    /// beyond the float range is [`Error::NonFinite`], as a NaN is.
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
    pub fn refit<'v>(&mut self, vertices: impl Vertices<'v>) -> Result<()> {
        let vertices = self.vertex_buffer("refit", &vertices.into_buffer())?;
        // SAFETY: a live scene; the buffer's constructor promised readable records, of the
        // scene's precision where the buffer knows it (checked above).
        check(unsafe { sys::minkq_scene_refit(self.raw.as_ptr(), vertices) })
    }

    /// [`Scene::refit`] with `[f64; 3]` vertices, for a [`SceneFlags::FLOAT64`] scene
    /// ([`SceneDesc::new_f64`]): rounded to float, the query radii widened by twice the
    /// farthest the rounding moved a vertex, so that every pair within r in double is
    /// reported. A float scene refuses them with [`Error::InvalidArgument`]; a double beyond
    /// the float range is [`Error::NonFinite`], as a NaN is.
    ///
    /// ```
    /// # use minkq::*;
    /// // A triangle in the plane x = 20000.0009 and a vertex 1 + 0.95e-3 in front of it, where
    /// // floats lie 2^-9 apart: rounding would pull the pair apart once the vertex comes near.
    /// let (plane, point) = (20000.0009, 20000.00185);
    /// let mut vertices = vec![[plane, -1.0, -1.0], [plane, 2.0, -1.0], [plane, -1.0, 2.0], [point + 1.0, 0.0, 0.0]];
    /// let mut scene = Scene::new(&Device::cpu()?, &SceneDesc::new_f64(&vertices, &[[0, 1, 2]]))?;
    /// let query = Query::vt(Mode::Sphere, 1e-3).with_flags(QueryFlags::LEAF_EXACT);
    /// let mut pairs = PairBuffer::new()?;
    /// assert!(scene.query(&query, &mut pairs)?.is_empty());
    /// vertices[3][0] = point; // 0.95e-3 from the triangle in double, 2^-9 in float
    /// assert!(point as f32 - plane as f32 > 1e-3);
    /// scene.refit(&vertices)?;
    /// assert_eq!(scene.query(&query, &mut pairs)?, &[[3, 0]]);
    ///
    /// // Floats are refused: the scene reads 3 doubles per vertex.
    /// let floats: Vec<[f32; 3]> = vertices.iter().map(|v| v.map(|x| x as f32)).collect();
    /// let err = scene.refit(&floats).unwrap_err();
    /// assert_eq!(err, Error::InvalidArgument("refit: [f32; 3] vertices, but a scene with SceneFlags::FLOAT64 reads [f64; 3]".into()));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    #[deprecated(note = "use `Scene::refit`, which takes `[f64; 3]` vertices too")]
    pub fn refit_f64(&mut self, vertices: &[[f64; 3]]) -> Result<()> {
        self.refit(vertices)
    }

    /// [`Scene::refit`] from a [`Buffer`]: strided records, host or (on a CUDA device) device
    /// memory, read in place on the device. On error the scene keeps its previous positions.
    /// The records are 3 floats, or 3 doubles on a [`SceneFlags::FLOAT64`] scene
    /// (`[f64; 3]`); a buffer made from a slice of the other precision is
    /// [`Error::InvalidArgument`], a raw buffer is read as the scene's flag says.
    ///
    /// ```
    /// # use minkq::*;
    /// let vertices = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    /// let mut scene = Scene::new(&Device::cpu()?, &SceneDesc::new(&vertices, &[[0, 1, 2]]))?;
    /// // x, y, z and a fourth float per vertex (16-byte records), as a vec4 array holds them.
    /// let moved = [[0.0f32, 0.0, 1.0, 0.0], [1.0, 0.0, 1.0, 0.0], [0.0, 1.0, 1.0, 0.0]];
    /// // SAFETY: three 16-byte records starting with x, y, z, borrowed from `moved`.
    /// scene.refit(unsafe { Buffer::from_raw_parts(moved.as_ptr().cast(), 16, 3, Memory::Host) })?;
    /// # Ok::<(), minkq::Error>(())
    /// ```
    #[deprecated(note = "use `Scene::refit`, which takes a `Buffer` too")]
    pub fn refit_buffer(&mut self, vertices: Buffer<'_>) -> Result<()> {
        self.refit(vertices)
    }

    /// Moves the vertices (same count) like [`Scene::refit`] and builds the trees afresh for
    /// the new positions: the trees [`Scene::new`] would build there, with the same topology
    /// and edge numbering. The pairs are the same as after a refit; only the speed of later
    /// queries differs. Worth it once large motions have raised [`Scene::tree_growth`] (above
    /// about 1.5), and every so many steps when the mesh changes shape a lot. Same errors as
    /// [`Scene::refit`]; on error the scene keeps its positions and trees. Takes the same
    /// [`Vertices`] as [`Scene::refit`].
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
    pub fn rebuild<'v>(&mut self, vertices: impl Vertices<'v>) -> Result<()> {
        let vertices = self.vertex_buffer("rebuild", &vertices.into_buffer())?;
        // SAFETY: as in refit.
        check(unsafe { sys::minkq_scene_rebuild(self.raw.as_ptr(), vertices) })
    }

    /// [`Scene::rebuild`] with `[f64; 3]` vertices, for a [`SceneFlags::FLOAT64`] scene: the
    /// trees [`Scene::new`] would build for them. Same errors as [`Scene::refit`]; on
    /// error the scene keeps its positions and trees.
    ///
    /// ```
    /// # use minkq::*;
    /// let mut vertices = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0],
    ///                         [0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]];
    /// let triangles = [[0, 1, 2], [3, 4, 5]];
    /// let mut scene = Scene::new(&Device::cpu()?, &SceneDesc::new_f64(&vertices, &triangles))?;
    /// for v in &mut vertices[3..] {
    ///     v[2] = 1.0; // lift the upper triangle away
    /// }
    /// scene.rebuild(&vertices)?;
    /// assert!(scene.query(&Query::vt(Mode::Sphere, 0.2), &mut PairBuffer::new()?)?.is_empty());
    /// assert_eq!(scene.tree_growth()?, 1.0);
    /// // A double beyond the float range cannot be rounded to a float: non-finite.
    /// vertices[4][0] = 1e39;
    /// assert!(matches!(scene.rebuild(&vertices), Err(Error::NonFinite(m)) if m.contains("vertex 4")));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    #[deprecated(note = "use `Scene::rebuild`, which takes `[f64; 3]` vertices too")]
    pub fn rebuild_f64(&mut self, vertices: &[[f64; 3]]) -> Result<()> {
        self.rebuild(vertices)
    }

    /// [`Scene::rebuild`] from a [`Buffer`]: strided records, host or (on a CUDA device)
    /// device memory, read in place on the device. On error the scene keeps its positions and
    /// trees. Records and precision as for [`Scene::refit`].
    ///
    /// ```
    /// # use minkq::*;
    /// let vertices = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    /// let mut scene = Scene::new(&Device::cpu()?, &SceneDesc::new(&vertices, &[[0, 1, 2]]))?;
    /// // x, y, z and a fourth float per vertex (16-byte records), as a vec4 array holds them.
    /// let moved = [[0.0f32, 0.0, 1.0, 0.0], [1.0, 0.0, 1.0, 0.0], [0.0, f32::NAN, 1.0, 0.0]];
    /// // SAFETY: three 16-byte records starting with x, y, z, borrowed from `moved`.
    /// let err = scene.rebuild(unsafe { Buffer::from_raw_parts(moved.as_ptr().cast(), 16, 3, Memory::Host) });
    /// assert!(matches!(err, Err(Error::NonFinite(m)) if m.starts_with("vertex 2 ")));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    #[deprecated(note = "use `Scene::rebuild`, which takes a `Buffer` too")]
    pub fn rebuild_buffer(&mut self, vertices: Buffer<'_>) -> Result<()> {
        self.rebuild(vertices)
    }

    /// Whether the scene was created with [`SceneFlags::FLOAT64`]: its vertices are
    /// `[f64; 3]` ([`Scene::refit`], [`Scene::rebuild`]) rather than `[f32; 3]`. For a
    /// scene of geometries: whether every moving geometry is float64 (and there is one), so
    /// that whole-scene refits and rebuilds take `[f64; 3]`.
    ///
    /// ```
    /// # use minkq::*;
    /// let floats = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    /// let doubles = [[0.0f64, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    /// let device = Device::cpu()?;
    /// assert!(!Scene::new(&device, &SceneDesc::new(&floats, &[[0, 1, 2]]))?.is_float64());
    /// assert!(Scene::new(&device, &SceneDesc::new_f64(&doubles, &[[0, 1, 2]]))?.is_float64());
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn is_float64(&self) -> bool {
        self.float64
    }

    /// The C buffer of `call`'s vertices on this scene: see [`vertex_buffer`]. A scene whose
    /// moving geometries mix precisions takes none: the library refuses the call with its
    /// message before reading the buffer.
    fn vertex_buffer(&self, call: &str, vertices: &Buffer<'_>) -> Result<sys::minkq_buffer> {
        if self.layout.mixed_precision() {
            return Ok(vertices.raw());
        }
        vertex_buffer(call, vertices, self.float64, Holder::Scene)
    }

    /// How far the refits since the last build (creation or [`Scene::rebuild`]) have stretched
    /// the trees: their area cost (scale-free; it grows with the nodes a query visits) now over
    /// its value right after that build, the larger of the scene's trees. 1 after a build. It
    /// sees boxes that stretch, not a mesh folding or flattening into new neighbours (where a
    /// rebuild can still help). Rebuild when it passes about 1.5, and every so many steps when
    /// the mesh changes shape a lot (`minkq_scene_tree_growth` in `minkq.h`; what rebuilds
    /// bought on the benchmark scenes is in `docs/design-notes.md`). A tree whose elements all lie
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

    /// The number of vertices (of every geometry).
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

    /// The number of triangles (of every geometry).
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

    /// The number of edges (given, or derived for an EE scene; of every geometry).
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

    /// The scene's edges, numbered as EE pairs number them (in the global numbering, by global
    /// vertex ids, for a scene of geometries).
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
}

/// What holds the vertices a buffer is checked for: a whole scene or one of its geometries.
#[derive(Clone, Copy)]
enum Holder {
    Scene,
    Geometry,
}

impl Holder {
    /// The holder and its precision flag, as messages name them.
    fn names(self) -> (&'static str, &'static str) {
        match self {
            Holder::Scene => ("a scene", "SceneFlags::FLOAT64"),
            Holder::Geometry => ("a geometry", "GeometryFlags::FLOAT64"),
        }
    }
}

/// The C buffer of `call`'s vertices for a scene or geometry of double (`float64`) or float
/// vertices: [`Error::InvalidArgument`], naming both record types, for a slice of the other
/// precision, which the C API cannot detect (it would misread the memory). Raw buffers pass:
/// the holder's flag decides how they are read.
fn vertex_buffer(call: &str, vertices: &Buffer<'_>, float64: bool, holder: Holder) -> Result<sys::minkq_buffer> {
    let wanted = if float64 { Precision::F64 } else { Precision::F32 };
    let (name, flag) = holder.names();
    vertices.raw_at(wanted).map_err(|got| {
        Error::InvalidArgument(format!(
            "{call}: {} vertices, but {name} {} {flag} reads {}",
            got.vertex(),
            if float64 { "with" } else { "without" },
            wanted.vertex()
        ))
    })
}

impl Drop for Scene {
    fn drop(&mut self) {
        // SAFETY: created by minkq_scene_create or _create_geometries and released once, before its device (whose
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
            .field("geometries", &self.geometry_count())
            .field("float64", &self.float64)
            .finish()
    }
}
