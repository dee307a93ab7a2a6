//! minkq._native: the pyo3 extension under the `minkq` Python package. It takes arrays through
//! the buffer protocol (numpy; no copy) or as raw descriptors `(address, byte_stride, count,
//! device)` that the package built from `__dlpack__` / `__cuda_array_interface__` (host or
//! CUDA device memory, read in place). The package has already checked dtype, shape, strides,
//! memory kind and device, says which argument is wrong, and keeps the arrays alive for the
//! call. The extension releases the GIL around every build, refit, rebuild and query (and the
//! tree growth, which waits for the object's lock and, on CUDA, the device), and raises the
//! package's exceptions (minkq._errors) named after the C error codes.
//!
//! Every object holds its minkq handle in a Mutex: the C API lets one thread at a time use an
//! object, so Python threads sharing one Scene wait for each other instead of racing.
use std::mem;
use std::slice;
use std::sync::{Mutex, MutexGuard};

use std::ffi::c_void;

use minkq::{
    Buffer, Bvh, BvhBufferQuery, CountOut, Device, Memory, Mode, PairsOut, Query, QueryFlags, QueryKind, Reserve,
    Scene, SceneBuffers, SceneFlags, Stream,
};
use pyo3::buffer::{Element, PyBuffer};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

/// The package exception for a minkq error (minkq._errors._from_status builds it).
fn to_py_err(py: Python<'_>, err: minkq::Error) -> PyErr {
    let needed = match &err {
        minkq::Error::Capacity { needed, .. } => Some(*needed),
        _ => None,
    };
    let made = py
        .import("minkq._errors")
        .and_then(|m| m.getattr("_from_status"))
        .and_then(|f| f.call1((err.status(), err.message(), needed)));
    match made {
        Ok(exception) => PyErr::from_value(exception),
        Err(import_failed) => import_failed,
    }
}

fn lock<T>(mutex: &Mutex<T>) -> MutexGuard<'_, T> {
    // A panic while locked cannot leave a minkq object half-changed (the C API keeps its state
    // on error), so a poisoned lock is still usable.
    mutex.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// A buffer viewed as rows of `R` (each `per_row` items of `T`, with trailing dimensions
/// `trailing`): a C-contiguous array of shape (n, *trailing).
struct Rows<T: Element> {
    buffer: PyBuffer<T>,
    rows: usize,
}

impl<T: Element> Rows<T> {
    fn get(obj: &PyAny, name: &str, trailing: &[usize], writable: bool) -> PyResult<Rows<T>> {
        let buffer = PyBuffer::<T>::get(obj).map_err(|e| {
            PyTypeError::new_err(format!("{name}: expected a {} array: {e}", std::any::type_name::<T>()))
        })?;
        let shape = buffer.shape();
        if shape.len() != trailing.len() + 1 || shape[1..] != *trailing {
            let wanted: Vec<String> = trailing.iter().map(|d| d.to_string()).collect();
            return Err(PyValueError::new_err(format!(
                "{name}: expected shape (n, {}), got {shape:?}",
                wanted.join(", ")
            )));
        }
        if !buffer.is_c_contiguous() {
            return Err(PyValueError::new_err(format!("{name}: expected a C-contiguous array")));
        }
        if writable && buffer.readonly() {
            return Err(PyValueError::new_err(format!("{name}: the array is read-only")));
        }
        // pyo3 0.17's element check takes a byte-swapped buffer ('>' on a little-endian host) for
        // a native one: refuse one here rather than read its values swapped.
        let order = buffer.format().to_bytes().first().copied();
        let swapped =
            if cfg!(target_endian = "little") { matches!(order, Some(b'>') | Some(b'!')) } else { order == Some(b'<') };
        if swapped {
            return Err(PyTypeError::new_err(format!(
                "{name}: expected native byte order, got buffer format {:?}",
                buffer.format()
            )));
        }
        let rows = shape[0];
        Ok(Rows { buffer, rows })
    }

    /// The rows as a mutable slice of `R`, which must be `trailing`'s product of `T`s.
    ///
    /// # Safety
    /// `R` is a plain array of that many `T`s, the buffer is writable (checked in `get`) and not otherwise
    /// borrowed while the slice lives.
    unsafe fn as_mut_slice<R>(&mut self) -> &mut [R] {
        if self.rows == 0 {
            &mut []
        } else {
            slice::from_raw_parts_mut(self.buffer.buf_ptr() as *mut R, self.rows)
        }
    }
}

