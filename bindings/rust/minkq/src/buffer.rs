//! Caller memory described the C API's way (`minkq_buffer`): pointer, byte stride, count and
//! memory kind. Host slices convert safely; raw pointers (CUDA device memory, foreign arrays)
//! need an `unsafe` promise once, at construction, after which every call taking a buffer is
//! safe.
use std::ffi::c_void;
use std::fmt;
use std::marker::PhantomData;
use std::mem;
use std::ptr;

use crate::aabb::Aabb;
use crate::sys;

/// Where a buffer's memory lives (`minkq_memory`).
///
/// ```
/// use minkq::Memory;
/// assert_ne!(Memory::Host, Memory::Device);
/// assert_eq!(Memory::Device.name(), "device");
/// ```
#[non_exhaustive]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Memory {
    /// Ordinary host memory.
    Host,
    /// CUDA device memory of the GPU the object (scene, BVH) lives on. A CPU device refuses
    /// it with [`Error::InvalidArgument`](crate::Error::InvalidArgument) before reading it.
    Device,
}

impl Memory {
    /// `"host"` or `"device"`.
    ///
    /// ```
    /// assert_eq!(minkq::Memory::Host.name(), "host");
    /// ```
    pub fn name(self) -> &'static str {
        match self {
            Memory::Host => "host",
            Memory::Device => "device",
        }
    }

    pub(crate) fn raw(self) -> sys::minkq_memory {
        match self {
            Memory::Host => sys::MINKQ_MEMORY_HOST,
            Memory::Device => sys::MINKQ_MEMORY_DEVICE,
        }
    }
}

pub(crate) mod sealed {
    /// The floating-point type of a buffer's coordinates, where the buffer knows it (a slice's
    /// records of floats or doubles): how a float64 scene tells `[f64; 3]` vertices from
    /// `[f32; 3]` ones, which the C API cannot.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub enum Precision {
        F32,
        F64,
    }

    impl Precision {
        /// The vertex record of this precision, for messages: `"[f32; 3]"` or `"[f64; 3]"`.
        pub fn vertex(self) -> &'static str {
            match self {
                Precision::F32 => "[f32; 3]",
                Precision::F64 => "[f64; 3]",
            }
        }
    }

    pub trait Sealed {
        /// The precision of the record's coordinates; `None` for integer records.
        const PRECISION: Option<Precision>;
    }
}

use sealed::Precision;

/// The plain records a host slice may hold when it becomes a [`Buffer`]: arrays of `f32`,
/// `f64` or `i32` without padding, [`Aabb`], and `f32` (a geometry's thickness per vertex).
/// Sealed: the C API reads these bytes as floats, doubles and ints.
///
/// ```
/// fn record_size<T: minkq::Record>() -> usize { std::mem::size_of::<T>() }
/// assert_eq!(record_size::<[f32; 3]>(), 12);
/// assert_eq!(record_size::<[f64; 3]>(), 24); // vertices of a SceneFlags::FLOAT64 scene
/// assert_eq!(record_size::<minkq::Aabb>(), 24);
/// ```
pub trait Record: sealed::Sealed + Copy {}

/// The vertex records of a [`SceneDesc`](crate::SceneDesc): `[f32; 3]` (a float scene) or
/// `[f64; 3]` (a [`SceneFlags::FLOAT64`](crate::SceneFlags::FLOAT64) scene). Sealed.
///
/// ```
/// fn bytes_per_vertex<V: minkq::Vertex>() -> usize { std::mem::size_of::<V>() }
/// assert_eq!((bytes_per_vertex::<[f32; 3]>(), bytes_per_vertex::<[f64; 3]>()), (12, 24));
/// ```
pub trait Vertex: Record {}

macro_rules! records {
    ($($t:ty => $precision:expr),*) => {$(
        impl sealed::Sealed for $t {
            const PRECISION: Option<Precision> = $precision;
        }
        impl Record for $t {}
    )*};
}
records!(
    [f32; 3] => Some(Precision::F32),
    [f64; 3] => Some(Precision::F64),
    [i32; 3] => None,
    [i32; 2] => None,
    [[f32; 3]; 2] => Some(Precision::F32),
    f32 => Some(Precision::F32),
    Aabb => Some(Precision::F32)
);
impl Vertex for [f32; 3] {}
impl Vertex for [f64; 3] {}

