use std::cell::Cell;
use std::ffi::{CStr, CString};
use std::fmt;
use std::marker::PhantomData;
use std::ptr::{self, NonNull};
use std::sync::Arc;

use crate::error::{check, Error, Result};
use crate::sys;

/// Which backend a [`Device`] runs on.
///
/// ```
/// let device = minkq::Device::new("cpu")?;
/// assert_eq!(device.backend(), minkq::Backend::Cpu);
/// # Ok::<(), minkq::Error>(())
/// ```
#[non_exhaustive]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Backend {
    /// All cores, through a thread pool.
    Cpu,
    /// An NVIDIA GPU.
    Cuda,
}

impl Backend {
    /// The backend's name, as a device spec starts: `"cpu"` or `"cuda"`.
    ///
    /// ```
    /// assert_eq!(minkq::Device::cpu()?.backend().name(), "cpu");
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn name(self) -> &'static str {
        match self {
            Backend::Cpu => "cpu",
            Backend::Cuda => "cuda",
        }
    }
}

/// The C device handle, shared by the [`Device`] and every scene and BVH made on it, so that
/// the device is released only after all of them (as the C API requires).
pub(crate) struct DeviceHandle(NonNull<sys::minkq_device>);

// SAFETY: the C API documents that "a device may be shared by scenes used from different
// threads". Through this handle the crate only passes the pointer to scene/BVH creation
// (serialised by `Device: !Sync`, see below) and to minkq_device_release, which runs once, when
// the last `Arc` is dropped and so no other thread holds the handle.
unsafe impl Send for DeviceHandle {}
unsafe impl Sync for DeviceHandle {}

impl DeviceHandle {
    pub(crate) fn as_ptr(&self) -> *mut sys::minkq_device {
        self.0.as_ptr()
    }
}

impl Drop for DeviceHandle {
    fn drop(&mut self) {
        // SAFETY: created by minkq_device_create; every scene and BVH holding a clone of the
        // Arc is gone, so nothing made on the device is left.
        unsafe { sys::minkq_device_release(self.0.as_ptr()) }
    }
}

/// A compute device: the CPU backend (all cores) or a CUDA GPU. Scenes and BVHs are built on a
/// device and keep it alive; it is released (`minkq_device_release`) when the `Device` and all
/// of them are dropped.
///
/// Threads: `Device` is `Send` but not `Sync`. The C API allows one object to be used by one
/// thread at a time, so a `&Device` (which would let two threads create scenes on it at once)
/// must not cross threads; move the `Device`, or wrap it in a `Mutex`, to build from several
/// threads. The scenes and BVHs made on it may go to different threads: the C API documents
/// that a device may be shared by scenes used from different threads.
///
/// ```
/// use minkq::Device;
/// let device = Device::new("auto")?; // CUDA when a GPU is usable, else the CPU
/// println!("running on {}", device.name());
/// # Ok::<(), minkq::Error>(())
/// ```
///
/// ```compile_fail
/// fn shared_between_threads<T: Sync>() {}
/// shared_between_threads::<minkq::Device>(); // Device is not Sync
/// ```
pub struct Device {
    pub(crate) handle: Arc<DeviceHandle>,
    _not_sync: PhantomData<Cell<()>>,
}

impl Device {
    /// Creates a device from `"cpu"`, `"cuda"` (GPU 0), `"cuda:N"` or `"auto"` (CUDA if a GPU
    /// is usable, else the CPU).
    ///
    /// Errors: [`Error::InvalidArgument`] for an unknown spec (or one holding a NUL byte),
    /// [`Error::Unsupported`] for CUDA where minkq was built without it or no such GPU exists.
    ///
    /// ```
    /// use minkq::{Device, Error};
    /// let cpu = Device::new("cpu")?;
    /// if minkq::cuda_device_count() == 0 {
    ///     assert!(matches!(Device::new("cuda"), Err(Error::Unsupported(_))));
    /// }
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn new(spec: &str) -> Result<Device> {
        let spec =
            CString::new(spec).map_err(|_| Error::InvalidArgument(format!("device spec {spec:?} holds a NUL byte")))?;
        let mut raw = ptr::null_mut();
        // SAFETY: a valid C string and out pointer.
        check(unsafe { sys::minkq_device_create(spec.as_ptr(), &mut raw) })?;
        let raw = NonNull::new(raw).ok_or_else(|| Error::Internal("minkq_device_create returned NULL".into()))?;
        Ok(Device { handle: Arc::new(DeviceHandle(raw)), _not_sync: PhantomData })
    }

    /// The CPU device: `Device::new("cpu")`.
    ///
    /// ```
    /// let device = minkq::Device::cpu()?;
    /// assert!(device.name().starts_with("cpu"));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn cpu() -> Result<Device> {
        Device::new("cpu")
    }

    /// CUDA GPU `ordinal` (0 for the first): `Device::new("cuda:N")`. [`Error::Unsupported`]
    /// where minkq was built without CUDA or has no such GPU ([`cuda_device_count`]).
    ///
    /// ```
    /// use minkq::{Device, Error};
    /// let gpus = minkq::cuda_device_count();
    /// if gpus > 0 {
    ///     assert!(Device::cuda(0)?.name().starts_with("cuda:0"));
    /// }
    /// assert!(matches!(Device::cuda(gpus), Err(Error::Unsupported(_)))); // one past the last GPU
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn cuda(ordinal: usize) -> Result<Device> {
        Device::new(&format!("cuda:{ordinal}"))
    }

    /// A description such as `"cpu (8 threads, avx2)"` or `"cuda:0 (NVIDIA H100 80GB HBM3)"`.
    ///
    /// ```
    /// let device = minkq::Device::cpu()?;
    /// assert!(device.name().contains("threads"));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn name(&self) -> &str {
        // SAFETY: the name lives as long as the device, which outlives &self.
        let name = unsafe { CStr::from_ptr(sys::minkq_device_name(self.handle.as_ptr())) };
        name.to_str().unwrap_or("(name not UTF-8)")
    }

    /// The backend this device runs on.
    ///
    /// ```
    /// use minkq::{Backend, Device};
    /// let device = Device::new("auto")?;
    /// let expected = if minkq::cuda_device_count() > 0 { Backend::Cuda } else { Backend::Cpu };
    /// assert_eq!(device.backend(), expected);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn backend(&self) -> Backend {
        // SAFETY: a live device.
        match unsafe { sys::minkq_device_backend(self.handle.as_ptr()) } {
            sys::MINKQ_BACKEND_CUDA => Backend::Cuda,
            _ => Backend::Cpu,
        }
    }
}

impl fmt::Debug for Device {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Device").field("name", &self.name()).field("backend", &self.backend()).finish()
    }
}

/// The number of usable CUDA devices (0 where minkq was built without CUDA or has no GPU).
///
/// ```
/// let gpus = minkq::cuda_device_count();
/// println!("{gpus} CUDA device(s)");
/// ```
pub fn cuda_device_count() -> usize {
    // SAFETY: no arguments.
    let count = unsafe { sys::minkq_cuda_device_count() };
    usize::try_from(count).unwrap_or(0)
}