/// An array argument: a buffer-protocol array (numpy), or a raw descriptor `(address,
/// byte_stride, count, device)` built by the package (minkq._interop) for DLPack and CUDA
/// array interface objects, which it keeps alive during the call.
enum Array<T: Element> {
    Host { rows: Rows<T>, row_bytes: usize },
    Raw { address: usize, byte_stride: usize, count: usize, memory: Memory },
}

impl<T: Element> Array<T> {
    fn get(obj: &PyAny, name: &str, trailing: &[usize], writable: bool) -> PyResult<Array<T>> {
        if let Ok(tuple) = obj.downcast::<PyTuple>() {
            let (address, byte_stride, count, device): (usize, usize, usize, bool) = tuple.extract().map_err(|e| {
                PyTypeError::new_err(format!(
                    "{name}: expected a raw descriptor (address, byte_stride, count, device): {e}"
                ))
            })?;
            let memory = if device { Memory::Device } else { Memory::Host };
            return Ok(Array::Raw { address, byte_stride, count, memory });
        }
        let rows = Rows::get(obj, name, trailing, writable)?;
        let row_bytes = trailing.iter().product::<usize>() * mem::size_of::<T>();
        Ok(Array::Host { rows, row_bytes })
    }

    /// The records as a minkq buffer.
    ///
    /// # Safety
    /// A raw descriptor describes memory that stays readable while the buffer is used (the
    /// package's promise).
    unsafe fn buffer(&self) -> Buffer<'_> {
        match self {
            Array::Host { rows, row_bytes } => {
                Buffer::from_raw_parts(rows.buffer.buf_ptr() as *const _, *row_bytes, rows.rows, Memory::Host)
            }
            Array::Raw { address, byte_stride, count, memory } => {
                Buffer::from_raw_parts(*address as *const _, *byte_stride, *count, *memory)
            }
        }
    }

    /// The rows as a pair output (rows of 2 int32, packed).
    ///
    /// # Safety
    /// As `buffer`, writable, packed, and not otherwise used during the call.
    unsafe fn pairs_out(&mut self) -> PairsOut<'_> {
        match self {
            Array::Host { rows, .. } => {
                PairsOut::from_raw_parts(rows.buffer.buf_ptr() as *mut i32, rows.rows, Memory::Host)
            }
            Array::Raw { address, count, memory, .. } => {
                PairsOut::from_raw_parts(*address as *mut i32, *count, *memory)
            }
        }
    }
}

impl Array<u64> {
    /// The one-element array as a count output.
    ///
    /// # Safety
    /// As `pairs_out`, for one u64.
    unsafe fn count_out(&mut self) -> CountOut<'_> {
        match self {
            Array::Host { rows, .. } => CountOut::from_raw_parts(rows.buffer.buf_ptr() as *mut u64, Memory::Host),
            Array::Raw { address, memory, .. } => CountOut::from_raw_parts(*address as *mut u64, *memory),
        }
    }

    /// A writable one-element uint64 array (numpy, or a raw descriptor of one).
    fn count(obj: &PyAny, name: &str) -> PyResult<Array<u64>> {
        let array = Array::<u64>::get(obj, name, &[], true)?;
        let rows = match &array {
            Array::Host { rows, .. } => rows.rows,
            Array::Raw { count, .. } => *count,
        };
        if rows != 1 {
            return Err(PyValueError::new_err(format!("{name}: expected shape (1,), got {rows} elements")));
        }
        Ok(array)
    }
}

/// A scene's vertex rows: 3 floats each, or 3 doubles each in a float64 scene
/// (MINKQ_SCENE_FLOAT64, whose every vertex buffer the library reads as doubles).
enum Vertices {
    Float32(Array<f32>),
    Float64(Array<f64>),
}

impl Vertices {
    fn get(obj: &PyAny, name: &str, float64: bool) -> PyResult<Vertices> {
        Ok(if float64 {
            Vertices::Float64(Array::get(obj, name, &[3], false)?)
        } else {
            Vertices::Float32(Array::get(obj, name, &[3], false)?)
        })
    }

