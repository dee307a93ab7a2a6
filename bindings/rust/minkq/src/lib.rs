//! Safe Rust API for minkq: which pairs of mesh elements may lie within distance r of each
//! other?
//!
//! minkq builds a BVH over triangles, edges or boxes and runs batched sphere, capsule and box
//! queries against it, on the CPU or with CUDA. Cloth and soft-body simulators use it for their
//! per-step broad phase: **VT** pairs (vertex within r of a triangle) and **EE** pairs (edge
//! within r of an edge). Codimensional elements (particles, rods, yarn: [`SceneDesc::codim`])
//! get **VV** pairs (vertex within r of a vertex) and **EV** pairs (vertex within r of an edge).
//! Every pair within r is reported, in every [`Mode`], for every finite input; finer modes
//! report subsets of coarser ones.
//!
//! This crate wraps the C ABI (`capi/minkq.h`, bound raw in [`sys`]): every handle is owned by
//! a type that releases it in `Drop`, every call returns [`Result`] with the library's message,
//! and pairs come back as slices of `[i32; 2]`: [`Scene::query`] into a library-owned
//! [`PairBuffer`], [`Scene::query_into`] into memory of the caller's (a [`PairSink`]: a `Vec`
//! that grows, a slice, or a [`PairsOut`] in device memory). One [`Scene::refit`] (and
//! `rebuild`, `refit_swept`, `rebuild_swept`) takes every kind of [`Vertices`]: `[f32; 3]` or
//! `[f64; 3]` slices, `Vec`s and arrays, and [`Buffer`]s.
//!
//! ```
//! use minkq::{Device, Mode, PairBuffer, Query, QueryFlags, Scene, SceneDesc};
//!
//! let device = Device::new("auto")?;
//! // Two triangles, one 0.1 above the other.
//! let mut vertices = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0],
//!                         [0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]];
//! let triangles = [[0, 1, 2], [3, 4, 5]];
//! let mut scene = Scene::new(&device, &SceneDesc::new(&vertices, &triangles))?;
//! let mut pairs = PairBuffer::new()?;
//! let r = 0.2;
//! let vt = scene.query(&Query::vt(Mode::Box, r).with_flags(QueryFlags::LEAF_EXACT), &mut pairs)?;
//! assert_eq!(vt.len(), 6);
//! let ee = scene.query(&Query::ee(Mode::CapsuleExact, r), &mut pairs)?;
//! assert!(ee.len() >= 9);
//!
//! // Every simulation step: move the vertices, refit, query again.
//! for v in &mut vertices[3..] {
//!     v[2] += 1.0;
//! }
//! scene.refit(&vertices)?;
//! assert!(scene.query(&Query::ee(Mode::CapsuleExact, r), &mut pairs)?.is_empty());
//! // Once large motions have degraded the refitted trees, build them afresh (same pairs).
//! if scene.tree_growth()? > 1.5 {
//!     scene.rebuild(&vertices)?;
//! }
//! # Ok::<(), minkq::Error>(())
//! ```
//!
//! # Refit and rebuild
//! [`Scene::refit`] moves the vertices and updates the trees' boxes in place, keeping the
//! grouping of the last build: cheap, but after large deformations the boxes overlap more and
//! queries visit more nodes. [`Scene::tree_growth`] tracks how far refits have stretched the
//! trees (their area cost over its value at the last build: 1 after a build; it misses a mesh
//! folding into new neighbours), and [`Scene::rebuild`] moves the vertices and builds the
//! trees afresh. Both give the same pairs; [`Bvh`] has the same three
//! calls.
//!
//! # Codimensional elements
//! A scene need not hold triangles: [`SceneDesc::codim`] takes vertices and explicit edges (a
//! rod is a polyline, a particle a vertex of no edge) with [`SceneFlags::VV`],
//! [`SceneFlags::EV`] and [`SceneFlags::DROP_INCIDENT`]. [`Query::vv`] pairs vertices within r,
//! once each as (v, w) with v < w (neighbours along a rod too: no VV pair is incident);
//! [`Query::ev`] pairs a vertex with an edge within r, not with its own edges. Every mode
//! (points are zero-length capsules), [`QueryFlags::LEAF_EXACT`], float64 vertices and swept
//! steps work as for VT. The flags can join [`SceneFlags::VT`] and [`SceneFlags::EE`] on a
//! triangle mesh; a query of a kind the scene was built without is
//! [`Error::InvalidArgument`].
//!
//! ```
//! use minkq::{Device, Mode, PairBuffer, Query, QueryFlags, Scene, SceneDesc};
//! // Two parallel rods 0.05 apart, 4 vertices each, 0.2 between neighbours.
//! let vertices: Vec<[f32; 3]> = (0..8).map(|i| [(i % 4) as f32 * 0.2, (i / 4) as f32 * 0.05, 0.0]).collect();
//! let edges = [[0, 1], [1, 2], [2, 3], [4, 5], [5, 6], [6, 7]];
//! let scene = Scene::new(&Device::cpu()?, &SceneDesc::codim(&vertices, &edges))?;
//! let contacts = QueryFlags::LEAF_EXACT | QueryFlags::CANONICAL;
//! let mut pairs = PairBuffer::new()?;
//! let vv = scene.query(&Query::vv(Mode::Box, 0.1).with_flags(contacts), &mut pairs)?;
//! assert_eq!(vv, &[[0, 4], [1, 5], [2, 6], [3, 7]]);
//! let ev = scene.query(&Query::ev(Mode::Box, 0.1).with_flags(contacts), &mut pairs)?;
//! assert_eq!(ev.len(), 12); // each vertex against the one or two edges facing it
//! # Ok::<(), minkq::Error>(())
//! ```
//!
//! # Scenes of many geometries
//! [`Scene::from_geometries`] builds one scene of many [`GeometryDesc`]s: cloth, colliders,
//! rods and particles, each with its own vertices (`[f32; 3]` or `[f64; 3]`), [`Kinds`],
//! thickness per vertex, world, collision group and mask, and [`GeometryFlags`] (self pairs,
//! static). Its queries report self pairs within geometries that ask for them and cross pairs
//! between geometries that share a kind and a world and pass each other's masks, in one
//! global numbering ([`Scene::geometry_range`], [`Scene::locate_pair`]). A step moves the
//! moving geometries together ([`Scene::refit`]) or one at a time
//! ([`Scene::refit_geometry`]); static ones are built once.
//!
//! # Float64 vertices
//! A scene built from `[f64; 3]` vertices ([`SceneDesc::new_f64`]; [`SceneFlags::FLOAT64`] on
//! [`SceneBuffers`]) rounds them to float, the precision of its trees and tests, and widens
//! every query radius by twice the farthest the rounding moved a vertex, so that every pair
//! within r in double is reported, in every mode. Its refits and rebuilds take `[f64; 3]`
//! (slices of doubles or buffers of them: every [`Vertices`]); vertices of the other
//! precision are refused with [`Error::InvalidArgument`], and a double beyond the float range
//! is [`Error::NonFinite`].
//!
//! # Swept positions
//! For continuous collision detection, [`Scene::refit_swept`] and [`Scene::rebuild_swept`]
//! take the positions at the start and the end of a step (any [`Vertices`], as
//! [`Scene::refit`] does: `[f32; 3]`, `[f64; 3]` or [`Buffer`]s). Every vertex moves
//! linearly between them, and the queries report every pair whose elements come within r at
//! some time of the step: the candidates a narrow phase then decides. VT tests the vertex's
//! path, EE runs [`Mode::Box`] only, and [`QueryFlags::LEAF_EXACT`] is [`Error::Unsupported`].
//! The scene stays swept ([`Scene::is_swept`]) until a plain refit or rebuild. Stream-ordered
//! swept steps: [`Scene::refit_swept_async`] and [`Scene::rebuild_swept_async`] (with
//! [`Reserve::SWEPT`]; a non-finite coordinate in either buffer leaves the scene at rest).
//!
//! # Threads
//! The C API allows different objects to be used from different threads at once, but one
//! object only from one thread at a time, and lets scenes on different threads share a device.
//! So [`Device`], [`Scene`], [`Bvh`] and [`PairBuffer`] are `Send` (they can move to another
//! thread) and not `Sync` (a shared reference cannot cross threads, which would let two threads
//! call into the same object). Scenes and BVHs keep their device alive, and can be sent to
//! other threads independently of it.
//!
//! # Device memory and strided arrays
//! Besides slices, scenes and BVHs take [`Buffer`]s: records at any byte stride, in host
//! memory or, on a CUDA device, in device memory read in place ([`Scene::from_buffers`],
//! [`Scene::refit`] and [`Scene::rebuild`] (a buffer is a [`Vertices`]),
//! [`Scene::query_into`] with a [`PairsOut`] (a [`PairSink`]), and the same on [`Bvh`]). A buffer over a raw pointer is built with the
//! `unsafe` [`Buffer::from_raw_parts`]; every call taking it is safe. The blocking calls take
//! no stream: on a CUDA device the library works on the calling thread's per-thread default
//! stream and synchronises it before each call returns, so inputs must be ready (or ordered
//! before that stream) when a call is made, and outputs are ready for every stream when it
//! returns.
//!
//! # Stream-ordered calls
//! A simulator that records its step into a CUDA graph uses the scene's asynchronous calls
//! instead: [`Scene::refit_async`], [`Scene::rebuild_async`], [`Scene::query_async`] and
//! [`Scene::query_vt_ee_async`] enqueue their work on a [`Stream`] and return without
//! synchronising, allocating or reading results on the host. Their buffers are device memory
//! on CUDA (host memory on the CPU, where the calls run to completion and the stream is
//! ignored: a program tested on the CPU keeps the same rules); a query writes its exact pair
//! count to a [`CountOut`] and at most its capacity of pairs, never [`Error::Capacity`].
//! [`Scene::reserve`] reserves their scratch beforehand, and [`Scene::async_status`] waits for
//! the stream and reports a refit or rebuild that met a non-finite vertex (the scene then kept
//! its positions).
//!
//! ```
//! use minkq::{Buffer, CountOut, Device, Mode, PairsOut, Query, QueryFlags, Reserve, Scene, SceneDesc, Stream};
//!
//! let mut vertices = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0],
//!                         [0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]];
//! let mut scene = Scene::new(&Device::cpu()?, &SceneDesc::new(&vertices, &[[0, 1, 2], [3, 4, 5]]))?;
//! let mut pairs = vec![[0i32; 2]; 64];
//! scene.reserve(Reserve::REFIT, pairs.len())?; // before capturing: the calls below never allocate
//! let query = Query::vt(Mode::Box, 0.2).with_flags(QueryFlags::LEAF_EXACT | QueryFlags::CANONICAL);
//! let mut count = 0u64;
//! for _step in 0..3 {
//!     for v in &mut vertices[3..] {
//!         v[2] += 0.01;
//!     }
//!     scene.refit_async(Buffer::from_slice(&vertices), Stream::null())?;
//!     scene.query_async(&query, PairsOut::from_slice(&mut pairs), CountOut::from_mut(&mut count), Stream::null())?;
//!     scene.async_status(Stream::null())?; // waits for the stream; Ok: every vertex was finite
//!     assert!(count as usize <= pairs.len()); // else grow `pairs` (and the reservation) and run again
//! }
//! assert_eq!(count, 6);
//! # Ok::<(), minkq::Error>(())
//! ```
//!
//! # Linking
//! `minkq-sys` links `libminkq.so` from `MINKQ_LIB_DIR` (the CMake build's `capi/` folder) or
//! builds it with CMake; this crate's tests and examples find it at run time through an rpath.
//!
//! # Cargo features
//! `cuda`: where `minkq-sys` builds `libminkq.so` itself (no `MINKQ_LIB_DIR`, in the source
//! tree), it builds it with the CUDA backend (`MINKQ_WITH_CUDA=ON`, which needs the CUDA
//! toolkit; the variable, when set, decides). Off by default: the default build needs no CUDA.
//! The feature gates no API: [`Device::cuda`], device-memory [`Buffer`]s and [`PairsOut`], and
//! [`Stream`]s exist in every build, and without a usable GPU they are refused with
//! [`Error::Unsupported`] or [`Error::InvalidArgument`], so that one program serves both
//! backends ([`Device::new`]`("auto")` picks).
#![deny(missing_docs)]