/// A read-only view of caller memory for the duration of a borrow: `count` records, record i
/// at `data + i * byte_stride`, in host or device memory (`minkq_buffer`). What a record is
/// depends on the argument it is passed as (vertices: 3 floats, or 3 doubles for a
/// [`SceneFlags::FLOAT64`](crate::SceneFlags::FLOAT64) scene; triangles: 3 int32; edges:
/// 2 int32; boxes: 6 floats); the library checks the stride against it.
///
/// Host slices convert safely with [`Buffer::from_slice`]; any other memory, in particular
/// CUDA device memory, through the `unsafe` [`Buffer::from_raw_parts`]. Functions taking a
/// `Buffer` are safe: the promise was made when it was built.
///
/// A buffer made from a slice remembers whether its records hold `f32` or `f64` coordinates,
/// so that a scene refuses vertices of the other precision, and a [`Bvh`](crate::Bvh) `f64`
/// ones, with [`Error::InvalidArgument`](crate::Error::InvalidArgument): the C API cannot tell
/// the two apart and would misread the memory. A raw buffer carries no such knowledge: the
/// scene's flag decides how its records are read.
///
/// ```
/// use minkq::{Buffer, Memory};
/// let vertices = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0]];
/// let buffer = Buffer::from_slice(&vertices);
/// assert_eq!((buffer.len(), buffer.byte_stride(), buffer.memory()), (2, 12, Memory::Host));
/// ```
#[derive(Clone, Copy)]
pub struct Buffer<'a> {
    raw: sys::minkq_buffer,
    /// The coordinates' type, known for slices of float and double records.
    precision: Option<Precision>,
    _borrow: PhantomData<&'a [u8]>,
}

// SAFETY: a Buffer is a shared view (like &[T]) of plain records that nobody mutates while it
// lives (the promise of its constructors); reading it from another thread is fine.
unsafe impl Send for Buffer<'_> {}
unsafe impl Sync for Buffer<'_> {}

impl<'a> Buffer<'a> {
    /// A packed host buffer over a slice. A slice of `[f64; 3]` holds the vertices of a
    /// [`SceneFlags::FLOAT64`](crate::SceneFlags::FLOAT64) scene (24-byte records).
    ///
    /// ```
    /// let triangles = [[0, 1, 2], [2, 1, 3]];
    /// let buffer = minkq::Buffer::from_slice(&triangles);
    /// assert_eq!(buffer.len(), 2);
    /// assert_eq!(buffer.data(), triangles.as_ptr().cast());
    /// assert_eq!(minkq::Buffer::from_slice(&[[0.0f64; 3]; 2]).byte_stride(), 24);
    /// ```
    pub fn from_slice<T: Record>(values: &'a [T]) -> Buffer<'a> {
        Buffer {
            raw: sys::minkq_buffer {
                data: if values.is_empty() { ptr::null() } else { values.as_ptr().cast() },
                byte_stride: mem::size_of::<T>(),
                count: values.len(),
                memory: sys::MINKQ_MEMORY_HOST,
            },
            precision: T::PRECISION,
            _borrow: PhantomData,
        }
    }

    /// No records (`data` NULL, count 0): e.g. "derive the edges from the triangles".
    ///
    /// ```
    /// let none = minkq::Buffer::empty();
    /// assert!(none.is_empty() && none.data().is_null());
    /// ```
    pub fn empty() -> Buffer<'static> {
        Buffer {
            raw: sys::minkq_buffer { data: ptr::null(), byte_stride: 0, count: 0, memory: sys::MINKQ_MEMORY_HOST },
            precision: None,
            _borrow: PhantomData,
        }
    }