    /// The rows as a minkq buffer (record stride 12 or 24 bytes for numpy rows).
    ///
    /// # Safety
    /// As `Array::buffer`.
    unsafe fn buffer(&self) -> Buffer<'_> {
        match self {
            Vertices::Float32(array) => array.buffer(),
            Vertices::Float64(array) => array.buffer(),
        }
    }
}

/// The stream an asynchronous call is enqueued on, from its address (a cudaStream_t; 0: CUDA's
/// default stream; ignored on the CPU).
fn stream(address: usize) -> Stream {
    // SAFETY: the package passes the stream of the arrays' library or the caller's own, alive
    // while the work runs (the caller's promise, as for the arrays); a CPU device ignores it.
    unsafe { Stream::from_raw(address as *mut c_void) }
}

fn parse_kind(kind: &str) -> PyResult<QueryKind> {
    kind.parse().map_err(|_| PyValueError::new_err(format!("kind: expected 'vt', 'ee', 'vv' or 'ev', got {kind:?}")))
}

fn parse_mode(mode: &str) -> PyResult<Mode> {
    mode.parse().map_err(|_| {
        PyValueError::new_err(format!("mode: expected 'box', 'sphere', 'capsule_ray' or 'capsule_exact', got {mode:?}"))
    })
}

fn query_flags(leaf_exact: bool, canonical: bool, digest: bool) -> QueryFlags {
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
struct PyDevice {
    inner: Mutex<Device>,
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
        let backend = match device.backend() {
            minkq::Backend::Cpu => "cpu",
            minkq::Backend::Cuda => "cuda",
        };
        Ok(PyDevice { inner: Mutex::new(device), name, backend })
    }
}

/// A mesh scene: VT and EE queries over triangles, VV and EV over vertices and edges (which
/// need no triangles); float32 vertices, or float64 ones with `float64`.
#[pyclass(module = "minkq._native", name = "Scene")]
struct PyScene {
    inner: Mutex<Scene>,
    #[pyo3(get)]
    vertex_count: usize,
    #[pyo3(get)]
    triangle_count: usize,
    #[pyo3(get)]
    edge_count: usize,
    /// Whether the scene reads its vertices as doubles (MINKQ_SCENE_FLOAT64).
    #[pyo3(get)]
    float64: bool,
}

