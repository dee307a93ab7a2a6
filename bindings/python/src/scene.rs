//! The Scene class: a mesh scene's creation (one mesh, or many geometries), updates (blocking,
//! swept, stream-ordered, of one geometry) and queries.
use std::sync::Mutex;

use minkq::{Buffer, Query, QueryFlags, QueryKind, Reserve, Scene, SceneBuffers, SceneFlags};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::arrays::{Array, Rows, Vertices};
use crate::geometries::{self, parse_element, GeometryArgs};
use crate::{lock, parse_kind, parse_mode, query_flags, stream, to_py_err, PyDevice};

/// A mesh scene: VT and EE queries over triangles, VV and EV over vertices and edges (which
/// need no triangles); float32 vertices, or float64 ones with `float64`. Or a scene of many
/// geometries (`from_geometries`), each of its own precision.
#[pyclass(module = "minkq._native", name = "Scene")]
pub(crate) struct PyScene {
    inner: Mutex<Scene>,
    #[pyo3(get)]
    vertex_count: usize,
    #[pyo3(get)]
    triangle_count: usize,
    #[pyo3(get)]
    edge_count: usize,
    /// Whether the scene reads its vertices as doubles (MINKQ_SCENE_FLOAT64; for a scene of
    /// geometries: whether every moving one is float64, the precision of whole-scene moves).
    #[pyo3(get)]
    float64: bool,
    /// Whether each geometry's vertices are doubles (one geometry for a one-mesh scene).
    geometry_float64: Vec<bool>,
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
        Ok(PyScene::wrap(scene, vec![float64]))
    }

    /// A scene of many geometries (minkq_scene_create_geometries), from the package's checked
    /// descriptions (minkq._geometry._NativeGeometry).
    #[staticmethod]
    fn from_geometries(
        py: Python<'_>,
        device: PyRef<'_, PyDevice>,
        geometries: Vec<GeometryArgs<'_>>,
    ) -> PyResult<Self> {
        let (scene, geometry_float64) = geometries::create(py, &device.inner, &geometries)?;
        Ok(PyScene::wrap(scene, geometry_float64))
    }

    /// The number of geometries (minkq_scene_geometry_count).
    #[getter]
    fn geometry_count(&self) -> usize {
        self.geometry_float64.len()
    }

    /// Geometry `g`'s (first global id, count) of `element` ("vertex", "triangle", "edge").
    fn geometry_range(&self, py: Python<'_>, g: u32, element: &str) -> PyResult<(usize, usize)> {
        let element = parse_element(element)?;
        let scene = &self.inner;
        let range = py.allow_threads(|| lock(scene).geometry_range(g, element)).map_err(|e| to_py_err(py, e))?;
        Ok((range.start, range.len()))
    }

    /// Moves geometry `g` and refits its trees (minkq_scene_geometry_refit).
    fn refit_geometry(&self, py: Python<'_>, g: u32, vertices: &PyAny) -> PyResult<()> {
        let vertices = Vertices::get(vertices, "vertices", self.is_float64(g))?;
        // SAFETY: rows of 3 floats (doubles for a float64 geometry), alive in this frame.
        let vertices = unsafe { vertices.buffer() };
        let scene = &self.inner;
        py.allow_threads(|| lock(scene).refit_geometry(g, vertices)).map_err(|e| to_py_err(py, e))
    }

    /// Moves geometry `g` and builds its trees afresh (minkq_scene_geometry_rebuild).
    fn rebuild_geometry(&self, py: Python<'_>, g: u32, vertices: &PyAny) -> PyResult<()> {
        let vertices = Vertices::get(vertices, "vertices", self.is_float64(g))?;
        // SAFETY: as in refit_geometry.
        let vertices = unsafe { vertices.buffer() };
        let scene = &self.inner;
        py.allow_threads(|| lock(scene).rebuild_geometry(g, vertices)).map_err(|e| to_py_err(py, e))
    }

    /// Swept positions of geometry `g`, its trees refitted (minkq_scene_geometry_refit_swept).
    fn refit_geometry_swept(&self, py: Python<'_>, g: u32, x0: &PyAny, x1: &PyAny) -> PyResult<()> {
        self.sweep_at(py, self.is_float64(g), x0, x1, |scene, x0, x1| scene.refit_geometry_swept(g, x0, x1))
    }

    /// Swept positions of geometry `g`, its trees built afresh
    /// (minkq_scene_geometry_rebuild_swept).
    fn rebuild_geometry_swept(&self, py: Python<'_>, g: u32, x0: &PyAny, x1: &PyAny) -> PyResult<()> {
        self.sweep_at(py, self.is_float64(g), x0, x1, |scene, x0, x1| scene.rebuild_geometry_swept(g, x0, x1))
    }

    fn refit(&self, py: Python<'_>, vertices: &PyAny) -> PyResult<()> {
        let vertices = Vertices::get(vertices, "vertices", self.float64)?;
        // SAFETY: rows of 3 floats (doubles in a float64 scene), alive in this frame.
        let vertices = unsafe { vertices.buffer() };
        let scene = &self.inner;
        py.allow_threads(|| lock(scene).refit(vertices)).map_err(|e| to_py_err(py, e))
    }

    fn rebuild(&self, py: Python<'_>, vertices: &PyAny) -> PyResult<()> {
        let vertices = Vertices::get(vertices, "vertices", self.float64)?;
        // SAFETY: rows of 3 floats (doubles in a float64 scene), alive in this frame.
        let vertices = unsafe { vertices.buffer() };
        let scene = &self.inner;
        py.allow_threads(|| lock(scene).rebuild(vertices)).map_err(|e| to_py_err(py, e))
    }

    /// Swept positions x0 -> x1, the trees refitted to the swept boxes (minkq_scene_refit_swept).
    fn refit_swept(&self, py: Python<'_>, x0: &PyAny, x1: &PyAny) -> PyResult<()> {
        self.sweep(py, x0, x1, |scene, x0, x1| scene.refit_swept(x0, x1))
    }

    /// Swept positions x0 -> x1, the trees built afresh (minkq_scene_rebuild_swept).
    fn rebuild_swept(&self, py: Python<'_>, x0: &PyAny, x1: &PyAny) -> PyResult<()> {
        self.sweep(py, x0, x1, |scene, x0, x1| scene.rebuild_swept(x0, x1))
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
        let info = py.allow_threads(|| lock(scene).query_into(&query, pairs)).map_err(|e| to_py_err(py, e))?;
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

    /// The exact number of pairs of a query, none written (MINKQ_QUERY_COUNT).
    fn count(&self, py: Python<'_>, kind: &str, mode: &str, radius: f32, leaf_exact: bool) -> PyResult<u64> {
        let query =
            Query::new(parse_kind(kind)?, parse_mode(mode)?, radius).with_flags(query_flags(leaf_exact, false, false));
        let scene = &self.inner;
        py.allow_threads(|| lock(scene).count(&query)).map_err(|e| to_py_err(py, e))
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
    fn wrap(scene: Scene, geometry_float64: Vec<bool>) -> PyScene {
        PyScene {
            vertex_count: scene.vertex_count(),
            triangle_count: scene.triangle_count(),
            edge_count: scene.edge_count(),
            float64: scene.is_float64(),
            geometry_float64,
            inner: Mutex::new(scene),
        }
    }

    /// Whether geometry `g` reads doubles (false out of range: the library refuses `g` then).
    fn is_float64(&self, g: u32) -> bool {
        self.geometry_float64.get(g as usize).copied().unwrap_or(false)
    }

    /// Runs `call` on the scene, without the GIL, with the swept positions `x0` and `x1` as
    /// buffers of the scene's precision: the one path of the blocking and stream-ordered swept
    /// calls.
    fn sweep<F>(&self, py: Python<'_>, x0: &PyAny, x1: &PyAny, call: F) -> PyResult<()>
    where
        F: for<'a> FnOnce(&mut Scene, Buffer<'a>, Buffer<'a>) -> minkq::Result<()> + Send,
    {
        self.sweep_at(py, self.float64, x0, x1, call)
    }

    /// `sweep` with positions of doubles (`float64`) or floats: a whole scene's or one
    /// geometry's.
    fn sweep_at<F>(&self, py: Python<'_>, float64: bool, x0: &PyAny, x1: &PyAny, call: F) -> PyResult<()>
    where
        F: for<'a> FnOnce(&mut Scene, Buffer<'a>, Buffer<'a>) -> minkq::Result<()> + Send,
    {
        let x0 = Vertices::get(x0, "x0", float64)?;
        let x1 = Vertices::get(x1, "x1", float64)?;
        // SAFETY: rows of 3 floats (doubles in a float64 scene), alive in this frame (on CUDA,
        // for the stream-ordered calls, the caller keeps them alive until the enqueued work has
        // run).
        let (x0, x1) = unsafe { (x0.buffer(), x1.buffer()) };
        let scene = &self.inner;
        py.allow_threads(|| call(&mut lock(scene), x0, x1)).map_err(|e| to_py_err(py, e))
    }
}
