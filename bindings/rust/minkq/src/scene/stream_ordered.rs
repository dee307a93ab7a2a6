//! A scene's stream-ordered calls (`minkq_scene_*_async`), for a simulation step captured into a
//! CUDA graph: the reservation, refit, rebuild and queries enqueued on a [`Stream`], and the
//! pending error.
use super::Scene;
use crate::buffer::{Buffer, Memory, PairsOut};
use crate::error::{check, Error, Result};
use crate::query::{Query, Reserve};
use crate::stream::{CountOut, Stream};
use crate::sys;

impl Scene {
    /// Reserves, on the scene's device, the scratch its asynchronous calls use, so that they
    /// never allocate (`minkq_scene_reserve`): [`Reserve::REFIT`] for
    /// [`Scene::refit_async`], [`Reserve::REBUILD`] for [`Scene::rebuild_async`] (and
    /// refits), [`Reserve::SWEPT`] with either for [`Scene::refit_swept_async`] and
    /// [`Scene::rebuild_swept_async`], and `canonical_capacity` pairs for the sort of asynchronous queries with
    /// [`QueryFlags::CANONICAL`] (whose capacity may not exceed it). Queries without
    /// `CANONICAL` need no reservation. Reservations only grow and last as long as the scene.
    /// A blocking call (it may allocate and synchronise): make it before capturing a graph.
    ///
    /// Errors: [`Error::SizeOverflow`] (`canonical_capacity`), [`Error::OutOfMemory`],
    /// [`Error::Device`].
    ///
    /// [`QueryFlags::CANONICAL`]: crate::QueryFlags::CANONICAL
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
    /// the reservation, or for host vertices on a CUDA device (device ones on the CPU). On a
    /// [`SceneFlags::FLOAT64`](crate::SceneFlags::FLOAT64) scene the records are 3 doubles, as
    /// for [`Scene::refit_buffer`].
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
        let vertices = self.vertex_buffer("refit_async", &vertices)?;
        // SAFETY: a live scene; the buffer's constructor promised records readable until the
        // enqueued work has run (host slices are read before this returns: CPU devices only);
        // the stream's constructor promised a stream of the scene's device.
        check(unsafe { sys::minkq_scene_refit_async(self.raw.as_ptr(), vertices, stream.as_raw()) })
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
        let vertices = self.vertex_buffer("rebuild_async", &vertices)?;
        // SAFETY: as in refit_async.
        check(unsafe { sys::minkq_scene_rebuild_async(self.raw.as_ptr(), vertices, stream.as_raw()) })
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
    /// [`QueryFlags::CANONICAL`]: crate::QueryFlags::CANONICAL
    /// [`QueryFlags::DIGEST`]: crate::QueryFlags::DIGEST
    /// [`QueryFlags::STATS`]: crate::QueryFlags::STATS
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
    /// rebuild (swept ones too: [`Scene::refit_swept_async`], [`Scene::rebuild_swept_async`])
    /// since the last call (or the reservation) accepted its vertices, else the error
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
}