#[pymethods]
impl PyScene {
    #[new]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        device: PyRef<'_, PyDevice>,
        vertices: &PyAny,
        triangles: &PyAny,
        edges: Option<&PyAny>,
        vt: bool,
        ee: bool,
        vv: bool,
        ev: bool,
        drop_incident: bool,
        float64: bool,
    ) -> PyResult<Self> {
        let vertices = Vertices::get(vertices, "vertices", float64)?;
        let triangles = Array::<i32>::get(triangles, "triangles", &[3], false)?;
        let edges = edges.map(|e| Array::<i32>::get(e, "edges", &[2], false)).transpose()?;
        let mut flags = SceneFlags::empty();
        for (wanted, flag) in [
            (vt, SceneFlags::VT),
            (ee, SceneFlags::EE),
            (vv, SceneFlags::VV),
            (ev, SceneFlags::EV),
            (drop_incident, SceneFlags::DROP_INCIDENT),
            (float64, SceneFlags::FLOAT64),
        ] {
            if wanted {
                flags |= flag;
            }
        }
        // SAFETY: shapes checked: rows of 3 floats (doubles with FLOAT64), 3 and 2 int32; the
        // arrays live in this frame.
        let desc = unsafe {
            SceneBuffers {
                vertices: vertices.buffer(),
                triangles: triangles.buffer(),
                edges: edges.as_ref().map_or(Buffer::empty(), |e| e.buffer()),
                flags,
            }
        };
        let device = &device.inner;
        let scene = py.allow_threads(|| Scene::from_buffers(&lock(device), &desc)).map_err(|e| to_py_err(py, e))?;
        Ok(PyScene {
            vertex_count: scene.vertex_count(),
            triangle_count: scene.triangle_count(),
            edge_count: scene.edge_count(),
            float64,
            inner: Mutex::new(scene),
        })
    }

    fn refit(&self, py: Python<'_>, vertices: &PyAny) -> PyResult<()> {
        let vertices = Vertices::get(vertices, "vertices", self.float64)?;
        // SAFETY: rows of 3 floats (doubles in a float64 scene), alive in this frame.
        let vertices = unsafe { vertices.buffer() };
        let scene = &self.inner;
        py.allow_threads(|| lock(scene).refit_buffer(vertices)).map_err(|e| to_py_err(py, e))
    }

    fn rebuild(&self, py: Python<'_>, vertices: &PyAny) -> PyResult<()> {
        let vertices = Vertices::get(vertices, "vertices", self.float64)?;
        // SAFETY: rows of 3 floats (doubles in a float64 scene), alive in this frame.
        let vertices = unsafe { vertices.buffer() };
        let scene = &self.inner;
        py.allow_threads(|| lock(scene).rebuild_buffer(vertices)).map_err(|e| to_py_err(py, e))
    }

    /// Swept positions x0 -> x1, the trees refitted to the swept boxes (minkq_scene_refit_swept).
    fn refit_swept(&self, py: Python<'_>, x0: &PyAny, x1: &PyAny) -> PyResult<()> {
        self.sweep(py, x0, x1, |scene, x0, x1| scene.refit_swept_buffers(x0, x1))
    }

    /// Swept positions x0 -> x1, the trees built afresh (minkq_scene_rebuild_swept).
    fn rebuild_swept(&self, py: Python<'_>, x0: &PyAny, x1: &PyAny) -> PyResult<()> {
        self.sweep(py, x0, x1, |scene, x0, x1| scene.rebuild_swept_buffers(x0, x1))
    }

    /// Whether the scene's positions are swept ones (minkq_scene_is_swept).
    fn is_swept(&self, py: Python<'_>) -> bool {
        let scene = &self.inner;
        // Without the GIL: the lock may wait for a call running on another thread.
        py.allow_threads(|| lock(scene).is_swept())
    }

    /// The trees' area cost now over its value at the last build (minkq_scene_tree_growth).
    fn tree_growth(&self, py: Python<'_>) -> PyResult<f64> {
        let scene = &self.inner;
        py.allow_threads(|| lock(scene).tree_growth()).map_err(|e| to_py_err(py, e))
    }

    /// Writes the edges into `out`, an (edge_count, 2) int32 array.
    fn edges_into(&self, py: Python<'_>, out: &PyAny) -> PyResult<()> {
        let mut out = Rows::<i32>::get(out, "out", &[2], true)?;
        let scene = &self.inner;
        // Without the GIL: the lock may wait for a query running on another thread.
        let edges = py.allow_threads(|| lock(scene).edges()).map_err(|e| to_py_err(py, e))?;
        if edges.len() != out.rows {
            return Err(PyValueError::new_err(format!("out: expected {} rows, got {}", edges.len(), out.rows)));
        }
        // SAFETY: rows of 2 int32, writable.
        unsafe { out.as_mut_slice::<[i32; 2]>() }.copy_from_slice(&edges);
        Ok(())
    }

    /// Runs a query into `out`, a writable (capacity, 2) int32 array; returns (count, digest).
    #[allow(clippy::too_many_arguments)]
    fn query_into(
        &self,
        py: Python<'_>,
        out: &PyAny,
        kind: &str,
        mode: &str,
        radius: f32,
        leaf_exact: bool,
        canonical: bool,
        digest: bool,
    ) -> PyResult<(u64, Option<u64>)> {
        let query = Query::new(parse_kind(kind)?, parse_mode(mode)?, radius)
            .with_flags(query_flags(leaf_exact, canonical, digest));
        let mut out = Array::<i32>::get(out, "out", &[2], true)?;
        // SAFETY: rows of 2 int32, writable, packed, used only here.
        let pairs = unsafe { out.pairs_out() };
        let scene = &self.inner;
        let info = py.allow_threads(|| lock(scene).query_to(&query, pairs)).map_err(|e| to_py_err(py, e))?;
        Ok((info.count, info.digest))
    }

    /// Runs a VT and an EE query in one pass into `vt_out` and `ee_out` (writable (capacity, 2)
    /// int32 arrays in the same memory); returns ((count, digest), (count, digest)).
    #[allow(clippy::too_many_arguments)]
    fn query_vt_ee_into(
        &self,
        py: Python<'_>,
        vt_out: &PyAny,
        ee_out: &PyAny,
        vt_mode: &str,
        ee_mode: &str,
        radius: f32,
        leaf_exact: bool,
        canonical: bool,
        digest: bool,
    ) -> PyResult<((u64, Option<u64>), (u64, Option<u64>))> {
        let flags = query_flags(leaf_exact, canonical, digest);
        let vt = Query::new(QueryKind::Vt, parse_mode(vt_mode)?, radius).with_flags(flags);
        let ee = Query::new(QueryKind::Ee, parse_mode(ee_mode)?, radius).with_flags(flags);
        let mut vt_out = Array::<i32>::get(vt_out, "vt_out", &[2], true)?;
        let mut ee_out = Array::<i32>::get(ee_out, "ee_out", &[2], true)?;
        // SAFETY: rows of 2 int32, writable, packed, used only here (two distinct arrays: the
        // caller allocates each).
        let (vt_pairs, ee_pairs) = unsafe { (vt_out.pairs_out(), ee_out.pairs_out()) };
        let scene = &self.inner;
        let (vt_info, ee_info) = py
            .allow_threads(|| lock(scene).query_vt_ee_to(&vt, &ee, vt_pairs, ee_pairs))
            .map_err(|e| to_py_err(py, e))?;
        Ok(((vt_info.count, vt_info.digest), (ee_info.count, ee_info.digest)))
    }

    /// Reserves the scratch of the asynchronous calls (minkq_scene_reserve).
    fn reserve(
        &self,
        py: Python<'_>,
        refit: bool,
        rebuild: bool,
        swept: bool,
        canonical_capacity: usize,
    ) -> PyResult<()> {
        let mut flags = Reserve::empty();
        if refit {
            flags |= Reserve::REFIT;
        }
        if rebuild {
            flags |= Reserve::REBUILD;
        }
        if swept {
            flags |= Reserve::SWEPT;
        }
        let scene = &self.inner;
        py.allow_threads(|| lock(scene).reserve(flags, canonical_capacity)).map_err(|e| to_py_err(py, e))
    }

    /// minkq_scene_refit_async on the stream at `stream_address`.
    fn refit_async(&self, py: Python<'_>, vertices: &PyAny, stream_address: usize) -> PyResult<()> {
        let vertices = Vertices::get(vertices, "vertices", self.float64)?;
        // SAFETY: rows of 3 floats (doubles in a float64 scene), alive in this frame (on CUDA,
        // the caller keeps them alive until the enqueued work has run).
        let vertices = unsafe { vertices.buffer() };
        let scene = &self.inner;
        py.allow_threads(|| lock(scene).refit_async(vertices, stream(stream_address))).map_err(|e| to_py_err(py, e))
    }

    /// minkq_scene_rebuild_async on the stream at `stream_address`.
    fn rebuild_async(&self, py: Python<'_>, vertices: &PyAny, stream_address: usize) -> PyResult<()> {
        let vertices = Vertices::get(vertices, "vertices", self.float64)?;
        // SAFETY: as in refit_async.
        let vertices = unsafe { vertices.buffer() };
        let scene = &self.inner;
        py.allow_threads(|| lock(scene).rebuild_async(vertices, stream(stream_address))).map_err(|e| to_py_err(py, e))
    }

    /// minkq_scene_refit_swept_async on the stream at `stream_address`.
    fn refit_swept_async(&self, py: Python<'_>, x0: &PyAny, x1: &PyAny, stream_address: usize) -> PyResult<()> {
        self.sweep(py, x0, x1, |scene, x0, x1| scene.refit_swept_async(x0, x1, stream(stream_address)))
    }

    /// minkq_scene_rebuild_swept_async on the stream at `stream_address`.
    fn rebuild_swept_async(&self, py: Python<'_>, x0: &PyAny, x1: &PyAny, stream_address: usize) -> PyResult<()> {
        self.sweep(py, x0, x1, |scene, x0, x1| scene.rebuild_swept_async(x0, x1, stream(stream_address)))
    }

    /// minkq_scene_query_async into `out` ((capacity, 2) int32) and `count` ((1,) uint64).
    #[allow(clippy::too_many_arguments)]
    fn query_async(
        &self,
        py: Python<'_>,
        out: &PyAny,
        count: &PyAny,
        kind: &str,
        mode: &str,
        radius: f32,
        leaf_exact: bool,
        canonical: bool,
        stream_address: usize,
    ) -> PyResult<()> {
        let query = Query::new(parse_kind(kind)?, parse_mode(mode)?, radius)
            .with_flags(query_flags(leaf_exact, canonical, false));
        let mut out = Array::<i32>::get(out, "out_pairs", &[2], true)?;
        let mut count = Array::count(count, "out_count")?;
        // SAFETY: rows of 2 int32 and one u64, writable, packed, used only by this query (on
        // CUDA, kept alive by the caller until the enqueued work has run).
        let (pairs, count) = unsafe { (out.pairs_out(), count.count_out()) };
        let scene = &self.inner;
        py.allow_threads(|| lock(scene).query_async(&query, pairs, count, stream(stream_address)))
            .map_err(|e| to_py_err(py, e))
    }

    /// minkq_scene_query_vt_ee_async into two (capacity, 2) int32 arrays and two (1,) uint64
    /// counts.
    #[allow(clippy::too_many_arguments)]
    fn query_vt_ee_async(
        &self,
        py: Python<'_>,
        vt_out: &PyAny,
        vt_count: &PyAny,
        ee_out: &PyAny,
        ee_count: &PyAny,
        vt_mode: &str,
        ee_mode: &str,
        radius: f32,
        leaf_exact: bool,
        canonical: bool,
        stream_address: usize,
    ) -> PyResult<()> {
        let flags = query_flags(leaf_exact, canonical, false);
        let vt = Query::new(QueryKind::Vt, parse_mode(vt_mode)?, radius).with_flags(flags);
        let ee = Query::new(QueryKind::Ee, parse_mode(ee_mode)?, radius).with_flags(flags);
        let mut vt_out = Array::<i32>::get(vt_out, "vt_pairs", &[2], true)?;
        let mut vt_count = Array::count(vt_count, "vt_count")?;
        let mut ee_out = Array::<i32>::get(ee_out, "ee_pairs", &[2], true)?;
        let mut ee_count = Array::count(ee_count, "ee_count")?;
        // SAFETY: as in query_async (the library refuses one count for both queries).
        let outs = unsafe { (vt_out.pairs_out(), vt_count.count_out(), ee_out.pairs_out(), ee_count.count_out()) };
        let scene = &self.inner;
        py.allow_threads(|| {
            let (vt_pairs, vt_count, ee_pairs, ee_count) = outs;
            lock(scene).query_vt_ee_async(&vt, &ee, vt_pairs, vt_count, ee_pairs, ee_count, stream(stream_address))
        })
        .map_err(|e| to_py_err(py, e))
    }

    /// minkq_scene_async_status: waits for the stream, raises the pending error and clears it.
    fn async_status(&self, py: Python<'_>, stream_address: usize) -> PyResult<()> {
        let scene = &self.inner;
        py.allow_threads(|| lock(scene).async_status(stream(stream_address))).map_err(|e| to_py_err(py, e))
    }

    /// Runs a query with MINKQ_QUERY_STATS (pairs discarded); returns (nodes_visited,
    /// node_tests, primitive_tests, candidates).
    fn work(
        &self,
        py: Python<'_>,
        kind: &str,
        mode: &str,
        radius: f32,
        leaf_exact: bool,
    ) -> PyResult<(u64, u64, u64, u64)> {
        let query = Query::new(parse_kind(kind)?, parse_mode(mode)?, radius)
            .with_flags(query_flags(leaf_exact, false, false) | QueryFlags::STATS);
        let scene = &self.inner;
        let w = py.allow_threads(|| lock(scene).work(&query)).map_err(|e| to_py_err(py, e))?;
        Ok((w.nodes_visited, w.node_tests, w.primitive_tests, w.candidates))
    }
}