    /// A buffer over arbitrary memory: `count` records, record i at `data + i * byte_stride`
    /// (`byte_stride` 0: packed), in `memory`.
    ///
    /// This is how CUDA device arrays (a Warp, PyTorch or CuPy array's pointer) reach a scene
    /// on a CUDA device without a copy to the host. The library reads the records on its own
    /// CUDA stream (the per-thread default stream of the calling thread) and synchronises it
    /// before returning: work that produces the data on another stream must be complete, or
    /// ordered before that stream, when the call is made.
    ///
    /// Such a buffer does not know whether its vertices are floats or doubles: a scene reads
    /// them as its [`SceneFlags::FLOAT64`](crate::SceneFlags::FLOAT64) flag says (3 doubles per
    /// record with it, 3 floats without), and the promise below covers that record size.
    ///
    /// # Safety
    /// For the lifetime `'a`: when `count > 0`, the `(count - 1) * byte_stride + record size`
    /// bytes from `data` are readable in `memory` (for [`Memory::Device`]: device memory of
    /// the GPU of every object this buffer is passed to, or host memory the GPU can read), and
    /// nothing writes them while a call reading them runs.
    ///
    /// ```
    /// use minkq::{Buffer, Device, Error, Memory, Scene, SceneBuffers, SceneFlags};
    /// // Vertices with a fourth, ignored float per record (stride 16 bytes), read in place.
    /// let padded = [[0.0f32, 0.0, 0.0, 9.0], [1.0, 0.0, 0.0, 9.0], [0.0, 1.0, 0.0, 9.0]];
    /// // SAFETY: three records of 16 bytes, each starting with 3 floats, borrowed from `padded`.
    /// let vertices = unsafe { Buffer::from_raw_parts(padded.as_ptr().cast(), 16, 3, Memory::Host) };
    /// let triangles = [[0, 1, 2]];
    /// let desc = SceneBuffers::new(vertices, Buffer::from_slice(&triangles));
    /// let scene = Scene::from_buffers(&Device::cpu()?, &desc)?;
    /// assert_eq!(scene.vertex_count(), 3);
    ///
    /// // Device memory on a CPU device is refused before it is read.
    /// // SAFETY: never dereferenced: the CPU device rejects device memory.
    /// let on_gpu = unsafe { Buffer::from_raw_parts(padded.as_ptr().cast(), 16, 3, Memory::Device) };
    /// let err = Scene::from_buffers(&Device::cpu()?, &SceneBuffers::new(on_gpu, Buffer::from_slice(&triangles)));
    /// assert!(matches!(err, Err(Error::InvalidArgument(m)) if m.contains("device memory")));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub unsafe fn from_raw_parts(data: *const c_void, byte_stride: usize, count: usize, memory: Memory) -> Buffer<'a> {
        Buffer {
            raw: sys::minkq_buffer { data, byte_stride, count, memory: memory.raw() },
            precision: None,
            _borrow: PhantomData,
        }
    }

    /// The address of record 0 (NULL for an empty slice).
    ///
    /// ```
    /// assert!(minkq::Buffer::from_slice::<[i32; 2]>(&[]).data().is_null());
    /// ```
    pub fn data(&self) -> *const c_void {
        self.raw.data
    }

    /// Bytes from one record to the next (0: packed).
    ///
    /// ```
    /// assert_eq!(minkq::Buffer::from_slice(&[[0i32; 2]]).byte_stride(), 8);
    /// ```
    pub fn byte_stride(&self) -> usize {
        self.raw.byte_stride
    }

    /// The number of records.
    ///
    /// ```
    /// assert_eq!(minkq::Buffer::from_slice(&[[0.0f32; 3]; 5]).len(), 5);
    /// ```
    pub fn len(&self) -> usize {
        self.raw.count
    }

    /// Whether the buffer holds no record.
    ///
    /// ```
    /// assert!(minkq::Buffer::from_slice::<[f32; 3]>(&[]).is_empty());
    /// ```
    pub fn is_empty(&self) -> bool {
        self.raw.count == 0
    }

    /// Host or device memory.
    ///
    /// ```
    /// assert_eq!(minkq::Buffer::empty().memory(), minkq::Memory::Host);
    /// ```
    pub fn memory(&self) -> Memory {
        if self.raw.memory == sys::MINKQ_MEMORY_DEVICE {
            Memory::Device
        } else {
            Memory::Host
        }
    }

    /// A buffer over the same memory starting `byte_offset` bytes later: e.g. the second
    /// corner of each box of a (lo, hi) array.
    ///
    /// # Safety
    /// The resulting buffer must satisfy [`Buffer::from_raw_parts`]'s contract: every record
    /// lies inside the memory this buffer was built over.
    ///
    /// ```
    /// let segments = [[[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0]]];
    /// let starts = minkq::Buffer::from_slice(&segments);
    /// // SAFETY: each 24-byte record holds the end point 12 bytes in.
    /// let ends = unsafe { starts.offset(12) };
    /// assert_eq!(ends.data() as usize - starts.data() as usize, 12);
    /// ```
    pub unsafe fn offset(&self, byte_offset: usize) -> Buffer<'a> {
        let data = if self.raw.data.is_null() {
            self.raw.data
        } else {
            self.raw.data.cast::<u8>().wrapping_add(byte_offset).cast()
        };
        Buffer { raw: sys::minkq_buffer { data, ..self.raw }, ..*self }
    }

    pub(crate) fn raw(&self) -> sys::minkq_buffer {
        self.raw
    }

    /// The coordinates' type, where the buffer knows it (a slice of float or double records).
    pub(crate) fn precision(&self) -> Option<Precision> {
        self.precision
    }

    /// The C buffer for a reader of `wanted` precision, or `Err` with the buffer's precision
    /// when it is a slice of records of the other one (raw buffers pass: the reader decides).
    pub(crate) fn raw_at(&self, wanted: Precision) -> std::result::Result<sys::minkq_buffer, Precision> {
        match self.precision {
            Some(precision) if precision != wanted => Err(precision),
            _ => Ok(self.raw),
        }
    }
}

