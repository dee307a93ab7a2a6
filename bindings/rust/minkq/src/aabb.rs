//! The box record the C API reads for BVH builds, refits and box queries: its own module so
//! that `buffer` (which seals it as a record) and `bvh` (which builds over it) both depend on
//! it and not on each other.

/// An axis-aligned box, `lo <= hi` on every axis: 6 floats, the C API's box layout.
///
/// ```
/// let b = minkq::Aabb::new([0.0, 0.0, 0.0], [1.0, 2.0, 3.0]);
/// assert_eq!(b.hi[2], 3.0);
/// assert_eq!(std::mem::size_of::<minkq::Aabb>(), 24);
/// ```
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Aabb {
    /// The low corner.
    pub lo: [f32; 3],
    /// The high corner.
    pub hi: [f32; 3],
}

impl Aabb {
    /// The box from `lo` to `hi`.
    ///
    /// ```
    /// let b = minkq::Aabb::new([0.0; 3], [1.0; 3]);
    /// assert_eq!(b.lo, [0.0; 3]);
    /// ```
    pub fn new(lo: [f32; 3], hi: [f32; 3]) -> Aabb {
        Aabb { lo, hi }
    }
}
