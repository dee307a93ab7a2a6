//! Scenes of many geometries (`minkq_scene_create_geometries`): the package's checked
//! geometries (minkq._geometry._NativeGeometry, read by attribute) as the safe crate's
//! descriptions, and the creation of their scene.
use std::sync::Mutex;

use minkq::{Buffer, Device, Element, GeometryDesc, GeometryFlags, Kinds, Scene};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::arrays::{Array, Vertices};
use crate::{lock, to_py_err};

/// One geometry as the package passes it: arrays checked (numpy or raw descriptors), the
/// flags and filters as plain values.
#[derive(FromPyObject)]
pub(crate) struct GeometryArgs<'a> {
    vertices: &'a PyAny,
    triangles: &'a PyAny,
    edges: Option<&'a PyAny>,
    thickness: Option<&'a PyAny>,
    float64: bool,
    vt: bool,
    ee: bool,
    vv: bool,
    ev: bool,
    self_pairs: bool,
    drop_incident: bool,
    #[pyo3(attribute("static"))]
    is_static: bool,
    /// -1: every world.
    world: i32,
    group: u32,
    mask: u32,
}

/// A geometry's arrays, viewed for the call, and its description's other fields.
struct Checked {
    vertices: Vertices,
    triangles: Array<i32>,
    edges: Option<Array<i32>>,
    thickness: Option<Array<f32>>,
    kinds: Kinds,
    flags: GeometryFlags,
    world: Option<u32>,
    group: u32,
    mask: u32,
}

impl Checked {
    fn get(g: usize, args: &GeometryArgs<'_>) -> PyResult<Checked> {
        let name = |field: &str| format!("geometries[{g}].{field}");
        let mut kinds = Kinds::empty();
        for (wanted, kind) in [(args.vt, Kinds::VT), (args.ee, Kinds::EE), (args.vv, Kinds::VV), (args.ev, Kinds::EV)] {
            if wanted {
                kinds |= kind;
            }
        }
        let mut flags = GeometryFlags::empty();
        for (wanted, flag) in [
            (args.self_pairs, GeometryFlags::SELF),
            (args.drop_incident, GeometryFlags::DROP_INCIDENT),
            (args.float64, GeometryFlags::FLOAT64),
            (args.is_static, GeometryFlags::STATIC),
        ] {
            if wanted {
                flags |= flag;
            }
        }
        let world = match args.world {
            -1 => None,
            w => Some(u32::try_from(w).map_err(|_| {
                PyValueError::new_err(format!(
                    "{}: expected a world id >= 0, or -1 for every world, got {w}",
                    name("world")
                ))
            })?),
        };
        Ok(Checked {
            vertices: Vertices::get(args.vertices, &name("vertices"), args.float64)?,
            triangles: Array::get(args.triangles, &name("triangles"), &[3], false)?,
            edges: args.edges.map(|e| Array::get(e, &name("edges"), &[2], false)).transpose()?,
            thickness: args.thickness.map(|t| Array::get(t, &name("thickness"), &[], false)).transpose()?,
            kinds,
            flags,
            world,
            group: args.group,
            mask: args.mask,
        })
    }

    /// The description over the viewed arrays.
    ///
    /// # Safety
    /// Raw descriptors describe memory that stays readable while the description is used (the
    /// package's promise, as for every array argument).
    unsafe fn desc(&self) -> GeometryDesc<'_> {
        let mut desc = GeometryDesc::from_buffers(self.vertices.buffer(), self.triangles.buffer());
        desc.edges = self.edges.as_ref().map_or(Buffer::empty(), |e| e.buffer());
        desc.thickness = self.thickness.as_ref().map_or(Buffer::empty(), |t| t.buffer());
        desc.kinds(self.kinds).flags(self.flags).world(self.world).group(self.group).mask(self.mask)
    }
}

/// The scene of `geometries` on `device`, built without the GIL, and each geometry's
/// precision (whether its vertices are doubles).
pub(crate) fn create(
    py: Python<'_>,
    device: &Mutex<Device>,
    geometries: &[GeometryArgs<'_>],
) -> PyResult<(Scene, Vec<bool>)> {
    let checked = geometries.iter().enumerate().map(|(g, args)| Checked::get(g, args)).collect::<PyResult<Vec<_>>>()?;
    // SAFETY: shapes checked: rows of 3 floats (doubles with FLOAT64), 3 and 2 int32, one float
    // per thickness; the arrays live in this frame.
    let descs: Vec<GeometryDesc<'_>> = checked.iter().map(|c| unsafe { c.desc() }).collect();
    let scene = py.allow_threads(|| Scene::from_geometries(&lock(device), &descs)).map_err(|e| to_py_err(py, e))?;
    Ok((scene, geometries.iter().map(|args| args.float64).collect()))
}

/// An element's name, as the package spells it.
pub(crate) fn parse_element(element: &str) -> PyResult<Element> {
    match element {
        "vertex" => Ok(Element::Vertex),
        "triangle" => Ok(Element::Triangle),
        "edge" => Ok(Element::Edge),
        _ => Err(PyValueError::new_err(format!("element: expected 'vertex', 'triangle' or 'edge', got {element:?}"))),
    }
}