impl<'a, T: Record> From<&'a [T]> for Buffer<'a> {
    fn from(values: &'a [T]) -> Buffer<'a> {
        Buffer::from_slice(values)
    }
}

impl fmt::Debug for Buffer<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Buffer")
            .field("data", &self.raw.data)
            .field("byte_stride", &self.raw.byte_stride)
            .field("count", &self.raw.count)
            .field("memory", &self.memory())
            .finish()
    }
}

/// Where a query writes its pairs: room for `capacity` pairs (2 int32 each, packed) in host
/// or device memory, borrowed mutably for `'a`.
///
/// ```
/// use minkq::{Memory, PairsOut};
/// let mut pairs = [[0i32; 2]; 8];
/// let out = PairsOut::from_slice(&mut pairs);
/// assert_eq!((out.capacity(), out.memory()), (8, Memory::Host));
/// ```
pub struct PairsOut<'a> {
    data: *mut i32,
    capacity: usize,
    memory: Memory,
    _borrow: PhantomData<&'a mut [[i32; 2]]>,
}

// SAFETY: an exclusive borrow of plain ints (like &mut [[i32; 2]]).
unsafe impl Send for PairsOut<'_> {}

impl<'a> PairsOut<'a> {
    /// Pairs into a host slice.
    ///
    /// ```
    /// let mut pairs = vec![[0i32; 2]; 3];
    /// assert_eq!(minkq::PairsOut::from_slice(&mut pairs).capacity(), 3);
    /// ```
    pub fn from_slice(out: &'a mut [[i32; 2]]) -> PairsOut<'a> {
        PairsOut { data: out.as_mut_ptr().cast(), capacity: out.len(), memory: Memory::Host, _borrow: PhantomData }
    }

    /// Pairs into arbitrary memory, e.g. a CUDA device array of shape (capacity, 2) int32.
    /// Queries on a CUDA device write device memory on the device's stream and synchronise it
    /// before returning, so the pairs are ready for any stream when the call returns.
    ///
    /// # Safety
    /// For `'a`: `data` is valid for writing `2 * capacity` int32 in `memory` (device memory
    /// of the GPU of the object queried), 4-byte aligned, and nothing else reads or writes
    /// that memory while a query writes it.
    ///
    /// ```
    /// use minkq::*;
    /// let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]];
    /// let scene = Scene::new(&Device::cpu()?, &SceneDesc::new(&vertices, &[[0, 1, 2], [3, 4, 5]]))?;
    /// let mut storage = vec![0i32; 2 * 16];
    /// // SAFETY: 16 pairs of host memory, borrowed from `storage` for the query.
    /// let out = unsafe { PairsOut::from_raw_parts(storage.as_mut_ptr(), 16, Memory::Host) };
    /// assert_eq!(scene.query_to(&Query::vt(Mode::Sphere, 0.2), out)?.count, 6);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub unsafe fn from_raw_parts(data: *mut i32, capacity: usize, memory: Memory) -> PairsOut<'a> {
        PairsOut { data, capacity, memory, _borrow: PhantomData }
    }

    /// The number of pairs that fit.
    ///
    /// ```
    /// assert_eq!(minkq::PairsOut::from_slice(&mut []).capacity(), 0);
    /// ```
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Host or device memory.
    ///
    /// ```
    /// assert_eq!(minkq::PairsOut::from_slice(&mut [[0; 2]]).memory(), minkq::Memory::Host);
    /// ```
    pub fn memory(&self) -> Memory {
        self.memory
    }

    pub(crate) fn data(&self) -> *mut i32 {
        if self.capacity == 0 {
            ptr::null_mut()
        } else {
            self.data
        }
    }
}

impl<'a> From<&'a mut [[i32; 2]]> for PairsOut<'a> {
    fn from(out: &'a mut [[i32; 2]]) -> PairsOut<'a> {
        PairsOut::from_slice(out)
    }
}

impl fmt::Debug for PairsOut<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("PairsOut").field("capacity", &self.capacity).field("memory", &self.memory).finish()
    }
}