impl PyScene {
    /// Runs `call` on the scene, without the GIL, with the swept positions `x0` and `x1` as
    /// buffers of the scene's precision: the one path of the blocking and stream-ordered swept
    /// calls.
    fn sweep<F>(&self, py: Python<'_>, x0: &PyAny, x1: &PyAny, call: F) -> PyResult<()>
    where
        F: for<'a> FnOnce(&mut Scene, Buffer<'a>, Buffer<'a>) -> minkq::Result<()> + Send,
    {
        let x0 = Vertices::get(x0, "x0", self.float64)?;
        let x1 = Vertices::get(x1, "x1", self.float64)?;
        // SAFETY: rows of 3 floats (doubles in a float64 scene), alive in this frame (on CUDA,
        // for the stream-ordered calls, the caller keeps them alive until the enqueued work has
        // run).
        let (x0, x1) = unsafe { (x0.buffer(), x1.buffer()) };
        let scene = &self.inner;
        py.allow_threads(|| call(&mut lock(scene), x0, x1)).map_err(|e| to_py_err(py, e))
    }
}

/// A BVH over user boxes: sphere, capsule and box queries.
#[pyclass(module = "minkq._native", name = "Bvh")]
struct PyBvh {
    inner: Mutex<Bvh>,
    #[pyo3(get)]
    box_count: usize,
}

#[pymethods]
impl PyBvh {
    #[new]
    fn new(py: Python<'_>, device: PyRef<'_, PyDevice>, boxes: &PyAny) -> PyResult<Self> {
        let boxes = Array::<f32>::get(boxes, "boxes", &[2, 3], false)?;
        // SAFETY: rows of 6 floats (lo, hi), alive in this frame.
        let boxes = unsafe { boxes.buffer() };
        let device = &device.inner;
        let bvh = py.allow_threads(|| Bvh::from_buffer(&lock(device), boxes)).map_err(|e| to_py_err(py, e))?;
        Ok(PyBvh { box_count: bvh.len(), inner: Mutex::new(bvh) })
    }

