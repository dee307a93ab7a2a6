//! A scene's swept positions (`minkq_scene_refit_swept`, `minkq_scene_rebuild_swept`), for
//! continuous collision detection: every vertex moves linearly from `x0` to `x1` over a step,
//! and the queries report every pair whose elements come within r at some time of it. Also
//! the stream-ordered swept steps (`minkq_scene_refit_swept_async`,
//! `minkq_scene_rebuild_swept_async`).
use super::Scene;
use crate::buffer::Buffer;
use crate::error::{check, Result};
use crate::inputs::Vertices;
use crate::stream::Stream;
use crate::sys;

impl Scene {
    /// Swept positions, for continuous collision detection (CCD): every vertex moves linearly
    /// from `x0` to `x1` over the step (`x(t) = x0 + t (x1 - x0)`, t in [0, 1]). The scene
    /// keeps both, boxes each element over both positions and refits its trees to those boxes
    /// (keeping the grouping of the last build, as [`Scene::refit`] does). Its queries are then
    /// swept until the next plain refit or rebuild ([`Scene::is_swept`]): they report every
    /// pair whose two elements come within r at some time of the step, the candidates a CCD
    /// narrow phase then decides.
    ///
    /// The modes, as node and primitive tests against the elements' swept boxes:
    /// - VT: the vertex is its path, the segment `x0 -> x1`: [`Mode::Box`] (the segment's box
    ///   grown by r), [`Mode::CapsuleRay`] and [`Mode::CapsuleExact`] (the capsule of radius r
    ///   around the path), and [`Mode::Sphere`], the same as [`Mode::CapsuleExact`] (the sphere
    ///   swept along the path);
    /// - EE: [`Mode::Box`] only (each edge's swept box grown by r); the other modes are
    ///   [`Error::Unsupported`];
    /// - VV and EV: as VT, the vertex (for VV, each of the two) is its path against the other
    ///   element's swept box; every mode runs, [`Mode::Sphere`] the same as
    ///   [`Mode::CapsuleExact`].
    ///
    /// [`QueryFlags::LEAF_EXACT`] is [`Error::Unsupported`] on swept positions (it would need
    /// the time of closest approach, which the narrow phase finds);
    /// [`SceneFlags::DROP_INCIDENT`] and the once-per-pair EE rule apply as for static queries.
    /// At `x0 == x1` the pairs are the static queries' (VT, VV and EV [`Mode::CapsuleExact`]
    /// and [`Mode::Sphere`]: the static [`Mode::Sphere`] pairs).
    ///
    /// Errors: those of [`Scene::refit`] for either slice (a vertex count other than the
    /// scene's, [`Error::NonFinite`]; on a [`SceneFlags::FLOAT64`] scene, which takes
    /// [`Scene::refit_swept_f64`], [`Error::InvalidArgument`]). On error the scene keeps its
    /// positions, trees and swept state.
    ///
    /// A vertex flying through a still triangle: apart at both ends of the step, found by the
    /// swept query.
    ///
    /// ```
    /// use minkq::{Device, Error, Mode, PairBuffer, Query, QueryFlags, Scene, SceneDesc};
    /// // Triangle 0 in the plane x = 0; vertex 3 goes from x = -1 to x = +1 straight through it.
    /// let x0 = [[0.0, -1.0, -1.0], [0.0, 2.0, -1.0], [0.0, -1.0, 2.0], [-1.0, 0.1, 0.1]];
    /// let mut x1 = x0;
    /// x1[3][0] = 1.0;
    /// let triangles = [[0, 1, 2]];
    /// let mut scene = Scene::new(&Device::cpu()?, &SceneDesc::new(&x0, &triangles))?;
    /// let query = Query::vt(Mode::CapsuleExact, 0.01);
    /// let mut pairs = PairBuffer::new()?;
    /// // Static queries at either end find nothing: the vertex is 1 from the triangle.
    /// assert!(scene.query(&query, &mut pairs)?.is_empty());
    /// scene.refit(&x1)?;
    /// assert!(scene.query(&query, &mut pairs)?.is_empty());
    /// // Over the step, its path crosses the triangle.
    /// scene.refit_swept(&x0, &x1)?;
    /// assert!(scene.is_swept());
    /// assert_eq!(scene.query(&query, &mut pairs)?, &[[3, 0]]);
    /// assert_eq!(scene.query(&Query::vt(Mode::Box, 0.01), &mut pairs)?, &[[3, 0]]);
    ///
    /// // Swept EE queries run box mode only; leaf-exact needs a narrow phase.
    /// let err = scene.query(&Query::ee(Mode::CapsuleExact, 0.01), &mut pairs).unwrap_err();
    /// assert!(matches!(err, Error::Unsupported(m) if m.contains("box mode only")));
    /// let leaf_exact = query.with_flags(QueryFlags::LEAF_EXACT);
    /// assert!(matches!(scene.query(&leaf_exact, &mut pairs), Err(Error::Unsupported(_))));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    ///
    /// Two particles crossing a rod and each other's path: VV and EV swept queries.
    ///
    /// ```
    /// use minkq::{Device, Mode, PairBuffer, Query, QueryFlags, Scene, SceneDesc};
    /// // A rod (vertices 0, 1, 2) along x; particle 3 flies through it in y, particle 4 in x
    /// // passes where particle 3 has been.
    /// let x0 = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.5, -1.0, 0.0], [-1.0, 0.5, 0.0]];
    /// let mut x1 = x0;
    /// x1[3] = [0.5, 1.0, 0.0];
    /// x1[4] = [2.0, 0.5, 0.0];
    /// let mut scene = Scene::new(&Device::cpu()?, &SceneDesc::codim(&x0, &[[0, 1], [1, 2]]))?;
    /// let mut pairs = PairBuffer::new()?;
    /// let canonical = QueryFlags::CANONICAL;
    /// assert!(scene.query(&Query::ev(Mode::Sphere, 0.01), &mut pairs)?.is_empty());
    /// scene.refit_swept(&x0, &x1)?;
    /// // Particle 3 crosses edge 0 at t = 0.5.
    /// assert_eq!(scene.query(&Query::ev(Mode::CapsuleExact, 0.01).with_flags(canonical), &mut pairs)?, &[[3, 0]]);
    /// // Particles 3 and 4 pass (0.5, 0.5) at t = 0.75 and t = 0.5: never together (0.42 apart
    /// // at their closest), but each path meets the other's box: a candidate for the narrow
    /// // phase, which decides.
    /// let vv = scene.query(&Query::vv(Mode::CapsuleExact, 0.01).with_flags(canonical), &mut pairs)?;
    /// assert_eq!(vv, &[[3, 4]]);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    ///
    /// [`Mode::Box`]: crate::Mode::Box
    /// [`Mode::Sphere`]: crate::Mode::Sphere
    /// [`Mode::CapsuleRay`]: crate::Mode::CapsuleRay
    /// [`Mode::CapsuleExact`]: crate::Mode::CapsuleExact
    /// [`Error::Unsupported`]: crate::Error::Unsupported
    /// [`Error::NonFinite`]: crate::Error::NonFinite
    /// [`Error::InvalidArgument`]: crate::Error::InvalidArgument
    /// [`QueryFlags::LEAF_EXACT`]: crate::QueryFlags::LEAF_EXACT
    /// [`SceneFlags::DROP_INCIDENT`]: crate::SceneFlags::DROP_INCIDENT
    /// [`SceneFlags::FLOAT64`]: crate::SceneFlags::FLOAT64
    pub fn refit_swept<'v>(&mut self, x0: impl Vertices<'v>, x1: impl Vertices<'v>) -> Result<()> {
        let (x0, x1) = (x0.into_buffer(), x1.into_buffer());
        let (x0, x1) = self.swept_buffers("refit_swept", &x0, &x1)?;
        // SAFETY: a live scene; the buffers' constructors promised readable records, of the
        // scene's precision where the buffers know it (checked above).
        check(unsafe { sys::minkq_scene_refit_swept(self.raw.as_ptr(), x0, x1) })
    }

    /// [`Scene::refit_swept`] with `[f64; 3]` positions, for a [`SceneFlags::FLOAT64`] scene
    /// ([`SceneDesc::new_f64`](crate::SceneDesc::new_f64)): both rounded to float, the query
    /// radii widened as for [`Scene::refit_f64`], so that every pair within r in double at
    /// some time of the step is reported. A float scene refuses them with
    /// [`Error::InvalidArgument`]; a double beyond the float range is [`Error::NonFinite`].
    ///
    /// ```
    /// # use minkq::*;
    /// // The flying vertex of `refit_swept`, far from the origin, in double.
    /// let base = 7000.0;
    /// let x0 = [[base, -1.0, -1.0], [base, 2.0, -1.0], [base, -1.0, 2.0], [base - 1.0, 0.1, 0.1]];
    /// let mut x1 = x0;
    /// x1[3][0] = base + 1.0;
    /// let mut scene = Scene::new(&Device::cpu()?, &SceneDesc::new_f64(&x0, &[[0, 1, 2]]))?;
    /// scene.refit_swept(&x0, &x1)?;
    /// assert!(scene.is_swept());
    /// assert_eq!(scene.query(&Query::vt(Mode::Sphere, 1e-3), &mut PairBuffer::new()?)?, &[[3, 0]]);
    /// // Floats are refused, for either end: the scene reads 3 doubles per vertex.
    /// let floats: Vec<[f32; 3]> = x1.iter().map(|v| v.map(|x| x as f32)).collect();
    /// let err = scene.refit_swept(Buffer::from_slice(&x0), Buffer::from_slice(&floats)).unwrap_err();
    /// assert_eq!(err, Error::InvalidArgument("refit_swept: x1: [f32; 3] vertices, but a scene with SceneFlags::FLOAT64 reads [f64; 3]".into()));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    ///
    /// [`SceneFlags::FLOAT64`]: crate::SceneFlags::FLOAT64
    /// [`Error::NonFinite`]: crate::Error::NonFinite
    /// [`Error::InvalidArgument`]: crate::Error::InvalidArgument
    #[deprecated(note = "use `Scene::refit_swept`, which takes `[f64; 3]` vertices too")]
    pub fn refit_swept_f64(&mut self, x0: &[[f64; 3]], x1: &[[f64; 3]]) -> Result<()> {
        self.refit_swept(x0, x1)
    }

    /// [`Scene::refit_swept`] from two [`Buffer`]s: strided records, host or (on a CUDA
    /// device) device memory, read in place on the device. Records and precision as for
    /// [`Scene::refit_buffer`], for each buffer; a slice buffer of the other precision is
    /// [`Error::InvalidArgument`] naming the buffer (`x0` or `x1`). On error the scene keeps
    /// its positions, trees and swept state.
    ///
    /// ```
    /// # use minkq::*;
    /// let x0 = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    /// let mut scene = Scene::new(&Device::cpu()?, &SceneDesc::new(&x0, &[[0, 1, 2]]))?;
    /// // The triangle lifted by 1 over the step, as 16-byte (vec4) records.
    /// let x1 = [[0.0f32, 0.0, 1.0, 0.0], [1.0, 0.0, 1.0, 0.0], [0.0, 1.0, 1.0, 0.0]];
    /// // SAFETY: three 16-byte records starting with x, y, z, borrowed from `x1`.
    /// let x1 = unsafe { Buffer::from_raw_parts(x1.as_ptr().cast(), 16, 3, Memory::Host) };
    /// scene.refit_swept(Buffer::from_slice(&x0), x1)?;
    /// assert!(scene.is_swept());
    /// // Doubles on a float scene are refused before the library could misread them.
    /// let doubles = [[0.0f64; 3]; 3];
    /// let err = scene.refit_swept(Buffer::from_slice(&doubles), x1).unwrap_err();
    /// assert!(matches!(err, Error::InvalidArgument(m) if m.starts_with("refit_swept: x0: [f64; 3] vertices")));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    ///
    /// [`Error::InvalidArgument`]: crate::Error::InvalidArgument
    #[deprecated(note = "use `Scene::refit_swept`, which takes `Buffer`s too")]
    pub fn refit_swept_buffers(&mut self, x0: Buffer<'_>, x1: Buffer<'_>) -> Result<()> {
        self.refit_swept(x0, x1)
    }

    /// Swept positions like [`Scene::refit_swept`], with the trees built afresh for the
    /// elements' swept boxes (as [`Scene::rebuild`] builds them for static positions). The
    /// pairs are the same as after [`Scene::refit_swept`]; only the speed of later queries
    /// differs. Same errors; on error the scene keeps its positions, trees and swept state. A
    /// [`SceneFlags::FLOAT64`] scene takes [`Scene::rebuild_swept_f64`].
    ///
    /// ```
    /// # use minkq::*;
    /// // Two triangles 1 apart in z, one flying onto the other over the step.
    /// let x0 = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0],
    ///           [0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]];
    /// let mut x1 = x0;
    /// for v in &mut x1[3..] {
    ///     v[2] = -1.0; // through the lower triangle and 1 beyond it
    /// }
    /// let mut scene = Scene::new(&Device::cpu()?, &SceneDesc::new(&x0, &[[0, 1, 2], [3, 4, 5]]))?;
    /// let query = Query::vt(Mode::Sphere, 0.01).with_flags(QueryFlags::CANONICAL);
    /// let mut pairs = PairBuffer::new()?;
    /// assert!(scene.query(&query, &mut pairs)?.is_empty());
    /// scene.rebuild_swept(&x0, &x1)?;
    /// assert_eq!(scene.tree_growth()?, 1.0);
    /// assert_eq!(scene.query(&query, &mut pairs)?, &[[0, 1], [1, 1], [2, 1], [3, 0], [4, 0], [5, 0]]);
    /// let err = scene.rebuild_swept(&x0, &x1[..5]).unwrap_err();
    /// assert_eq!(err, Error::InvalidArgument("rebuild_swept with 5 x1 vertices but the scene has 6".into()));
    /// assert!(scene.is_swept()); // kept
    /// # Ok::<(), minkq::Error>(())
    /// ```
    ///
    /// [`SceneFlags::FLOAT64`]: crate::SceneFlags::FLOAT64
    pub fn rebuild_swept<'v>(&mut self, x0: impl Vertices<'v>, x1: impl Vertices<'v>) -> Result<()> {
        let (x0, x1) = (x0.into_buffer(), x1.into_buffer());
        let (x0, x1) = self.swept_buffers("rebuild_swept", &x0, &x1)?;
        // SAFETY: a live scene; the buffers' constructors promised readable records, of the
        // scene's precision where the buffers know it (checked above).
        check(unsafe { sys::minkq_scene_rebuild_swept(self.raw.as_ptr(), x0, x1) })
    }

    /// [`Scene::rebuild_swept`] with `[f64; 3]` positions, for a [`SceneFlags::FLOAT64`]
    /// scene. Same errors as [`Scene::refit_swept_f64`]; on error the scene keeps its
    /// positions, trees and swept state.
    ///
    /// ```
    /// # use minkq::*;
    /// let x0 = [[0.0, -1.0, -1.0], [0.0, 2.0, -1.0], [0.0, -1.0, 2.0], [-1.0, 0.1, 0.1]];
    /// let mut x1 = x0;
    /// x1[3][0] = 1.0;
    /// let mut scene = Scene::new(&Device::cpu()?, &SceneDesc::new_f64(&x0, &[[0, 1, 2]]))?;
    /// scene.rebuild_swept(&x0, &x1)?;
    /// assert_eq!(scene.query(&Query::vt(Mode::CapsuleRay, 0.01), &mut PairBuffer::new()?)?, &[[3, 0]]);
    /// // A double beyond the float range cannot be rounded to a float: non-finite.
    /// x1[1][2] = 1e39;
    /// assert!(matches!(scene.rebuild_swept(&x0, &x1), Err(Error::NonFinite(m)) if m.contains("vertex 1")));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    ///
    /// [`SceneFlags::FLOAT64`]: crate::SceneFlags::FLOAT64
    #[deprecated(note = "use `Scene::rebuild_swept`, which takes `[f64; 3]` vertices too")]
    pub fn rebuild_swept_f64(&mut self, x0: &[[f64; 3]], x1: &[[f64; 3]]) -> Result<()> {
        self.rebuild_swept(x0, x1)
    }

    /// [`Scene::rebuild_swept`] from two [`Buffer`]s: records, memory and precision as for
    /// [`Scene::refit_swept_buffers`]. On error the scene keeps its positions, trees and swept
    /// state.
    ///
    /// ```
    /// # use minkq::*;
    /// let x0 = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    /// let mut scene = Scene::new(&Device::cpu()?, &SceneDesc::new(&x0, &[[0, 1, 2]]))?;
    /// let x1 = [[0.0f32, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, f32::NAN, 1.0]];
    /// let err = scene.rebuild_swept(Buffer::from_slice(&x0), Buffer::from_slice(&x1)).unwrap_err();
    /// assert!(matches!(err, Error::NonFinite(m) if m.starts_with("x1 vertex 2 ")));
    /// assert!(!scene.is_swept()); // kept its static positions
    /// # Ok::<(), minkq::Error>(())
    /// ```
    #[deprecated(note = "use `Scene::rebuild_swept`, which takes `Buffer`s too")]
    pub fn rebuild_swept_buffers(&mut self, x0: Buffer<'_>, x1: Buffer<'_>) -> Result<()> {
        self.rebuild_swept(x0, x1)
    }

    /// [`Scene::refit_swept_buffers`], enqueued on `stream` (`minkq_scene_refit_swept_async`)
    /// as [`Scene::refit_async`] is: on a CUDA device `x0` and `x1` are device memory, read by
    /// the work enqueued (so the promise of [`Buffer::from_raw_parts`] lasts until that work
    /// has run), and the call returns without waiting, allocating or synchronising, so that it
    /// can be captured into a CUDA graph. On the CPU they are host memory and the step has run
    /// when this returns. Needs [`Reserve::REFIT`] `|` [`Reserve::SWEPT`]. The scene's queries
    /// are then those [`Scene::refit_swept`] gives for the same positions.
    ///
    /// Both buffers are checked together where they are read, on the device: with a NaN or
    /// infinity in either, the scene keeps its positions at rest (the start of its last
    /// accepted step, or its static positions, as both ends: its queries give the static pairs
    /// there, as at `x0 == x1`, and [`Scene::is_swept`] is true) and records the pending
    /// error, which [`Scene::async_status`] returns as [`Error::NonFinite`] naming the call and
    /// the first bad vertex. Errors at once: as [`Scene::refit_swept_buffers`] except
    /// [`Error::NonFinite`] (a slice buffer of the other precision is
    /// [`Error::InvalidArgument`] naming `x0` or `x1`); [`Error::InvalidArgument`] without the
    /// reservation, or for host buffers on a CUDA device (device ones on the CPU).
    ///
    /// The flying vertex of [`Scene::refit_swept`], stepped on a stream:
    ///
    /// ```
    /// # use minkq::*;
    /// let x0 = [[0.0, -1.0, -1.0], [0.0, 2.0, -1.0], [0.0, -1.0, 2.0], [-1.0, 0.1, 0.1]];
    /// let mut x1 = x0;
    /// x1[3][0] = 1.0;
    /// let triangles = [[0, 1, 2]];
    /// let mut scene = Scene::new(&Device::cpu()?, &SceneDesc::new(&x0, &triangles))?;
    /// let step = |scene: &mut Scene, x1: &[[f32; 3]]| {
    ///     scene.refit_swept_async(Buffer::from_slice(&x0), Buffer::from_slice(x1), Stream::null())
    /// };
    /// // A plain refit's reservation does not cover swept steps.
    /// scene.reserve(Reserve::REFIT, 0)?;
    /// assert!(matches!(step(&mut scene, &x1), Err(Error::InvalidArgument(m)) if m.contains("MINKQ_RESERVE_SWEPT")));
    /// scene.reserve(Reserve::REFIT | Reserve::SWEPT, 0)?;
    /// step(&mut scene, &x1)?;
    /// scene.async_status(Stream::null())?;
    /// assert!(scene.is_swept());
    /// // The blocking swept step's pairs.
    /// let mut blocking = Scene::new(&Device::cpu()?, &SceneDesc::new(&x0, &triangles))?;
    /// blocking.refit_swept(&x0, &x1)?;
    /// let query = Query::vt(Mode::CapsuleExact, 0.01);
    /// let (mut pairs, mut want) = (PairBuffer::new()?, PairBuffer::new()?);
    /// assert_eq!(scene.query(&query, &mut pairs)?, blocking.query(&query, &mut want)?);
    /// assert_eq!(scene.query(&query, &mut pairs)?, &[[3, 0]]);
    ///
    /// // A NaN in x1: accepted at once, reported by async_status. The scene is at rest at x0,
    /// // where the vertex is 1 from the triangle: no pair.
    /// x1[3][1] = f32::NAN;
    /// step(&mut scene, &x1)?;
    /// let err = scene.async_status(Stream::null()).unwrap_err();
    /// assert!(matches!(&err, Error::NonFinite(m) if m.contains("minkq_scene_refit_swept_async: vertex 3")));
    /// assert!(scene.query(&query, &mut pairs)?.is_empty());
    /// # Ok::<(), minkq::Error>(())
    /// ```
    ///
    /// [`Error::NonFinite`]: crate::Error::NonFinite
    /// [`Error::InvalidArgument`]: crate::Error::InvalidArgument
    /// [`Reserve::REFIT`]: crate::Reserve::REFIT
    /// [`Reserve::SWEPT`]: crate::Reserve::SWEPT
    pub fn refit_swept_async(&mut self, x0: Buffer<'_>, x1: Buffer<'_>, stream: Stream) -> Result<()> {
        let (x0, x1) = self.swept_buffers("refit_swept_async", &x0, &x1)?;
        // SAFETY: a live scene; the buffers' constructors promised records readable until the
        // enqueued work has run (host slices are read before this returns: CPU devices only),
        // of the scene's precision where the buffers know it (checked above); the stream's
        // constructor promised a stream of the scene's device.
        check(unsafe { sys::minkq_scene_refit_swept_async(self.raw.as_ptr(), x0, x1, stream.as_raw()) })
    }

    /// [`Scene::rebuild_swept_buffers`], enqueued on `stream` as [`Scene::refit_swept_async`]
    /// is (`minkq_scene_rebuild_swept_async`): the trees [`Scene::rebuild_swept`] builds for
    /// the elements' swept boxes. Needs [`Reserve::REBUILD`] `|` [`Reserve::SWEPT`]. With a NaN
    /// or infinity in either buffer the scene keeps its positions at rest (its trees then built
    /// for those), as [`Scene::refit_swept_async`] does, and [`Scene::async_status`] reports
    /// it. On a [`SceneFlags::FLOAT64`] scene both buffers hold 3 doubles per vertex.
    ///
    /// ```
    /// # use minkq::*;
    /// // Two triangles 1 apart in z, in double, the upper one flying through the lower one.
    /// let x0 = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0],
    ///           [0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]];
    /// let mut x1 = x0;
    /// for v in &mut x1[3..] {
    ///     v[2] = -1.0;
    /// }
    /// let triangles = [[0, 1, 2], [3, 4, 5]];
    /// let mut scene = Scene::new(&Device::cpu()?, &SceneDesc::new_f64(&x0, &triangles))?;
    /// let (b0, b1) = (Buffer::from_slice(&x0), Buffer::from_slice(&x1));
    /// // A refit's reservation does not cover rebuilds.
    /// scene.reserve(Reserve::REFIT | Reserve::SWEPT, 0)?;
    /// assert!(matches!(scene.rebuild_swept_async(b0, b1, Stream::null()), Err(Error::InvalidArgument(_))));
    /// scene.reserve(Reserve::REBUILD | Reserve::SWEPT, 0)?;
    /// scene.rebuild_swept_async(b0, b1, Stream::null())?;
    /// scene.async_status(Stream::null())?;
    /// assert_eq!(scene.tree_growth()?, 1.0);
    /// let mut blocking = Scene::new(&Device::cpu()?, &SceneDesc::new_f64(&x0, &triangles))?;
    /// blocking.rebuild_swept_f64(&x0, &x1)?;
    /// let query = Query::vt(Mode::Sphere, 0.01).with_flags(QueryFlags::CANONICAL);
    /// let (mut pairs, mut want) = (PairBuffer::new()?, PairBuffer::new()?);
    /// assert_eq!(scene.query(&query, &mut pairs)?, blocking.query(&query, &mut want)?);
    /// assert_eq!(scene.query(&query, &mut pairs)?.len(), 6);
    /// // Floats for either end are refused at once, naming the buffer.
    /// let floats: Vec<[f32; 3]> = x1.iter().map(|v| v.map(|x| x as f32)).collect();
    /// let err = scene.rebuild_swept_async(b0, Buffer::from_slice(&floats), Stream::null()).unwrap_err();
    /// let Error::InvalidArgument(m) = err else { panic!("{err:?}") };
    /// assert!(m.starts_with("rebuild_swept_async: x1: [f32; 3] vertices"));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    ///
    /// [`Reserve::REBUILD`]: crate::Reserve::REBUILD
    /// [`Reserve::SWEPT`]: crate::Reserve::SWEPT
    /// [`SceneFlags::FLOAT64`]: crate::SceneFlags::FLOAT64
    pub fn rebuild_swept_async(&mut self, x0: Buffer<'_>, x1: Buffer<'_>, stream: Stream) -> Result<()> {
        let (x0, x1) = self.swept_buffers("rebuild_swept_async", &x0, &x1)?;
        // SAFETY: as in refit_swept_async.
        check(unsafe { sys::minkq_scene_rebuild_swept_async(self.raw.as_ptr(), x0, x1, stream.as_raw()) })
    }

    /// Whether the scene's positions are swept ones ([`Scene::refit_swept`],
    /// [`Scene::rebuild_swept`], their variants and the stream-ordered
    /// [`Scene::refit_swept_async`] and [`Scene::rebuild_swept_async`], also one that fell
    /// back to rest), so that its queries are swept; false after creation and after every
    /// plain refit or rebuild, blocking or stream-ordered.
    ///
    /// ```
    /// # use minkq::*;
    /// let x = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    /// let mut scene = Scene::new(&Device::cpu()?, &SceneDesc::new(&x, &[[0, 1, 2]]))?;
    /// assert!(!scene.is_swept());
    /// scene.refit_swept(&x, &x)?;
    /// assert!(scene.is_swept());
    /// scene.refit(&x)?; // static again
    /// assert!(!scene.is_swept());
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn is_swept(&self) -> bool {
        // SAFETY: a live scene.
        unsafe { sys::minkq_scene_is_swept(self.raw.as_ptr()) != 0 }
    }

    /// The C buffers of `call`'s two positions, each checked for the scene's precision.
    fn swept_buffers(
        &self,
        call: &str,
        x0: &Buffer<'_>,
        x1: &Buffer<'_>,
    ) -> Result<(sys::minkq_buffer, sys::minkq_buffer)> {
        Ok((self.vertex_buffer(&format!("{call}: x0"), x0)?, self.vertex_buffer(&format!("{call}: x1"), x1)?))
    }
}
