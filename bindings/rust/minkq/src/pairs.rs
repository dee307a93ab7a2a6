use std::fmt;
use std::ptr::{self, NonNull};
use std::slice;

use crate::error::{check, Error, Result};
use crate::sys;

/// A library-owned pair buffer that grows as needed (`minkq_result`): pass it to
/// [`Scene::query`](crate::Scene::query) step after step and its memory is reused.
///
/// Threads: `Send` but not `Sync`, like every C object (one thread at a time).
///
/// ```
/// # use minkq::*;
/// # let device = Device::cpu()?;
/// # let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]];
/// # let triangles = [[0, 1, 2], [3, 4, 5]];
/// # let scene = Scene::new(&device, &SceneDesc::new(&vertices, &triangles))?;
/// let mut pairs = PairBuffer::new()?;
/// for step in 0..3 {
///     let found = scene.query(&Query::ee(Mode::CapsuleExact, 0.2), &mut pairs)?;
///     assert_eq!(found.len(), 9);
/// }
/// # Ok::<(), minkq::Error>(())
/// ```
///
/// ```compile_fail
/// fn shared_between_threads<T: Sync>() {}
/// shared_between_threads::<minkq::PairBuffer>(); // PairBuffer is not Sync
/// ```
pub struct PairBuffer {
    raw: NonNull<sys::minkq_result>,
}

// SAFETY: the C API lets an object move between threads as long as one thread uses it at a
// time; `PairBuffer` is not `Sync`, and every method takes `&self` or `&mut self`.
unsafe impl Send for PairBuffer {}

impl PairBuffer {
    /// An empty buffer.
    ///
    /// ```
    /// let pairs = minkq::PairBuffer::new()?;
    /// assert!(pairs.is_empty());
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn new() -> Result<PairBuffer> {
        let mut raw = ptr::null_mut();
        // SAFETY: a valid out pointer.
        check(unsafe { sys::minkq_result_create(&mut raw) })?;
        let raw = NonNull::new(raw).ok_or_else(|| Error::Internal("minkq_result_create returned NULL".into()))?;
        Ok(PairBuffer { raw })
    }

    pub(crate) fn as_ptr(&mut self) -> *mut sys::minkq_result {
        self.raw.as_ptr()
    }

