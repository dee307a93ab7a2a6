//! Moving one geometry of a scene (`minkq_scene_geometry_refit`, `_rebuild` and their swept
//! forms): the other geometries, static or not, are not touched.
use super::{vertex_buffer, Holder, Scene};
use crate::buffer::Buffer;
use crate::error::{check, Result};
use crate::geometry::GeometryFlags;
use crate::inputs::Vertices;
use crate::sys;

/// `minkq_scene_geometry_refit_swept` or `minkq_scene_geometry_rebuild_swept`.
type SweepCall =
    unsafe extern "C" fn(*mut sys::minkq_scene, u32, sys::minkq_buffer, sys::minkq_buffer) -> sys::minkq_status;

impl Scene {
    /// Moves geometry `geometry`'s vertices (its count, `[f32; 3]` or, for a float64 geometry,
    /// `[f64; 3]`) and refits its trees, as [`Scene::refit`] does for a whole scene. The other
    /// geometries keep their positions and trees.
    ///
    /// Errors: [`Error::InvalidArgument`] for a static geometry
    /// ([`GeometryFlags::STATIC`](crate::GeometryFlags::STATIC)), one out of range, a vertex
    /// count other than the geometry's, or a slice of the other precision;
    /// [`Error::NonFinite`] naming the geometry and vertex. On error the scene keeps its
    /// positions. The example is at [`Scene::from_geometries`].
    ///
    /// ```
    /// # use minkq::*;
    /// let a = [[0.0f32; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    /// let b = [[0.0f64, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, f64::NAN, 1.0]];
    /// let mut scene = Scene::from_geometries(&Device::cpu()?, &[GeometryDesc::mesh(&a, &[[0, 1, 2]]); 2])?;
    /// let err = scene.refit_geometry(1, &b).unwrap_err();
    /// assert_eq!(err.message(), "geometry 1: refit: [f64; 3] vertices, but a geometry without GeometryFlags::FLOAT64 reads [f32; 3]");
    /// let err = scene.refit_geometry(1, &a[..2]).unwrap_err();
    /// assert_eq!(err.message(), "refit of geometry 1 with 2 vertices but the geometry has 3");
    /// # Ok::<(), minkq::Error>(())
    /// ```
    ///
    /// [`Error::InvalidArgument`]: crate::Error::InvalidArgument
    /// [`Error::NonFinite`]: crate::Error::NonFinite
    pub fn refit_geometry<'v>(&mut self, geometry: u32, vertices: impl Vertices<'v>) -> Result<()> {
        let vertices = self.geometry_vertex_buffer(geometry, "refit", &vertices.into_buffer())?;
        // SAFETY: a live scene; the buffer's constructor promised readable records, of the
        // geometry's precision where the buffer knows it (checked above).
        check(unsafe { sys::minkq_scene_geometry_refit(self.raw.as_ptr(), geometry, vertices) })
    }

    /// [`Scene::refit_geometry`] from a [`Buffer`]: strided records, host or (on a CUDA
    /// device) device memory, read as the geometry's precision says.
    ///
    /// ```
    /// # use minkq::*;
    /// let a = [[0.0f32; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    /// let mut scene = Scene::from_geometries(&Device::cpu()?, &[GeometryDesc::mesh(&a, &[[0, 1, 2]]); 2])?;
    /// let moved = [[0.0f32, 0.0, 1.0, 0.0], [1.0, 0.0, 1.0, 0.0], [0.0, f32::NAN, 1.0, 0.0]];
    /// // SAFETY: three 16-byte records starting with x, y, z, borrowed from `moved`.
    /// let err = scene.refit_geometry(0, unsafe { Buffer::from_raw_parts(moved.as_ptr().cast(), 16, 3, Memory::Host) });
    /// assert!(matches!(err, Err(Error::NonFinite(m)) if m.starts_with("geometry 0: vertex 2 ")));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    #[deprecated(note = "use `Scene::refit_geometry`, which takes a `Buffer` too")]
    pub fn refit_geometry_buffer(&mut self, geometry: u32, vertices: Buffer<'_>) -> Result<()> {
        self.refit_geometry(geometry, vertices)
    }

    /// Moves geometry `geometry`'s vertices and builds its trees afresh, as [`Scene::rebuild`]
    /// does for a whole scene: the same pairs as [`Scene::refit_geometry`], faster queries
    /// after large motions. Same errors; on error the scene keeps its positions and trees.
    ///
    /// ```
    /// # use minkq::*;
    /// let a = [[0.0f32; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    /// let b = [[0.0f32, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]];
    /// let mut scene = Scene::from_geometries(&Device::cpu()?, &[GeometryDesc::mesh(&a, &[[0, 1, 2]]), GeometryDesc::mesh(&a, &[[0, 1, 2]])])?;
    /// scene.rebuild_geometry(1, &b)?; // 0.1 above geometry 0 now
    /// let vt = Query::vt(Mode::Box, 0.2).with_flags(QueryFlags::LEAF_EXACT);
    /// assert_eq!(scene.query(&vt, &mut PairBuffer::new()?)?.len(), 6);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn rebuild_geometry<'v>(&mut self, geometry: u32, vertices: impl Vertices<'v>) -> Result<()> {
        let vertices = self.geometry_vertex_buffer(geometry, "rebuild", &vertices.into_buffer())?;
        // SAFETY: a live scene; the buffer's constructor promised readable records, of the
        // geometry's precision where the buffer knows it (checked above).
        check(unsafe { sys::minkq_scene_geometry_rebuild(self.raw.as_ptr(), geometry, vertices) })
    }

    /// [`Scene::rebuild_geometry`] from a [`Buffer`], as [`Scene::refit_geometry_buffer`].
    ///
    /// ```
    /// # use minkq::*;
    /// let a = [[0.0f32; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    /// let mut scene = Scene::from_geometries(&Device::cpu()?, &[GeometryDesc::mesh(&a, &[[0, 1, 2]])])?;
    /// scene.rebuild_geometry(0, Buffer::from_slice(&a))?;
    /// assert_eq!(scene.tree_growth()?, 1.0);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    #[deprecated(note = "use `Scene::rebuild_geometry`, which takes a `Buffer` too")]
    pub fn rebuild_geometry_buffer(&mut self, geometry: u32, vertices: Buffer<'_>) -> Result<()> {
        self.rebuild_geometry(geometry, vertices)
    }

    /// Swept positions for geometry `geometry`, as [`Scene::refit_swept`] gives them to a
    /// whole scene: its vertices move linearly from `x0` to `x1` over the step, and its trees
    /// are refitted to the elements' swept boxes. Its swept positions last until its next
    /// plain refit or rebuild; while any geometry is swept the scene's queries are swept
    /// ([`Scene::is_swept`]), under the rules of [`Scene::refit_swept`]. Errors as
    /// [`Scene::refit_geometry`] for either slice (named `x0` or `x1`); on error the scene
    /// keeps its positions, trees and swept state.
    ///
    /// ```
    /// # use minkq::*;
    /// // Geometry 1, a vertex, flies through geometry 0's triangle over the step.
    /// let triangle = [[0.0f32, -1.0, -1.0], [0.0, 2.0, -1.0], [0.0, -1.0, 2.0]];
    /// let (x0, x1) = ([[-1.0f32, 0.1, 0.1]], [[1.0f32, 0.1, 0.1]]);
    /// let mut scene = Scene::from_geometries(&Device::cpu()?, &[
    ///     GeometryDesc::mesh(&triangle, &[[0, 1, 2]]).kinds(Kinds::VT).flags(GeometryFlags::STATIC),
    ///     GeometryDesc::mesh(&x0, &[]).kinds(Kinds::VT),
    /// ])?;
    /// let query = Query::vt(Mode::CapsuleExact, 0.01);
    /// let mut pairs = PairBuffer::new()?;
    /// assert!(scene.query(&query, &mut pairs)?.is_empty());
    /// scene.refit_geometry_swept(1, &x0, &x1)?;
    /// assert!(scene.is_swept());
    /// assert_eq!(scene.query(&query, &mut pairs)?, &[[3, 0]]); // global vertex 3: geometry 1's 0
    /// scene.refit_geometry(1, &x1)?; // at rest again, beyond the triangle
    /// assert!(!scene.is_swept() && scene.query(&query, &mut pairs)?.is_empty());
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn refit_geometry_swept<'v>(
        &mut self,
        geometry: u32,
        x0: impl Vertices<'v>,
        x1: impl Vertices<'v>,
    ) -> Result<()> {
        let call = sys::minkq_scene_geometry_refit_swept;
        self.sweep_geometry(geometry, "refit_swept", x0.into_buffer(), x1.into_buffer(), call)
    }

    /// [`Scene::refit_geometry_swept`] from two [`Buffer`]s, as
    /// [`Scene::refit_geometry_buffer`] takes one.
    ///
    /// ```
    /// # use minkq::*;
    /// let a = [[0.0f32; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    /// let mut scene = Scene::from_geometries(&Device::cpu()?, &[GeometryDesc::mesh(&a, &[[0, 1, 2]])])?;
    /// let err = scene.refit_geometry_swept(0, Buffer::from_slice(&a), Buffer::from_slice(&a[..1])).unwrap_err();
    /// assert_eq!(err.message(), "refit_swept of geometry 0 with 1 x1 vertices but the geometry has 3");
    /// # Ok::<(), minkq::Error>(())
    /// ```
    #[deprecated(note = "use `Scene::refit_geometry_swept`, which takes `Buffer`s too")]
    pub fn refit_geometry_swept_buffers(&mut self, geometry: u32, x0: Buffer<'_>, x1: Buffer<'_>) -> Result<()> {
        self.refit_geometry_swept(geometry, x0, x1)
    }

    /// Swept positions for one geometry like [`Scene::refit_geometry_swept`], with its trees
    /// built afresh for the swept boxes (as [`Scene::rebuild_swept`] builds a scene's). The
    /// same pairs; same errors.
    ///
    /// ```
    /// # use minkq::*;
    /// let a = [[0.0f64; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    /// let mut scene = Scene::from_geometries(&Device::cpu()?, &[GeometryDesc::mesh(&a, &[[0, 1, 2]])])?;
    /// scene.rebuild_geometry_swept(0, &a, &a)?; // a float64 geometry takes [f64; 3]
    /// assert!(scene.is_swept());
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn rebuild_geometry_swept<'v>(
        &mut self,
        geometry: u32,
        x0: impl Vertices<'v>,
        x1: impl Vertices<'v>,
    ) -> Result<()> {
        let call = sys::minkq_scene_geometry_rebuild_swept;
        self.sweep_geometry(geometry, "rebuild_swept", x0.into_buffer(), x1.into_buffer(), call)
    }

    /// [`Scene::rebuild_geometry_swept`] from two [`Buffer`]s.
    ///
    /// ```
    /// # use minkq::*;
    /// let a = [[0.0f32; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    /// let mut scene = Scene::from_geometries(&Device::cpu()?, &[GeometryDesc::mesh(&a, &[[0, 1, 2]])])?;
    /// let err = scene.rebuild_geometry_swept(1, Buffer::from_slice(&a), Buffer::from_slice(&a)).unwrap_err();
    /// assert_eq!(err.message(), "geometry 1 is out of range: the scene has 1 geometries");
    /// # Ok::<(), minkq::Error>(())
    /// ```
    #[deprecated(note = "use `Scene::rebuild_geometry_swept`, which takes `Buffer`s too")]
    pub fn rebuild_geometry_swept_buffers(&mut self, geometry: u32, x0: Buffer<'_>, x1: Buffer<'_>) -> Result<()> {
        self.rebuild_geometry_swept(geometry, x0, x1)
    }

    /// The C buffer of `call`'s vertices for geometry `g`, checked for its precision. A
    /// geometry out of range or static takes none: the library refuses the call with its
    /// message before reading the buffer.
    fn geometry_vertex_buffer(&self, g: u32, call: &str, vertices: &Buffer<'_>) -> Result<sys::minkq_buffer> {
        match self.layout.moving_geometry(g) {
            Some(flags) => vertex_buffer(
                &format!("geometry {g}: {call}"),
                vertices,
                flags.contains(GeometryFlags::FLOAT64),
                Holder::Geometry,
            ),
            None => Ok(vertices.raw()),
        }
    }

    /// The C buffers of `call`'s two positions for geometry `g`, each checked.
    /// Moves geometry `g` to the swept positions `x0` -> `x1` through `call`, the C
    /// refit_swept or rebuild_swept of `name`, once both buffers pass the precision check.
    fn sweep_geometry(&mut self, g: u32, name: &str, x0: Buffer<'_>, x1: Buffer<'_>, call: SweepCall) -> Result<()> {
        let x0 = self.geometry_vertex_buffer(g, &format!("{name}: x0"), &x0)?;
        let x1 = self.geometry_vertex_buffer(g, &format!("{name}: x1"), &x1)?;
        // SAFETY: a live scene; the buffers' constructors promised readable records, of the
        // geometry's precision where the buffers know it (checked above).
        check(unsafe { call(self.raw.as_ptr(), g, x0, x1) })
    }
}
