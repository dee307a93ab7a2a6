//! [`PairSink`]: where [`Scene::query_into`](crate::Scene::query_into) and
//! [`Bvh::query_into`](crate::Bvh::query_into) write their pairs, chosen by the type of `out`.
use crate::buffer::{Memory, PairsOut};
use crate::error::Result;
use crate::pairs::query_vec;
use crate::query::QueryInfo;

pub(crate) mod sealed {
    use crate::buffer::PairsOut;

    /// Where the pairs go, as the query calls handle it.
    pub enum Sink<'o> {
        /// A `Vec` that grows to the count (the query then runs twice).
        Grow(&'o mut Vec<[i32; 2]>),
        /// Memory of a fixed capacity: `Error::Capacity` when the pairs do not fit.
        Fixed(PairsOut<'o>),
    }

    pub trait Sealed<'o> {
        fn sink(self) -> Sink<'o>;
    }
}
use sealed::Sink;

/// Caller-owned memory that a query writes its pairs into, (vertex, triangle) for VT, (e, f)
/// for EE and so on, as [`Scene::query_into`](crate::Scene::query_into) and
/// [`Bvh::query_into`](crate::Bvh::query_into) take it. Sealed; implemented for:
/// - `&mut Vec<[i32; 2]>`: cleared, then grown when too small (the query then runs twice) to
///   the exact count and an eighth more, so that a count that grows a little from one step to
///   the next fits; on success it holds exactly the pairs;
/// - `&mut [[i32; 2]]` and `&mut [[i32; 2]; N]`: a fixed capacity; the first `count` entries
///   are written, and [`Error::Capacity`](crate::Error::Capacity) (with the exact count needed,
///   nothing written past the end) when the pairs do not fit;
/// - [`PairsOut`]: a fixed capacity in host or (on a CUDA device) device memory, written in
///   place and ready for any stream when the call returns.
///
/// The library-owned [`PairBuffer`](crate::PairBuffer) is
/// [`Scene::query`](crate::Scene::query)'s.
///
/// ```
/// # use minkq::*;
/// # let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]];
/// # let scene = Scene::new(&Device::cpu()?, &SceneDesc::new(&vertices, &[[0, 1, 2], [3, 4, 5]]))?;
/// let query = Query::vt(Mode::Sphere, 0.2).with_flags(QueryFlags::CANONICAL);
/// let mut grown = Vec::new();
/// assert_eq!(scene.query_into(&query, &mut grown)?.count, 6);
/// let mut fixed = [[0; 2]; 8];
/// let info = scene.query_into(&query, &mut fixed)?;
/// assert_eq!(&fixed[..info.count as usize], &grown[..]);
/// let mut small = [[0; 2]; 4];
/// assert!(matches!(scene.query_into(&query, &mut small[..]), Err(Error::Capacity { needed: 6, .. })));
/// scene.query_into(&query, PairsOut::from_slice(&mut fixed))?;
/// # Ok::<(), minkq::Error>(())
/// ```
pub trait PairSink<'o>: sealed::Sealed<'o> {}

impl<'o> sealed::Sealed<'o> for &'o mut Vec<[i32; 2]> {
    fn sink(self) -> Sink<'o> {
        Sink::Grow(self)
    }
}
impl<'o> sealed::Sealed<'o> for &'o mut [[i32; 2]] {
    fn sink(self) -> Sink<'o> {
        Sink::Fixed(PairsOut::from_slice(self))
    }
}
impl<'o, const N: usize> sealed::Sealed<'o> for &'o mut [[i32; 2]; N] {
    fn sink(self) -> Sink<'o> {
        Sink::Fixed(PairsOut::from_slice(self))
    }
}
impl<'o> sealed::Sealed<'o> for PairsOut<'o> {
    fn sink(self) -> Sink<'o> {
        Sink::Fixed(self)
    }
}
impl<'o> PairSink<'o> for &'o mut Vec<[i32; 2]> {}
impl<'o> PairSink<'o> for &'o mut [[i32; 2]] {}
impl<'o, const N: usize> PairSink<'o> for &'o mut [[i32; 2]; N] {}
impl<'o> PairSink<'o> for PairsOut<'o> {}

/// Runs `query(pairs, capacity, memory)` into `out`: once into fixed memory, or into a `Vec`
/// grown as [`PairSink`] says.
pub(crate) fn write_pairs<'o>(
    out: impl PairSink<'o>,
    mut query: impl FnMut(*mut i32, usize, Memory) -> Result<QueryInfo>,
) -> Result<QueryInfo> {
    match out.sink() {
        Sink::Grow(pairs) => query_vec(pairs, |data, capacity| query(data, capacity, Memory::Host)),
        Sink::Fixed(pairs) => query(pairs.data(), pairs.capacity(), pairs.memory()),
    }
}
