//! The argument traits of the calls that move a scene or a BVH: [`Vertices`] (what
//! [`Scene::refit`](crate::Scene::refit) and its kin take) and [`Boxes`] (what
//! [`Bvh::refit`](crate::Bvh::refit) takes), so that one method serves host slices of either
//! precision and [`Buffer`]s.
use crate::aabb::Aabb;
use crate::buffer::{Buffer, Vertex};

pub(crate) mod sealed {
    /// Seals [`Vertices`](super::Vertices) and [`Boxes`](super::Boxes): the library reads their
    /// bytes as vertex or box records.
    pub trait Input {}
}

/// Vertex positions as a scene's refits and rebuilds take them: a slice, `Vec` or array of
/// `[f32; 3]` or `[f64; 3]` (the latter for a [`SceneFlags::FLOAT64`](crate::SceneFlags::FLOAT64)
/// scene or geometry), or a [`Buffer`] (strided records, host or device memory). Sealed.
///
/// ```
/// use minkq::{Buffer, Device, Scene, SceneDesc};
/// let mut vertices = vec![[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
/// let mut scene = Scene::new(&Device::cpu()?, &SceneDesc::new(&vertices, &[[0, 1, 2]]))?;
/// vertices[2][2] = 0.5;
/// scene.refit(&vertices)?; // &Vec
/// scene.refit(&vertices[..])?; // slice
/// scene.refit(&[[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])?; // array
/// scene.rebuild(Buffer::from_slice(&vertices))?; // buffer
/// # Ok::<(), minkq::Error>(())
/// ```
pub trait Vertices<'a>: sealed::Input {
    /// The positions as a [`Buffer`] (a slice's buffer remembers its precision).
    fn into_buffer(self) -> Buffer<'a>;
}

/// Boxes as a BVH's refits and rebuilds take them: a slice, `Vec` or array of [`Aabb`], or a
/// [`Buffer`] of 6-float records (host or device memory). Sealed.
///
/// ```
/// use minkq::{Aabb, Buffer, Bvh, Device};
/// let boxes = vec![Aabb::new([0.0; 3], [1.0; 3])];
/// let mut bvh = Bvh::new(&Device::cpu()?, &boxes)?;
/// bvh.refit(&boxes)?;
/// bvh.rebuild(Buffer::from_slice(&boxes))?;
/// # Ok::<(), minkq::Error>(())
/// ```
pub trait Boxes<'a>: sealed::Input {
    /// The boxes as a [`Buffer`].
    fn into_buffer(self) -> Buffer<'a>;
}

/// Implements `$trait` for slices, `Vec`s and arrays of the records `$record` names, and for
/// [`Buffer`].
macro_rules! input {
    ($trait:ident, [$($generics:tt)*] $record:ty) => {
        impl<'a, $($generics)*> sealed::Input for &'a [$record] {}
        impl<'a, $($generics)*> $trait<'a> for &'a [$record] {
            fn into_buffer(self) -> Buffer<'a> {
                Buffer::from_slice(self)
            }
        }
        impl<'a, $($generics)*> sealed::Input for &'a Vec<$record> {}
        impl<'a, $($generics)*> $trait<'a> for &'a Vec<$record> {
            fn into_buffer(self) -> Buffer<'a> {
                Buffer::from_slice(self)
            }
        }
        impl<'a, $($generics)* const N: usize> sealed::Input for &'a [$record; N] {}
        impl<'a, $($generics)* const N: usize> $trait<'a> for &'a [$record; N] {
            fn into_buffer(self) -> Buffer<'a> {
                Buffer::from_slice(self)
            }
        }
        impl<'a> $trait<'a> for Buffer<'a> {
            fn into_buffer(self) -> Buffer<'a> {
                self
            }
        }
    };
}
impl sealed::Input for Buffer<'_> {}
input!(Vertices, [V: Vertex,] V);
input!(Boxes, [] Aabb);
