//! minkq._native: the pyo3 extension under the `minkq` Python package. It takes arrays through
//! the buffer protocol (numpy; no copy) or as raw descriptors `(address, byte_stride, count,
//! device)` that the package built from `__dlpack__` / `__cuda_array_interface__` (host or
//! CUDA device memory, read in place). The package has already checked dtype, shape, strides,
//! memory kind and device, says which argument is wrong, and keeps the arrays alive for the
//! call. The extension releases the GIL around every build, refit, rebuild and query (and the
//! tree growth, which waits for the object's lock and, on CUDA, the device), and raises the
//! exceptions named after the C error codes, which it defines (errors.rs; the package
//! re-exports them from minkq._errors).
//!
//! Every object holds its minkq handle in a Mutex: the C API lets one thread at a time use an
//! object, so Python threads sharing one Scene wait for each other instead of racing.
use std::ffi::c_void;
use std::sync::{Mutex, MutexGuard};

use minkq::{Device, Mode, QueryFlags, QueryKind, Stream};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

mod arrays;
mod bvh;
mod errors;
mod geometries;
mod scene;

use bvh::PyBvh;
pub(crate) use errors::to_py_err;
use scene::PyScene;

pub(crate) fn lock<T>(mutex: &Mutex<T>) -> MutexGuard<'_, T> {
    // A panic while locked cannot leave a minkq object half-changed (the C API keeps its state
    // on error), so a poisoned lock is still usable.
    mutex.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// The stream an asynchronous call is enqueued on, from its address (a cudaStream_t; 0: CUDA's
/// default stream; ignored on the CPU).
pub(crate) fn stream(address: usize) -> Stream {
    // SAFETY: the package passes the stream of the arrays' library or the caller's own, alive
    // while the work runs (the caller's promise, as for the arrays); a CPU device ignores it.
    unsafe { Stream::from_raw(address as *mut c_void) }
}

pub(crate) fn parse_kind(kind: &str) -> PyResult<QueryKind> {
    kind.parse().map_err(|_| PyValueError::new_err(format!("kind: expected 'vt', 'ee', 'vv' or 'ev', got {kind:?}")))
}

pub(crate) fn parse_mode(mode: &str) -> PyResult<Mode> {
    mode.parse().map_err(|_| {
        PyValueError::new_err(format!("mode: expected 'box', 'sphere', 'capsule_ray' or 'capsule_exact', got {mode:?}"))
    })
}

pub(crate) fn query_flags(leaf_exact: bool, canonical: bool, digest: bool) -> QueryFlags {
    let mut flags = QueryFlags::empty();
    if leaf_exact {
        flags |= QueryFlags::LEAF_EXACT;
    }
    if canonical {
        flags |= QueryFlags::CANONICAL;
    }
    if digest {
        flags |= QueryFlags::DIGEST;
    }
    flags
}

/// A compute device: "cpu", "cuda", "cuda:N" or "auto".
#[pyclass(module = "minkq._native", name = "Device")]
pub(crate) struct PyDevice {
    pub(crate) inner: Mutex<Device>,
    #[pyo3(get)]
    name: String,
    #[pyo3(get)]
    backend: &'static str,
}

#[pymethods]
impl PyDevice {
    #[new]
    fn new(py: Python<'_>, spec: &str) -> PyResult<Self> {
        let device = Device::new(spec).map_err(|e| to_py_err(py, e))?;
        let name = device.name().to_string();
        let backend = device.backend().name();
        Ok(PyDevice { inner: Mutex::new(device), name, backend })
    }
}

/// Number of usable CUDA devices.
#[pyfunction]
fn cuda_device_count() -> usize {
    minkq::cuda_device_count()
}

/// The library's run-time version (major, minor, patch).
#[pyfunction]
fn version() -> (u32, u32, u32) {
    minkq::version()
}

/// The library's run-time ABI version.
#[pyfunction]
fn abi_version() -> u32 {
    minkq::abi_version()
}

/// Raises the exception minkq raises for a C status (for the tests of the mapping).
#[pyfunction]
#[pyo3(name = "_raise_status")]
fn raise_status(py: Python<'_>, status: u32, message: &str) -> PyResult<()> {
    Err(to_py_err(py, minkq::Error::from_status(status, message)))
}

#[pymodule]
fn _native(py: Python<'_>, m: &PyModule) -> PyResult<()> {
    errors::register(py, m)?;
    m.add_class::<PyDevice>()?;
    m.add_class::<PyScene>()?;
    m.add_class::<PyBvh>()?;
    m.add_function(wrap_pyfunction!(cuda_device_count, m)?)?;
    m.add_function(wrap_pyfunction!(version, m)?)?;
    m.add_function(wrap_pyfunction!(abi_version, m)?)?;
    m.add_function(wrap_pyfunction!(raise_status, m)?)?;
    m.add("ABI_VERSION", minkq::ABI_VERSION)?;
    Ok(())
}
