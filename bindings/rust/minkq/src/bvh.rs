use std::fmt;
use std::ptr::{self, NonNull};
use std::sync::Arc;

use crate::aabb::Aabb;
use crate::buffer::sealed::Precision;
use crate::buffer::{Buffer, Memory, PairsOut};
use crate::device::{Device, DeviceHandle};
use crate::error::{check, Error, Result};
use crate::inputs::Boxes;
use crate::query::{Mode, QueryFlags, QueryInfo};
use crate::sink::{write_pairs, PairSink};
use crate::sys;

/// The query shapes of a [`BvhQuery`] (`minkq_shape` with its buffers).
///
/// ```
/// use minkq::Shapes;
/// let centres = [[0.5f32, 0.5, 0.5]];
/// let shapes = Shapes::Spheres(&centres);
/// assert!(matches!(shapes, Shapes::Spheres(c) if c.len() == 1));
/// ```
#[non_exhaustive]
#[derive(Clone, Copy, Debug)]
pub enum Shapes<'a> {
    /// Spheres of the query's radius around these centres; modes `Box`, `Sphere`.
    Spheres(&'a [[f32; 3]]),
    /// Capsules of the query's radius around these segments (start, end); modes `Box`,
    /// `CapsuleRay`, `CapsuleExact`.
    Capsules(&'a [[[f32; 3]; 2]]),
    /// Boxes; mode `Box`, radius 0.
    Boxes(&'a [Aabb]),
}

/// A batch of sphere, capsule or box queries against a [`Bvh`] (`minkq_bvh_query_desc`).
///
/// ```
/// use minkq::{BvhQuery, Mode, QueryFlags};
/// let segments = [[[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0]]];
/// let q = BvhQuery::capsules(&segments, Mode::CapsuleExact, 0.1).with_flags(QueryFlags::CANONICAL);
/// assert_eq!(q.mode, Mode::CapsuleExact);
/// ```
#[derive(Clone, Copy, Debug)]
pub struct BvhQuery<'a> {
    /// The query shapes.
    pub shapes: Shapes<'a>,
    /// The node test.
    pub mode: Mode,
    /// `CANONICAL` and `DIGEST` (`LEAF_EXACT` does not apply to boxes).
    pub flags: QueryFlags,
    /// The same r for every query: finite, >= 0.
    pub radius: f32,
}

impl<'a> BvhQuery<'a> {
    /// Spheres of radius `radius` around `centres`.
    ///
    /// ```
    /// let q = minkq::BvhQuery::spheres(&[[0.0; 3]], minkq::Mode::Sphere, 0.5);
    /// assert_eq!(q.radius, 0.5);
    /// ```
    pub fn spheres(centres: &'a [[f32; 3]], mode: Mode, radius: f32) -> BvhQuery<'a> {
        BvhQuery { shapes: Shapes::Spheres(centres), mode, flags: QueryFlags::empty(), radius }
    }

    /// Capsules of radius `radius` around `segments`.
    ///
    /// ```
    /// let q = minkq::BvhQuery::capsules(&[[[0.0; 3], [1.0; 3]]], minkq::Mode::CapsuleRay, 0.5);
    /// assert_eq!(q.mode, minkq::Mode::CapsuleRay);
    /// ```
    pub fn capsules(segments: &'a [[[f32; 3]; 2]], mode: Mode, radius: f32) -> BvhQuery<'a> {
        BvhQuery { shapes: Shapes::Capsules(segments), mode, flags: QueryFlags::empty(), radius }
    }

    /// Box–box overlap queries (mode `Box`, radius 0).
    ///
    /// ```
    /// let boxes = [minkq::Aabb::new([0.0; 3], [1.0; 3])];
    /// let q = minkq::BvhQuery::boxes(&boxes);
    /// assert_eq!((q.mode, q.radius), (minkq::Mode::Box, 0.0));
    /// ```
    pub fn boxes(boxes: &'a [Aabb]) -> BvhQuery<'a> {
        BvhQuery { shapes: Shapes::Boxes(boxes), mode: Mode::Box, flags: QueryFlags::empty(), radius: 0.0 }
    }

    /// The same query with `flags` added.
    ///
    /// ```
    /// use minkq::{BvhQuery, QueryFlags};
    /// let q = BvhQuery::boxes(&[]).with_flags(QueryFlags::DIGEST);
    /// assert!(q.flags.contains(QueryFlags::DIGEST));
    /// ```
    pub fn with_flags(mut self, flags: QueryFlags) -> BvhQuery<'a> {
        self.flags |= flags;
        self
    }

    fn buffers(&self) -> BvhBufferQuery<'a> {
        // Capsule ends and box corners are read in place: two strided views of one array.
        let (shape, first, second) = match self.shapes {
            Shapes::Spheres(centres) => (ShapeKind::Sphere, Buffer::from_slice(centres), Buffer::empty()),
            Shapes::Capsules(segments) => {
                let starts = Buffer::from_slice(segments);
                // SAFETY: each 24-byte record holds the end point 12 bytes in.
                (ShapeKind::Capsule, starts, unsafe { starts.offset(12) })
            }
            Shapes::Boxes(boxes) => {
                let lo = Buffer::from_slice(boxes);
                // SAFETY: each 24-byte Aabb holds `hi` 12 bytes in.
                (ShapeKind::Box, lo, unsafe { lo.offset(12) })
            }
        };
        BvhBufferQuery { shape, first, second, mode: self.mode, flags: self.flags, radius: self.radius }
    }
}

impl<'a> From<&BvhBufferQuery<'a>> for BvhBufferQuery<'a> {
    fn from(query: &BvhBufferQuery<'a>) -> BvhBufferQuery<'a> {
        *query
    }
}

impl<'a> From<&BvhQuery<'a>> for BvhBufferQuery<'a> {
    fn from(query: &BvhQuery<'a>) -> BvhBufferQuery<'a> {
        query.buffers()
    }
}

/// The query shape of a [`BvhBufferQuery`] (`minkq_shape`).
///
/// ```
/// assert_ne!(minkq::ShapeKind::Sphere, minkq::ShapeKind::Capsule);
/// ```
#[non_exhaustive]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ShapeKind {
    /// `first`: centres (3 floats); modes `Box`, `Sphere`.
    Sphere,
    /// `first`, `second`: segment starts and ends (3 floats each); modes `Box`, `CapsuleRay`,
    /// `CapsuleExact`.
    Capsule,
    /// `first`, `second`: two opposite corners (3 floats each); mode `Box`, radius 0.
    Box,
}

impl ShapeKind {
    fn raw(self) -> sys::minkq_shape {
        match self {
            ShapeKind::Sphere => sys::MINKQ_SHAPE_SPHERE,
            ShapeKind::Capsule => sys::MINKQ_SHAPE_CAPSULE,
            ShapeKind::Box => sys::MINKQ_SHAPE_BOX,
        }
    }
}

/// A [`BvhQuery`] over [`Buffer`]s: strided points in host or (on a CUDA device) device
/// memory (`minkq_bvh_query_desc`).
///
/// ```
/// use minkq::{Buffer, BvhBufferQuery, BvhQuery, Mode, ShapeKind};
/// let segments = [[[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0]]];
/// let q = BvhBufferQuery::from(&BvhQuery::capsules(&segments, Mode::CapsuleExact, 0.1));
/// assert_eq!((q.shape, q.first.len(), q.first.byte_stride()), (ShapeKind::Capsule, 1, 24));
/// ```
#[derive(Clone, Copy, Debug)]
pub struct BvhBufferQuery<'a> {
    /// What `first` and `second` hold.
    pub shape: ShapeKind,
    /// Centres, segment starts or first corners.
    pub first: Buffer<'a>,
    /// Segment ends or second corners (same count as `first`); empty for spheres.
    pub second: Buffer<'a>,
    /// The node test.
    pub mode: Mode,
    /// `CANONICAL` and `DIGEST`.
    pub flags: QueryFlags,
    /// The same r for every query: finite, >= 0.
    pub radius: f32,
}