mod aabb;
mod buffer;
mod bvh;
mod device;
mod error;
mod geometry;
mod inputs;
mod pairs;
mod query;
mod scene;
mod sink;
mod stream;

/// The raw FFI bindings (`minkq-sys`), for what the safe API does not cover.
///
/// ```
/// assert_eq!(minkq::sys::MINKQ_ABI_VERSION, minkq::ABI_VERSION);
/// ```
pub use minkq_sys as sys;

pub use aabb::Aabb;
pub use buffer::{Buffer, Memory, PairsOut, Record, Vertex};
pub use bvh::{Bvh, BvhBufferQuery, BvhQuery, ShapeKind, Shapes};
pub use device::{cuda_device_count, Backend, Device};
pub use error::{Error, Result};
pub use geometry::{Element, GeometryDesc, GeometryFlags, Kinds};
pub use inputs::{Boxes, Vertices};
pub use pairs::PairBuffer;
pub use query::{Mode, Query, QueryFlags, QueryInfo, QueryKind, Reserve, SceneFlags, WorkStats};
pub use scene::{Scene, SceneBuffers, SceneDesc};
pub use sink::PairSink;
pub use stream::{CountOut, Stream};

/// The ABI version this crate was generated against (`MINKQ_ABI_VERSION`).
///
/// ```
/// assert_eq!(minkq::abi_version(), minkq::ABI_VERSION);
/// ```
pub const ABI_VERSION: u32 = sys::MINKQ_ABI_VERSION;

/// The run-time library's ABI version; differs from [`ABI_VERSION`] when a mismatched
/// libminkq.so was loaded.
///
/// ```
/// assert_eq!(minkq::abi_version(), minkq::ABI_VERSION);
/// ```
pub fn abi_version() -> u32 {
    // SAFETY: no arguments.
    unsafe { sys::minkq_abi_version() }
}

/// The run-time library's version as (major, minor, patch).
///
/// ```
/// let (major, minor, patch) = minkq::version();
/// assert_eq!((major, minor, patch), (minkq::sys::MINKQ_VERSION_MAJOR, minkq::sys::MINKQ_VERSION_MINOR, minkq::sys::MINKQ_VERSION_PATCH));
/// ```
pub fn version() -> (u32, u32, u32) {
    // SAFETY: no arguments.
    let v = unsafe { sys::minkq_version() };
    (v / 10000, v / 100 % 100, v % 100)
}