    /// The pairs of the last successful query (empty after a failed one).
    ///
    /// ```
    /// # use minkq::*;
    /// # let device = Device::cpu()?;
    /// # let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]];
    /// # let triangles = [[0, 1, 2], [3, 4, 5]];
    /// # let scene = Scene::new(&device, &SceneDesc::new(&vertices, &triangles))?;
    /// let mut buffer = PairBuffer::new()?;
    /// scene.query(&Query::vt(Mode::Sphere, 0.2).with_flags(QueryFlags::CANONICAL), &mut buffer)?;
    /// assert_eq!(buffer.pairs(), &[[0, 1], [1, 1], [2, 1], [3, 0], [4, 0], [5, 0]]);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn pairs(&self) -> &[[i32; 2]] {
        let count = self.len();
        // SAFETY: the library holds 2 * count int32 at `pairs`, valid until the buffer is
        // reused (which needs &mut self) or released; [i32; 2] has the alignment of i32.
        unsafe {
            let data = sys::minkq_result_pairs(self.raw.as_ptr());
            if count == 0 || data.is_null() {
                &[]
            } else {
                slice::from_raw_parts(data.cast::<[i32; 2]>(), count)
            }
        }
    }

    /// The number of pairs of the last successful query: `pairs().len()` (0 after a
    /// [`QueryFlags::COUNT`](crate::QueryFlags::COUNT) query, which keeps none; its count is
    /// [`Scene::count`](crate::Scene::count)'s).
    ///
    /// ```
    /// let pairs = minkq::PairBuffer::new()?;
    /// assert_eq!(pairs.len(), 0);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn len(&self) -> usize {
        // SAFETY: a live result.
        unsafe {
            if sys::minkq_result_pairs(self.raw.as_ptr()).is_null() {
                0
            } else {
                sys::minkq_result_count(self.raw.as_ptr()) as usize
            }
        }
    }

    /// Whether the last query found no pair.
    ///
    /// ```
    /// assert!(minkq::PairBuffer::new()?.is_empty());
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// With [`QueryFlags::DIGEST`](crate::QueryFlags::DIGEST): the xxHash64 (seed 0) of the
    /// canonical pairs of the last query; 0 otherwise.
    ///
    /// ```
    /// # use minkq::*;
    /// # let device = Device::cpu()?;
    /// # let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]];
    /// # let triangles = [[0, 1, 2], [3, 4, 5]];
    /// # let scene = Scene::new(&device, &SceneDesc::new(&vertices, &triangles))?;
    /// let mut buffer = PairBuffer::new()?;
    /// scene.query(&Query::vt(Mode::Sphere, 0.2).with_flags(QueryFlags::DIGEST), &mut buffer)?;
    /// let mut again = [[0; 2]; 6];
    /// let info = scene.query_into(&Query::vt(Mode::Box, 0.2).with_flags(QueryFlags::DIGEST), &mut again)?;
    /// assert_eq!(Some(buffer.digest()), info.digest); // the same six pairs
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn digest(&self) -> u64 {
        // SAFETY: a live result.
        unsafe { sys::minkq_result_digest(self.raw.as_ptr()) }
    }

    /// With [`QueryFlags::STATS`](crate::QueryFlags::STATS): the work counts of the last
    /// query; all 0 otherwise.
    ///
    /// ```
    /// # use minkq::*;
    /// # let device = Device::cpu()?;
    /// # let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]];
    /// # let triangles = [[0, 1, 2], [3, 4, 5]];
    /// # let scene = Scene::new(&device, &SceneDesc::new(&vertices, &triangles))?;
    /// let mut buffer = PairBuffer::new()?;
    /// scene.query(&Query::vt(Mode::Sphere, 0.2).with_flags(QueryFlags::STATS), &mut buffer)?;
    /// assert_eq!(buffer.stats().candidates, 6);
    /// assert!(buffer.stats().primitive_tests >= 6);
    /// scene.query(&Query::vt(Mode::Sphere, 0.2), &mut buffer)?;
    /// assert_eq!(buffer.stats(), WorkStats::default());
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn stats(&self) -> crate::WorkStats {
        // SAFETY: a live result.
        let s = unsafe { sys::minkq_result_stats(self.raw.as_ptr()) };
        crate::WorkStats {
            nodes_visited: s.nodes_visited,
            node_tests: s.node_tests,
            primitive_tests: s.primitive_tests,
            candidates: s.candidates,
        }
    }
}

impl Drop for PairBuffer {
    fn drop(&mut self) {
        // SAFETY: created by minkq_result_create and released once.
        unsafe { sys::minkq_result_release(self.raw.as_ptr()) }
    }
}

impl fmt::Debug for PairBuffer {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("PairBuffer").field("len", &self.len()).finish()
    }
}

/// Runs `query(out_pairs, capacity)` into `out`, growing it once on CAPACITY to room for the
/// exact count and an eighth more (at least 64; the exact count where that does not fit), as
/// `minkq_scene_query_result` does, so that a count that grows a little from one step to the next
/// fits without a second run; on success `out` holds exactly the pairs.
pub(crate) fn query_vec(
    out: &mut Vec<[i32; 2]>,
    mut query: impl FnMut(*mut i32, usize) -> Result<crate::QueryInfo>,
) -> Result<crate::QueryInfo> {
    out.clear();
    for _ in 0..2 {
        match query(out.as_mut_ptr().cast::<i32>(), out.capacity()) {
            Ok(info) => {
                // SAFETY: the library wrote info.count <= capacity pairs.
                unsafe { out.set_len(info.count as usize) };
                return Ok(info);
            }
            Err(Error::Capacity { needed, .. }) => {
                let needed = usize::try_from(needed)
                    .map_err(|_| Error::SizeOverflow(format!("{needed} pairs do not fit in memory")))?;
                let room = needed.saturating_add(needed / 8).saturating_add(64);
                if out.try_reserve_exact(room).is_err() {
                    out.try_reserve_exact(needed)
                        .map_err(|e| Error::OutOfMemory(format!("cannot hold {needed} pairs: {e}")))?;
                }
            }
            Err(e) => return Err(e),
        }
    }
    Err(Error::Internal("the pair count changed between two runs of the same query".into()))
}
