//! A scene's blocking queries: into a [`PairBuffer`] or any [`PairSink`]; VT and
//! EE in one pass; the work a query does.
use std::ptr;

use super::Scene;
use crate::buffer::{Memory, PairsOut};
use crate::error::{check, Error, Result};
use crate::pairs::PairBuffer;
use crate::query::{Query, QueryFlags, QueryInfo, WorkStats};
use crate::sink::{write_pairs, PairSink};
use crate::sys;

/// The VT and the EE pairs of [`Scene::query_vt_ee`].
type VtEePairs<'r> = (&'r [[i32; 2]], &'r [[i32; 2]]);

impl Scene {
    /// Runs a query into a library-owned buffer that grows as needed and is reused from one
    /// call to the next ([`Scene::query_into`] writes caller-owned memory); returns its pairs,
    /// (vertex, triangle) for VT, (e, f) with e < f for EE, (v, w) with v < w for VV and
    /// (vertex, edge) for EV.
    ///
    /// Errors: [`Error::InvalidArgument`] (a query of a kind the scene was built without, e.g.
    /// `"VV query on a scene created without MINKQ_SCENE_VV"`, sphere mode for EE, a negative
    /// radius), [`Error::NonFinite`] (radius).
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

    /// Runs a query into caller-owned memory, chosen by the type of `out` (a [`PairSink`]): a
    /// `Vec` grows to the pairs; a slice, an array or a [`PairsOut`] (host or, on a CUDA
    /// device, device memory) has a fixed capacity, and if more pairs exist than it holds,
    /// nothing is written past it and the error is [`Error::Capacity`] with the exact count
    /// needed. Returns the count (and the digest and work stats the query's flags ask for).
    /// Errors as for [`Scene::query`].
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
    /// assert_eq!(scene.query_into(&query, &mut enough[..])?.count, 6);
    /// let mut grown = Vec::new();
    /// assert_eq!(scene.query_into(&query, &mut grown)?.count, 6);
    /// assert_eq!(grown.len(), 6);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn query_into<'o>(&self, query: &Query, out: impl PairSink<'o>) -> Result<QueryInfo> {
        write_pairs(out, |pairs, capacity, memory| self.query_raw(query, pairs, capacity, memory))
    }

    /// Deprecated: [`Scene::query_into`] takes a [`PairsOut`]. Runs a query into a [`PairsOut`]: host memory, or (on a CUDA device) device memory
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
    /// let info = scene.query_into(&Query::vt(Mode::Sphere, 0.2).with_flags(QueryFlags::CANONICAL), PairsOut::from_slice(&mut pairs))?;
    /// assert_eq!(&pairs[..info.count as usize], &[[0, 1], [1, 1], [2, 1], [3, 0], [4, 0], [5, 0]]);
    /// // Device memory on a CPU device is refused before it is written.
    /// // SAFETY: never written: the CPU device rejects device memory.
    /// let on_gpu = unsafe { PairsOut::from_raw_parts(pairs.as_mut_ptr().cast(), 8, Memory::Device) };
    /// assert!(matches!(scene.query_into(&Query::vt(Mode::Sphere, 0.2), on_gpu), Err(Error::InvalidArgument(_))));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    #[deprecated(note = "use `Scene::query_into`, which takes a `PairsOut` too")]
    pub fn query_to(&self, query: &Query, out: PairsOut<'_>) -> Result<QueryInfo> {
        self.query_into(query, out)
    }

    /// Deprecated: [`Scene::query_into`] takes a `Vec`. Runs a query into a `Vec`, growing it when it is too small (the query then runs twice)
    /// to the exact count and an eighth more, so that a count that grows a little from one step
    /// to the next fits; on success the `Vec` holds exactly the pairs.
    ///
    /// ```
    /// # use minkq::*;
    /// # let device = Device::cpu()?;
    /// # let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]];
    /// # let triangles = [[0, 1, 2], [3, 4, 5]];
    /// # let scene = Scene::new(&device, &SceneDesc::new(&vertices, &triangles))?;
    /// let mut pairs = Vec::new();
    /// let info = scene.query_into(&Query::ee(Mode::Box, 0.2).with_flags(QueryFlags::CANONICAL), &mut pairs)?;
    /// assert_eq!(info.count as usize, pairs.len());
    /// assert!(pairs.windows(2).all(|w| w[0] < w[1]));
    /// assert!(pairs.capacity() >= pairs.len() + pairs.len() / 8 + 64); // room to grow
    /// # Ok::<(), minkq::Error>(())
    /// ```
    #[deprecated(note = "use `Scene::query_into`, which takes a `Vec` too")]
    pub fn query_vec(&self, query: &Query, out: &mut Vec<[i32; 2]>) -> Result<QueryInfo> {
        self.query_into(query, out)
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
    ) -> Result<VtEePairs<'r>> {
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
        let info = self.count_raw(&query.with_flags(QueryFlags::STATS))?;
        Ok(info.stats.unwrap_or_default())
    }

    /// The exact number of pairs a query finds, without writing or keeping them
    /// ([`QueryFlags::COUNT`] added): to size a buffer first, or when the count is all that
    /// is needed. Its other flags apply (`LEAF_EXACT` counts contacts); `CANONICAL` and
    /// `DIGEST` are refused.
    ///
    /// ```
    /// # use minkq::*;
    /// # let device = Device::cpu()?;
    /// # let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]];
    /// # let triangles = [[0, 1, 2], [3, 4, 5]];
    /// # let scene = Scene::new(&device, &SceneDesc::new(&vertices, &triangles))?;
    /// let query = Query::vt(Mode::Sphere, 0.2);
    /// assert_eq!(scene.count(&query)?, 6);
    /// let mut exact = vec![[0; 2]; 6];
    /// assert_eq!(scene.query_into(&query, &mut exact)?.count, 6);
    /// let digest = query.with_flags(QueryFlags::DIGEST);
    /// assert!(matches!(scene.count(&digest), Err(Error::InvalidArgument(_))));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn count(&self, query: &Query) -> Result<u64> {
        Ok(self.count_raw(query)?.count)
    }

    fn count_raw(&self, query: &Query) -> Result<QueryInfo> {
        let query = query.with_flags(QueryFlags::COUNT);
        let desc = query.raw();
        let mut info = QueryInfo::raw();
        // SAFETY: a count-only query writes no pair: the null pointer is never written.
        let status = unsafe {
            sys::minkq_scene_query(self.raw.as_ptr(), &desc, ptr::null_mut(), 0, Memory::Host.raw(), &mut info)
        };
        check(status)?;
        Ok(QueryInfo::from_raw(&info, query.flags))
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