    fn refit(&self, py: Python<'_>, boxes: &PyAny) -> PyResult<()> {
        let boxes = Array::<f32>::get(boxes, "boxes", &[2, 3], false)?;
        // SAFETY: as in new.
        let boxes = unsafe { boxes.buffer() };
        let bvh = &self.inner;
        py.allow_threads(|| lock(bvh).refit_buffer(boxes)).map_err(|e| to_py_err(py, e))
    }

    fn rebuild(&self, py: Python<'_>, boxes: &PyAny) -> PyResult<()> {
        let boxes = Array::<f32>::get(boxes, "boxes", &[2, 3], false)?;
        // SAFETY: as in new.
        let boxes = unsafe { boxes.buffer() };
        let bvh = &self.inner;
        py.allow_threads(|| lock(bvh).rebuild_buffer(boxes)).map_err(|e| to_py_err(py, e))
    }

    /// The tree's area cost now over its value at the last build (minkq_bvh_tree_growth).
    fn tree_growth(&self, py: Python<'_>) -> PyResult<f64> {
        let bvh = &self.inner;
        py.allow_threads(|| lock(bvh).tree_growth()).map_err(|e| to_py_err(py, e))
    }

    /// Runs sphere ("sphere": centres (n, 3)), capsule ("capsule": segments (n, 2, 3)) or box
    /// ("box": boxes (n, 2, 3)) queries into `out`; returns (count, digest).
    #[allow(clippy::too_many_arguments)]
    fn query_into(
        &self,
        py: Python<'_>,
        out: &PyAny,
        shape: &str,
        queries: &PyAny,
        mode: &str,
        radius: f32,
        canonical: bool,
        digest: bool,
    ) -> PyResult<(u64, Option<u64>)> {
        let mode = parse_mode(mode)?;
        let flags = query_flags(false, canonical, digest);
        let mut out = Array::<i32>::get(out, "out", &[2], true)?;
        let (name, trailing): (_, &[usize]) = match shape {
            "sphere" => ("centres", &[3]),
            "capsule" => ("segments", &[2, 3]),
            "box" => ("boxes", &[2, 3]),
            _ => {
                return Err(PyValueError::new_err(format!(
                    "shape: expected 'sphere', 'capsule' or 'box', got {shape:?}"
                )))
            }
        };
        let rows = Array::<f32>::get(queries, name, trailing, false)?;
        // SAFETY: the shapes checked above; segments and boxes hold their second point 12
        // bytes into each record; `out` is writable and packed.
        let (query, pairs) = unsafe {
            let first = rows.buffer();
            let query = match shape {
                "sphere" => BvhBufferQuery::spheres(first, mode, radius),
                "capsule" => BvhBufferQuery::capsules(first, first.offset(12), mode, radius),
                _ => BvhBufferQuery { radius, mode, ..BvhBufferQuery::boxes(first, first.offset(12)) },
            };
            (query.with_flags(flags), out.pairs_out())
        };
        let bvh = &self.inner;
        let info = py.allow_threads(|| lock(bvh).query_to(&query, pairs)).map_err(|e| to_py_err(py, e))?;
        Ok((info.count, info.digest))
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
fn _native(_py: Python<'_>, m: &PyModule) -> PyResult<()> {
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
