//! The Bvh class: a BVH over user boxes and its sphere, capsule and box queries.
use std::sync::Mutex;

use minkq::{Bvh, BvhBufferQuery};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::arrays::Array;
use crate::{lock, parse_mode, query_flags, to_py_err, PyDevice};

/// A BVH over user boxes: sphere, capsule and box queries.
#[pyclass(module = "minkq._native", name = "Bvh")]
pub(crate) struct PyBvh {
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
        py.allow_threads(|| lock(bvh).refit(boxes)).map_err(|e| to_py_err(py, e))
    }

    fn rebuild(&self, py: Python<'_>, boxes: &PyAny) -> PyResult<()> {
        let boxes = Array::<f32>::get(boxes, "boxes", &[2, 3], false)?;
        // SAFETY: as in new.
        let boxes = unsafe { boxes.buffer() };
        let bvh = &self.inner;
        py.allow_threads(|| lock(bvh).rebuild(boxes)).map_err(|e| to_py_err(py, e))
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
        let mut out = Array::<i32>::get(out, "out", &[2], true)?;
        let rows = query_rows(shape, queries)?;
        // SAFETY: the rows' shape was checked for `shape`; `out` is writable and packed.
        let (query, pairs) = unsafe { (bvh_query(&rows, shape, mode, radius)?, out.pairs_out()) };
        let query = query.with_flags(query_flags(false, canonical, digest));
        let bvh = &self.inner;
        let info = py.allow_threads(|| lock(bvh).query_into(query, pairs)).map_err(|e| to_py_err(py, e))?;
        Ok((info.count, info.digest))
    }
    /// The exact number of pairs of sphere, capsule or box queries (as `query_into`), none
    /// written (MINKQ_QUERY_COUNT).
    fn count(&self, py: Python<'_>, shape: &str, queries: &PyAny, mode: &str, radius: f32) -> PyResult<u64> {
        let rows = query_rows(shape, queries)?;
        // SAFETY: the rows' shape was checked for `shape`.
        let query = unsafe { bvh_query(&rows, shape, mode, radius)? };
        let bvh = &self.inner;
        py.allow_threads(|| lock(bvh).count_buffers(&query)).map_err(|e| to_py_err(py, e))
    }
}

/// The query rows of a shape: centres (n, 3) for "sphere", segments or boxes (n, 2, 3).
fn query_rows(shape: &str, queries: &PyAny) -> PyResult<Array<f32>> {
    let (name, trailing): (_, &[usize]) = match shape {
        "sphere" => ("centres", &[3]),
        "capsule" => ("segments", &[2, 3]),
        "box" => ("boxes", &[2, 3]),
        _ => return Err(PyValueError::new_err(format!("shape: expected 'sphere', 'capsule' or 'box', got {shape:?}"))),
    };
    Array::<f32>::get(queries, name, trailing, false)
}

/// The query over `rows` (from query_rows for the same shape): segments and boxes hold their
/// second point 12 bytes into each record.
///
/// # Safety
/// `rows` has the shape query_rows checks for `shape`.
unsafe fn bvh_query<'a>(rows: &'a Array<f32>, shape: &str, mode: &str, radius: f32) -> PyResult<BvhBufferQuery<'a>> {
    let mode = parse_mode(mode)?;
    let first = rows.buffer();
    Ok(match shape {
        "sphere" => BvhBufferQuery::spheres(first, mode, radius),
        "capsule" => BvhBufferQuery::capsules(first, first.offset(12), mode, radius),
        _ => BvhBufferQuery { radius, mode, ..BvhBufferQuery::boxes(first, first.offset(12)) },
    })
}