impl<'a> BvhBufferQuery<'a> {
    /// Spheres of radius `radius` around the points of `centres`.
    ///
    /// ```
    /// use minkq::{Buffer, BvhBufferQuery, Mode};
    /// let q = BvhBufferQuery::spheres(Buffer::from_slice(&[[0.0f32; 3]]), Mode::Sphere, 0.5);
    /// assert!(q.second.is_empty());
    /// ```
    pub fn spheres(centres: Buffer<'a>, mode: Mode, radius: f32) -> BvhBufferQuery<'a> {
        BvhBufferQuery {
            shape: ShapeKind::Sphere,
            first: centres,
            second: Buffer::empty(),
            mode,
            flags: QueryFlags::empty(),
            radius,
        }
    }

    /// Capsules of radius `radius` around the segments `starts[i]`–`ends[i]`.
    ///
    /// ```
    /// use minkq::{Buffer, BvhBufferQuery, Mode};
    /// let (a, b) = ([[0.0f32; 3]], [[1.0f32; 3]]);
    /// let q = BvhBufferQuery::capsules(Buffer::from_slice(&a), Buffer::from_slice(&b), Mode::CapsuleRay, 0.5);
    /// assert_eq!(q.radius, 0.5);
    /// ```
    pub fn capsules(starts: Buffer<'a>, ends: Buffer<'a>, mode: Mode, radius: f32) -> BvhBufferQuery<'a> {
        BvhBufferQuery {
            shape: ShapeKind::Capsule,
            first: starts,
            second: ends,
            mode,
            flags: QueryFlags::empty(),
            radius,
        }
    }

