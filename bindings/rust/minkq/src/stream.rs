//! Stream-ordered calls: the CUDA stream they are enqueued on ([`Stream`]) and the caller
//! memory their exact pair counts are written to ([`CountOut`]).
use std::ffi::c_void;
use std::fmt;
use std::marker::PhantomData;
use std::ptr;

use crate::buffer::Memory;
use crate::sys;

/// A CUDA stream (`cudaStream_t`) for the scene's asynchronous calls
/// ([`Scene::refit_async`](crate::Scene::refit_async) and the others): their work is enqueued
/// on it and ordered on it only. [`Stream::null`] is CUDA's default stream. A CPU device
/// ignores the stream: its asynchronous calls run to completion before returning.
///
/// The stream is not owned: dropping a `Stream` does nothing.
///
/// ```
/// use minkq::Stream;
/// assert!(Stream::null().as_raw().is_null());
/// assert_eq!(Stream::default(), Stream::null());
/// ```
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Stream(sys::minkq_stream);

// SAFETY: a cudaStream_t may be used from any thread; a Stream is only passed to the library.
unsafe impl Send for Stream {}
unsafe impl Sync for Stream {}

impl Stream {
    /// CUDA's default stream (NULL); on a CPU device, what every stream is: ignored.
    ///
    /// ```
    /// assert!(minkq::Stream::null().as_raw().is_null());
    /// ```
    pub const fn null() -> Stream {
        Stream(ptr::null_mut())
    }

    /// A stream from its `cudaStream_t`, e.g. Warp's `wp.get_stream().cuda_stream`, PyTorch's
    /// `torch.cuda.current_stream().cuda_stream` or a stream created with `cudaStreamCreate`
    /// (the special handles `cudaStreamLegacy` (1) and `cudaStreamPerThread` (2) too).
    ///
    /// # Safety
    /// On a CUDA device, `stream` is NULL, a special handle or a live stream of the scene's
    /// GPU, and stays alive until the work enqueued on it has run. A CPU device never uses it.
    ///
    /// ```
    /// // SAFETY: only passed to a CPU device, which ignores it.
    /// let stream = unsafe { minkq::Stream::from_raw(0x2 as *mut std::ffi::c_void) };
    /// assert_eq!(stream.as_raw() as usize, 2);
    /// ```
    pub const unsafe fn from_raw(stream: *mut c_void) -> Stream {
        Stream(stream)
    }

    /// The `cudaStream_t`.
    ///
    /// ```
    /// assert!(minkq::Stream::null().as_raw().is_null());
    /// ```
    pub const fn as_raw(self) -> *mut c_void {
        self.0
    }
}

impl Default for Stream {
    fn default() -> Stream {
        Stream::null()
    }
}

impl fmt::Debug for Stream {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_tuple("Stream").field(&self.0).finish()
    }
}

/// Where an asynchronous query writes its exact pair count: one `u64` in host memory (CPU
/// devices) or device memory (CUDA devices), borrowed mutably for `'a`.
///
/// ```
/// use minkq::{CountOut, Memory};
/// let mut count = 0u64;
/// assert_eq!(CountOut::from_mut(&mut count).memory(), Memory::Host);
/// ```
pub struct CountOut<'a> {
    data: *mut u64,
    memory: Memory,
    _borrow: PhantomData<&'a mut u64>,
}

// SAFETY: an exclusive borrow of one plain integer (like &mut u64).
unsafe impl Send for CountOut<'_> {}

impl<'a> CountOut<'a> {
    /// The count into a host integer.
    ///
    /// ```
    /// let mut count = 7u64;
    /// let out = minkq::CountOut::from_mut(&mut count);
    /// assert!(!out.as_ptr().is_null());
    /// ```
    pub fn from_mut(count: &'a mut u64) -> CountOut<'a> {
        CountOut { data: count, memory: Memory::Host, _borrow: PhantomData }
    }

    /// The count into arbitrary memory, e.g. a one-element `uint64` CUDA array.
    ///
    /// # Safety
    /// `data` is valid for writing one 8-byte aligned `u64` in `memory` (device memory of the
    /// scene's GPU for [`Memory::Device`]) for `'a` and, on a CUDA device, until the work of
    /// the asynchronous query it is passed to has run on its stream; nothing else reads or
    /// writes it meanwhile (other than work ordered after that query).
    ///
    /// ```
    /// use minkq::{CountOut, Memory};
    /// let mut storage = [0u64; 1];
    /// // SAFETY: one u64 of host memory, borrowed from `storage`.
    /// let out = unsafe { CountOut::from_raw_parts(storage.as_mut_ptr(), Memory::Host) };
    /// assert_eq!(out.as_ptr(), storage.as_mut_ptr());
    /// ```
    pub unsafe fn from_raw_parts(data: *mut u64, memory: Memory) -> CountOut<'a> {
        CountOut { data, memory, _borrow: PhantomData }
    }

    /// Host or device memory.
    ///
    /// ```
    /// assert_eq!(minkq::CountOut::from_mut(&mut 0).memory(), minkq::Memory::Host);
    /// ```
    pub fn memory(&self) -> Memory {
        self.memory
    }

    /// The address written.
    ///
    /// ```
    /// let mut count = 0u64;
    /// let address: *mut u64 = &mut count;
    /// assert_eq!(minkq::CountOut::from_mut(&mut count).as_ptr(), address);
    /// ```
    pub fn as_ptr(&self) -> *mut u64 {
        self.data
    }
}

impl<'a> From<&'a mut u64> for CountOut<'a> {
    fn from(count: &'a mut u64) -> CountOut<'a> {
        CountOut::from_mut(count)
    }
}

impl fmt::Debug for CountOut<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("CountOut").field("data", &self.data).field("memory", &self.memory).finish()
    }
}