    /// Box–box overlap queries against the boxes with corners `first[i]`, `second[i]`.
    ///
    /// ```
    /// use minkq::{Buffer, BvhBufferQuery, Mode};
    /// let (lo, hi) = ([[0.0f32; 3]], [[1.0f32; 3]]);
    /// let q = BvhBufferQuery::boxes(Buffer::from_slice(&lo), Buffer::from_slice(&hi));
    /// assert_eq!((q.mode, q.radius), (Mode::Box, 0.0));
    /// ```
    pub fn boxes(first: Buffer<'a>, second: Buffer<'a>) -> BvhBufferQuery<'a> {
        BvhBufferQuery {
            shape: ShapeKind::Box,
            first,
            second,
            mode: Mode::Box,
            flags: QueryFlags::empty(),
            radius: 0.0,
        }
    }

    /// The same query with `flags` added.
    ///
    /// ```
    /// use minkq::{Buffer, BvhBufferQuery, QueryFlags};
    /// let q = BvhBufferQuery::boxes(Buffer::empty(), Buffer::empty()).with_flags(QueryFlags::CANONICAL);
    /// assert!(q.flags.contains(QueryFlags::CANONICAL));
    /// ```
    pub fn with_flags(mut self, flags: QueryFlags) -> BvhBufferQuery<'a> {
        self.flags |= flags;
        self
    }

    fn raw(&self) -> Result<sys::minkq_bvh_query_desc> {
        Ok(sys::minkq_bvh_query_desc {
            shape: self.shape.raw(),
            mode: self.mode.raw(),
            flags: self.flags.bits(),
            radius: self.radius,
            first: float_buffer("query: first", &self.first)?,
            second: float_buffer("query: second", &self.second)?,
        })
    }
}

/// A BVH over user boxes, answering sphere, capsule and box queries (`minkq_bvh`). Released
/// when dropped; keeps its device alive.
///
/// Threads: `Send` but not `Sync`, as [`Scene`](crate::Scene) and for the same reason: the C
/// API lets one thread at a time use an object.
///
/// ```
/// use minkq::{Aabb, Bvh, BvhQuery, Device, Mode, QueryFlags};
/// let device = Device::cpu()?;
/// let boxes = [Aabb::new([0.0; 3], [1.0; 3]), Aabb::new([2.0; 3], [3.0; 3])];
/// let bvh = Bvh::new(&device, &boxes)?;
/// let centres = [[1.5f32, 1.5, 1.5], [0.5, 0.5, 0.5]];
/// let mut pairs = Vec::new();
/// bvh.query_into(&BvhQuery::spheres(&centres, Mode::Sphere, 0.5).with_flags(QueryFlags::CANONICAL), &mut pairs)?;
/// assert_eq!(pairs, vec![[1, 0]]); // (query, box): only the second centre is inside a box
/// # Ok::<(), minkq::Error>(())
/// ```
///
/// ```compile_fail
/// fn shared_between_threads<T: Sync>() {}
/// shared_between_threads::<minkq::Bvh>(); // Bvh is not Sync
/// ```
pub struct Bvh {
    raw: NonNull<sys::minkq_bvh>,
    len: usize,
    _device: Arc<DeviceHandle>,
}

// SAFETY: as for Scene: one thread at a time, enforced by `Bvh: !Sync`.
unsafe impl Send for Bvh {}

impl Bvh {
    /// Builds a BVH over `boxes`.
    ///
    /// Errors: [`Error::NonFinite`], [`Error::InvalidArgument`] (`"box 3 has lo > hi"`),
    /// [`Error::SizeOverflow`].
    ///
    /// ```
    /// use minkq::{Aabb, Bvh, Device, Error};
    /// let device = Device::cpu()?;
    /// let err = Bvh::new(&device, &[Aabb::new([1.0; 3], [0.0; 3])]).unwrap_err();
    /// assert_eq!(err, Error::InvalidArgument("box 0 has lo > hi".into()));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn new(device: &Device, boxes: &[Aabb]) -> Result<Bvh> {
        Bvh::from_buffer(device, Buffer::from_slice(boxes))
    }

    /// [`Bvh::new`] over a [`Buffer`] of boxes (6 floats per record: lo x, y, z, hi x, y, z),
    /// host or (on a CUDA device) device memory, read in place. A BVH reads floats: a buffer
    /// made from a slice of `[f64; 3]` is [`Error::InvalidArgument`] here, in its refits and
    /// rebuilds and as query points.
    ///
    /// ```
    /// use minkq::{Aabb, Buffer, Bvh, Device};
    /// let boxes = [Aabb::new([0.0; 3], [1.0; 3])];
    /// let bvh = Bvh::from_buffer(&Device::cpu()?, Buffer::from_slice(&boxes))?;
    /// assert_eq!(bvh.len(), 1);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn from_buffer(device: &Device, boxes: Buffer<'_>) -> Result<Bvh> {
        let raw_boxes = float_buffer("create: boxes", &boxes)?;
        let mut raw = ptr::null_mut();
        // SAFETY: a live device; the buffer's constructor promised readable records.
        check(unsafe { sys::minkq_bvh_create(device.handle.as_ptr(), raw_boxes, &mut raw) })?;
        let raw = NonNull::new(raw).ok_or_else(|| Error::Internal("minkq_bvh_create returned NULL".into()))?;
        Ok(Bvh { raw, len: boxes.len(), _device: Arc::clone(&device.handle) })
    }

    /// New boxes (same count): a slice, `Vec` or array of [`Aabb`], or a [`Buffer`] of them in
    /// host or (on a CUDA device) device memory (any [`Boxes`]); refits in place. The tree keeps the grouping of its last build
    /// ([`Bvh::tree_growth`] measures how much that costs, [`Bvh::rebuild`] resets it).
    ///
    /// ```
    /// # use minkq::*;
    /// let mut boxes = vec![Aabb::new([0.0; 3], [1.0; 3])];
    /// let mut bvh = Bvh::new(&Device::cpu()?, &boxes)?;
    /// boxes[0] = Aabb::new([5.0; 3], [6.0; 3]);
    /// bvh.refit(&boxes)?;
    /// let mut pairs = Vec::new();
    /// bvh.query_into(&BvhQuery::spheres(&[[5.5; 3]], Mode::Sphere, 0.0), &mut pairs)?;
    /// assert_eq!(pairs, vec![[0, 0]]);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn refit<'b>(&mut self, boxes: impl Boxes<'b>) -> Result<()> {
        let boxes = float_buffer("refit: boxes", &boxes.into_buffer())?;
        // SAFETY: a live BVH; the buffer's constructor promised readable records.
        check(unsafe { sys::minkq_bvh_refit(self.raw.as_ptr(), boxes) })
    }

    /// Deprecated: [`Bvh::refit`] takes any [`Boxes`]. [`Bvh::refit`] from a [`Buffer`] of boxes, host or (on a CUDA device) device memory.
    ///
    /// ```
    /// # use minkq::*;
    /// let mut bvh = Bvh::new(&Device::cpu()?, &[Aabb::new([0.0; 3], [1.0; 3])])?;
    /// bvh.refit(Buffer::from_slice(&[Aabb::new([2.0; 3], [3.0; 3])]))?;
    /// let err = bvh.refit(Buffer::from_slice::<Aabb>(&[])).unwrap_err();
    /// assert!(matches!(err, Error::InvalidArgument(_)));
    /// // Doubles are refused: a Bvh reads floats.
    /// let err = bvh.refit(Buffer::from_slice(&[[0.0f64; 3], [1.0; 3]])).unwrap_err();
    /// assert_eq!(err, Error::InvalidArgument("refit: boxes: [f64; 3] records, but a Bvh reads floats".into()));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    #[deprecated(note = "use `Bvh::refit`, which takes a `Buffer` too")]
    pub fn refit_buffer(&mut self, boxes: Buffer<'_>) -> Result<()> {
        self.refit(boxes)
    }

    /// New boxes (same count); builds the tree afresh, as [`Bvh::new`] would. The pairs are the
    /// same as after a refit; only the speed of later queries differs (see
    /// [`Bvh::tree_growth`]). Same errors as [`Bvh::refit`]; on error the BVH keeps its boxes
    /// and tree.
    ///
    /// ```
    /// # use minkq::*;
    /// let mut boxes = vec![Aabb::new([0.0; 3], [1.0; 3]), Aabb::new([2.0; 3], [3.0; 3])];
    /// let mut bvh = Bvh::new(&Device::cpu()?, &boxes)?;
    /// boxes.swap(0, 1);
    /// bvh.rebuild(&boxes)?;
    /// assert_eq!(bvh.tree_growth()?, 1.0);
    /// let mut pairs = Vec::new();
    /// bvh.query_into(&BvhQuery::spheres(&[[2.5; 3]], Mode::Sphere, 0.0), &mut pairs)?;
    /// assert_eq!(pairs, vec![[0, 0]]);
    /// let err = bvh.rebuild(&boxes[..1]).unwrap_err();
    /// assert_eq!(err, Error::InvalidArgument("rebuild with 1 boxes but the bvh has 2".into()));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn rebuild<'b>(&mut self, boxes: impl Boxes<'b>) -> Result<()> {
        let boxes = float_buffer("rebuild: boxes", &boxes.into_buffer())?;
        // SAFETY: a live BVH; the buffer's constructor promised readable records.
        check(unsafe { sys::minkq_bvh_rebuild(self.raw.as_ptr(), boxes) })
    }

    /// Deprecated: [`Bvh::rebuild`] takes any [`Boxes`]. [`Bvh::rebuild`] from a [`Buffer`] of boxes, host or (on a CUDA device) device memory.
    ///
    /// ```
    /// # use minkq::*;
    /// let mut bvh = Bvh::new(&Device::cpu()?, &[Aabb::new([0.0; 3], [1.0; 3])])?;
    /// bvh.rebuild(Buffer::from_slice(&[Aabb::new([2.0; 3], [3.0; 3])]))?;
    /// let err = bvh.rebuild(Buffer::from_slice(&[Aabb::new([3.0; 3], [2.0; 3])])).unwrap_err();
    /// assert_eq!(err, Error::InvalidArgument("box 0 has lo > hi".into()));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    #[deprecated(note = "use `Bvh::rebuild`, which takes a `Buffer` too")]
    pub fn rebuild_buffer(&mut self, boxes: Buffer<'_>) -> Result<()> {
        self.rebuild(boxes)
    }

    /// How much the refits since the last build (creation or [`Bvh::rebuild`]) have degraded
    /// the tree: its area cost now over its value right after that build, as
    /// [`Scene::tree_growth`](crate::Scene::tree_growth). 1 after a build; infinity once a
    /// tree built without area (boxes on one line parallel to an axis, or at one point) gains
    /// any.
    ///
    /// ```
    /// # use minkq::*;
    /// // Unit boxes along a diagonal, then each moved to the mirror position.
    /// let boxes: Vec<Aabb> = (0..16).map(|i| Aabb::new([i as f32; 3], [i as f32 + 1.0; 3])).collect();
    /// let mut bvh = Bvh::new(&Device::cpu()?, &boxes)?;
    /// assert_eq!(bvh.tree_growth()?, 1.0);
    /// let mixed: Vec<Aabb> =
    ///     (0..16).map(|i| if i % 2 == 0 { boxes[i] } else { boxes[15 - i] }).collect();
    /// bvh.refit(&mixed)?;
    /// assert!(bvh.tree_growth()? > 1.5);
    /// bvh.rebuild(&mixed)?;
    /// assert_eq!(bvh.tree_growth()?, 1.0);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn tree_growth(&self) -> Result<f64> {
        let mut growth = 0.0;
        // SAFETY: a live BVH; `growth` is a writable double.
        check(unsafe { sys::minkq_bvh_tree_growth(self.raw.as_ptr(), &mut growth) })?;
        Ok(growth)
    }

    /// The number of boxes.
    ///
    /// ```
    /// # use minkq::*;
    /// let bvh = Bvh::new(&Device::cpu()?, &[Aabb::default(); 3])?;
    /// assert_eq!(bvh.len(), 3);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the BVH holds no box.
    ///
    /// ```
    /// # use minkq::*;
    /// assert!(Bvh::new(&Device::cpu()?, &[])?.is_empty());
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Pairs (query, box) for every query shape overlapping a box, into caller-owned memory
    /// chosen by the type of `out` (a [`PairSink`]: a `Vec` grows, a slice, an array or a
    /// [`PairsOut`] has a fixed capacity and gives [`Error::Capacity`] with the exact count when
    /// it is too small). The query is a [`BvhQuery`] over slices or a [`BvhBufferQuery`] over
    /// [`Buffer`]s (host or, on a CUDA device, device memory).
    ///
    /// ```
    /// # use minkq::*;
    /// let bvh = Bvh::new(&Device::cpu()?, &[Aabb::new([0.0; 3], [1.0; 3])])?;
    /// let segments = [[[-1.0, 0.5, 0.5], [2.0, 0.5, 0.5]], [[-1.0, 3.0, 0.5], [2.0, 3.0, 0.5]]];
    /// let mut out = [[0; 2]; 4];
    /// let info = bvh.query_into(&BvhQuery::capsules(&segments, Mode::CapsuleExact, 0.1), &mut out)?;
    /// assert_eq!(&out[..info.count as usize], &[[0, 0]]);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn query_into<'q, 'o>(
        &self,
        query: impl Into<BvhBufferQuery<'q>>,
        out: impl PairSink<'o>,
    ) -> Result<QueryInfo> {
        let query = query.into();
        write_pairs(out, |pairs, capacity, memory| self.query_raw(&query, pairs, capacity, memory))
    }

    /// Deprecated: [`Bvh::query_into`] takes both. Queries over [`Buffer`]s into a [`PairsOut`], host or (on a CUDA device) device
    /// memory; [`Error::Capacity`] with the exact count when `out` is too small.
    ///
    /// ```
    /// # use minkq::*;
    /// let bvh = Bvh::new(&Device::cpu()?, &[Aabb::new([0.0; 3], [1.0; 3])])?;
    /// // Centres with a fourth float each (16-byte records), read in place.
    /// let points = [[0.5f32, 0.5, 0.5, 1.0], [5.0, 5.0, 5.0, 1.0]];
    /// // SAFETY: two 16-byte records starting with x, y, z, borrowed from `points`.
    /// let centres = unsafe { Buffer::from_raw_parts(points.as_ptr().cast(), 16, 2, Memory::Host) };
    /// let mut out = [[0; 2]; 2];
    /// let info = bvh.query_into(&BvhBufferQuery::spheres(centres, Mode::Sphere, 0.1), PairsOut::from_slice(&mut out))?;
    /// assert_eq!(&out[..info.count as usize], &[[0, 0]]);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    #[deprecated(note = "use `Bvh::query_into`, which takes a `BvhBufferQuery` and a `PairsOut` too")]
    pub fn query_to(&self, query: &BvhBufferQuery<'_>, out: PairsOut<'_>) -> Result<QueryInfo> {
        self.query_into(query, out)
    }

    /// Deprecated: [`Bvh::query_into`] takes a `Vec`. Pairs (query, box) into a `Vec`, grown when too small to the exact count and an eighth
    /// more (as [`PairSink`] says).
    ///
    /// ```
    /// # use minkq::*;
    /// let bvh = Bvh::new(&Device::cpu()?, &[Aabb::new([0.0; 3], [1.0; 3]), Aabb::new([0.5; 3], [2.0; 3])])?;
    /// let mut pairs = Vec::new();
    /// let info = bvh.query_into(&BvhQuery::boxes(&[Aabb::new([0.9; 3], [1.1; 3])]).with_flags(QueryFlags::DIGEST), &mut pairs)?;
    /// assert_eq!(pairs, vec![[0, 0], [0, 1]]);
    /// assert!(info.digest.is_some());
    /// # Ok::<(), minkq::Error>(())
    /// ```
    #[deprecated(note = "use `Bvh::query_into`, which takes a `Vec` too")]
    pub fn query_vec(&self, query: &BvhQuery<'_>, out: &mut Vec<[i32; 2]>) -> Result<QueryInfo> {
        self.query_into(query, out)
    }

    /// The exact number of pairs a query finds, without writing them ([`QueryFlags::COUNT`]
    /// added; `CANONICAL` and `DIGEST` are refused).
    ///
    /// ```
    /// # use minkq::*;
    /// let bvh = Bvh::new(&Device::cpu()?, &[Aabb::new([0.0; 3], [1.0; 3]), Aabb::new([0.5; 3], [2.0; 3])])?;
    /// assert_eq!(bvh.count(&BvhQuery::boxes(&[Aabb::new([0.9; 3], [1.1; 3])]))?, 2);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn count(&self, query: &BvhQuery<'_>) -> Result<u64> {
        self.count_buffers(&BvhBufferQuery::from(query))
    }

    /// [`Bvh::count`] of a query over [`Buffer`]s (host or, on a CUDA device, device memory).
    ///
    /// ```
    /// # use minkq::*;
    /// let bvh = Bvh::new(&Device::cpu()?, &[Aabb::new([0.0; 3], [1.0; 3])])?;
    /// let centres = [[0.5f32, 0.5, 0.5], [5.0, 5.0, 5.0]];
    /// let query = BvhBufferQuery::spheres(Buffer::from_slice(&centres), Mode::Sphere, 0.1);
    /// assert_eq!(bvh.count_buffers(&query)?, 1);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn count_buffers(&self, query: &BvhBufferQuery<'_>) -> Result<u64> {
        let mut query = *query;
        query.flags |= QueryFlags::COUNT;
        Ok(self.query_raw(&query, ptr::null_mut(), 0, Memory::Host)?.count)
    }

    fn query_raw(
        &self,
        query: &BvhBufferQuery<'_>,
        pairs: *mut i32,
        capacity: usize,
        memory: Memory,
    ) -> Result<QueryInfo> {
        let desc = query.raw()?;
        let mut info = QueryInfo::raw();
        // SAFETY: the description's buffers are readable (their constructors' promise);
        // `pairs` holds 2 * capacity writable int32 in `memory`.
        let status =
            unsafe { sys::minkq_bvh_query(self.raw.as_ptr(), &desc, pairs, capacity, memory.raw(), &mut info) };
        match check(status) {
            Ok(()) => Ok(QueryInfo::from_raw(&info, query.flags)),
            Err(Error::Capacity { message, .. }) => Err(Error::Capacity { needed: info.count, message }),
            Err(e) => Err(e),
        }
    }
}

/// The C buffer of `what` for a BVH, which reads floats: [`Error::InvalidArgument`] for a
/// slice of `[f64; 3]` records (the vertices of a float64 scene), which it would misread.
fn float_buffer(what: &str, buffer: &Buffer<'_>) -> Result<sys::minkq_buffer> {
    buffer
        .raw_at(Precision::F32)
        .map_err(|got| Error::InvalidArgument(format!("{what}: {} records, but a Bvh reads floats", got.vertex())))
}

impl Drop for Bvh {
    fn drop(&mut self) {
        // SAFETY: created by minkq_bvh_create and released once, before its device.
        unsafe { sys::minkq_bvh_release(self.raw.as_ptr()) }
    }
}

impl fmt::Debug for Bvh {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Bvh").field("boxes", &self.len).finish()
    }
}
