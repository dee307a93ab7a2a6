//! Scenes of many geometries (`minkq_scene_create_geometries`): their creation, their
//! geometries' ranges in the global numbering, and the way back from a global id to a geometry.
use std::ops::Range;
use std::ptr::{self, NonNull};

use super::{vertex_buffer, Holder, Scene};
use crate::buffer::sealed::Precision;
use crate::device::Device;
use crate::error::{check, Error, Result};
use crate::geometry::{raw_defaults, Element, GeometryDesc, GeometryFlags};
use crate::query::QueryKind;
use crate::sys;

/// What the safe API keeps of a scene's geometries: each one's flags (for the precision of the
/// vertex buffers it takes) and first global ids (to map ids back to geometries).
pub(super) struct Layout {
    /// Each geometry's flags, FLOAT64 set where its vertices are doubles.
    flags: Box<[GeometryFlags]>,
    /// Per element (in `Element::ALL` order): each geometry's first global id, then the total.
    firsts: [Box<[usize]>; 3],
}

impl Layout {
    /// No geometry: a placeholder until the scene's own is read.
    pub(super) fn empty() -> Layout {
        Layout { flags: Box::new([]), firsts: [Box::new([0]), Box::new([0]), Box::new([0])] }
    }

    /// The layout of a live scene of geometries with `flags`, its ranges as the library gives them.
    pub(super) fn read(scene: &Scene, flags: Vec<GeometryFlags>) -> Result<Layout> {
        let mut firsts: [Vec<usize>; 3] = Default::default();
        for element in Element::ALL {
            let firsts = &mut firsts[element.index()];
            for g in 0..flags.len() as u32 {
                firsts.push(scene.geometry_range(g, element)?.start);
            }
            firsts.push(scene.element_count(element));
        }
        let [vertices, triangles, edges] = firsts;
        Ok(Layout {
            flags: flags.into_boxed_slice(),
            firsts: [vertices.into_boxed_slice(), triangles.into_boxed_slice(), edges.into_boxed_slice()],
        })
    }

    /// The flags of the geometries that move.
    fn moving(&self) -> impl Iterator<Item = &GeometryFlags> {
        self.flags.iter().filter(|f| !f.contains(GeometryFlags::STATIC))
    }

    /// Whether every moving geometry is float64, and there is one: the precision of the
    /// whole-scene calls (as the library decides it).
    pub(super) fn moving_float64(&self) -> bool {
        self.moving().next().is_some() && self.moving().all(|f| f.contains(GeometryFlags::FLOAT64))
    }

    /// Whether the moving geometries mix float and double vertices.
    pub(super) fn mixed_precision(&self) -> bool {
        let float64 = self.moving().filter(|f| f.contains(GeometryFlags::FLOAT64)).count();
        float64 > 0 && float64 < self.moving().count()
    }

    /// The flags of geometry `g` if it exists and moves: the ones its vertex buffers are
    /// checked against.
    pub(super) fn moving_geometry(&self, g: u32) -> Option<GeometryFlags> {
        self.flags.get(g as usize).copied().filter(|f| !f.contains(GeometryFlags::STATIC))
    }
}

impl Scene {
    /// A scene of many geometries (`minkq_scene_create_geometries`): triangle meshes, edge sets
    /// and vertex sets, each with its own vertices (`[f32; 3]` or `[f64; 3]`), topology,
    /// kinds, flags, thickness, world, group and mask, each with its own trees; the library
    /// copies them. Its queries ([`Scene::query`] and the others) report, for their kind:
    /// - self pairs within a geometry with [`GeometryFlags::SELF`] (incident ones dropped with
    ///   [`GeometryFlags::DROP_INCIDENT`]), as a scene of that geometry alone would;
    /// - cross pairs between two geometries that both have the kind, share a world (equal
    ///   worlds, or either `None`: every world) and each have their group in the other's mask.
    ///   VT and EV run both ways; EE and VV pairs are (lower, higher) global id;
    /// - with thickness, every pair within r + t(a) + t(b) ([`GeometryDesc::thickness`]), in
    ///   every mode; [`QueryFlags::LEAF_EXACT`] keeps exactly those (within the float slack).
    ///
    /// Pairs use one global numbering: the geometries' vertices, triangles and edges
    /// concatenated in the order given ([`Scene::geometry_range`]; [`Scene::locate`] and
    /// [`Scene::locate_pair`] map ids back), a geometry's edges numbered as a one-mesh scene
    /// numbers them. Whole-scene refits and rebuilds ([`Scene::refit`] and the others) take the
    /// vertices of the moving geometries one after another, all of one precision;
    /// [`Scene::refit_geometry`] and the others move one geometry. The stream-ordered calls
    /// take such scenes too: their whole-scene moves take the moving geometries' vertices as
    /// [`Scene::refit`] does (`minkq_async.h`).
    ///
    /// Errors: those of [`Scene::new`], the library's messages naming the geometry
    /// (`"geometry 1: triangle 0 references vertex 7 but the geometry has 3 vertices"`);
    /// [`Error::InvalidArgument`] also for no geometry, no kind, a thickness count other than
    /// the vertex count or a negative thickness, a world over `i32::MAX`, or a vertex slice
    /// whose precision contradicts [`GeometryFlags::FLOAT64`]; [`Error::NonFinite`] for a
    /// non-finite thickness; [`Error::SizeOverflow`] for more than 2^31 - 2 vertices,
    /// triangles or edges in all.
    ///
    /// A square of cloth 0.1 above a static body triangle:
    ///
    /// ```
    /// use minkq::{Device, Element, Error, GeometryDesc, GeometryFlags, Mode, PairBuffer, Query, QueryFlags, Scene};
    /// let mut cloth = vec![[0.0f32, 0.0, 0.1], [1.0, 0.0, 0.1], [1.0, 1.0, 0.1], [0.0, 1.0, 0.1]];
    /// let body = [[-1.0f32, -1.0, 0.0], [2.0, -1.0, 0.0], [-1.0, 2.0, 0.0]];
    /// let mut scene = Scene::from_geometries(&Device::cpu()?, &[
    ///     GeometryDesc::mesh(&cloth, &[[0, 1, 2], [0, 2, 3]]), // self pairs, moves
    ///     GeometryDesc::mesh(&body, &[[0, 1, 2]]).flags(GeometryFlags::STATIC), // no self pairs
    /// ])?;
    /// assert_eq!(scene.geometry_count(), 2);
    /// assert_eq!(scene.geometry_range(1, Element::Vertex)?, 4..7); // after the cloth's 4
    /// assert_eq!(scene.geometry_range(1, Element::Triangle)?, 2..3);
    ///
    /// let query = Query::vt(Mode::Box, 0.2).with_flags(QueryFlags::LEAF_EXACT | QueryFlags::CANONICAL);
    /// let mut pairs = PairBuffer::new()?;
    /// // Cloth vertices 0, 1 and 3 over the body's triangle (global triangle 2); vertex 2
    /// // lies beyond its hypotenuse.
    /// assert_eq!(scene.query(&query, &mut pairs)?, &[[0, 2], [1, 2], [3, 2]]);
    /// // (geometry, local id) of each side: cloth vertex 3, body triangle 0.
    /// assert_eq!(scene.locate_pair(query.kind, [3, 2]), Some([(0, 3), (1, 0)]));
    ///
    /// // A step moves the cloth only; the body is never touched and refuses to move.
    /// for v in &mut cloth {
    ///     v[2] += 1.0;
    /// }
    /// scene.refit_geometry(0, &cloth)?;
    /// assert!(scene.query(&query, &mut pairs)?.is_empty());
    /// let err = scene.refit_geometry(1, &body).unwrap_err();
    /// assert_eq!(err, Error::InvalidArgument("geometry 1 is static (MINKQ_GEOMETRY_STATIC): it is built once and never moves".into()));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    ///
    /// [`QueryFlags::LEAF_EXACT`]: crate::QueryFlags::LEAF_EXACT
    pub fn from_geometries(device: &Device, geometries: &[GeometryDesc<'_>]) -> Result<Scene> {
        let mut flags = Vec::with_capacity(geometries.len());
        let mut raw_descs = Vec::with_capacity(geometries.len());
        for (g, desc) in geometries.iter().enumerate() {
            let (raw, float64) = raw_geometry(g, desc)?;
            raw_descs.push(raw);
            flags.push(if float64 { desc.flags | GeometryFlags::FLOAT64 } else { desc.flags });
        }
        let mut raw = ptr::null_mut();
        // SAFETY: `raw_descs` holds `len` descriptions of this header's struct_size, whose
        // buffers' constructors promise readable records for their lifetime, which outlives
        // this call; the library copies them before returning. A null array with count 0 is
        // refused without being read.
        check(unsafe {
            sys::minkq_scene_create_geometries(
                device.handle.as_ptr(),
                if raw_descs.is_empty() { ptr::null() } else { raw_descs.as_ptr() },
                raw_descs.len(),
                &mut raw,
            )
        })?;
        let raw =
            NonNull::new(raw).ok_or_else(|| Error::Internal("minkq_scene_create_geometries returned NULL".into()))?;
        Scene::from_raw(raw, device, flags)
    }

    /// The number of geometries (1 for a scene made by [`Scene::new`]).
    ///
    /// ```
    /// # use minkq::*;
    /// let scene = Scene::new(&Device::cpu()?, &SceneDesc::new(&[[0.0f32; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], &[[0, 1, 2]]))?;
    /// assert_eq!(scene.geometry_count(), 1);
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn geometry_count(&self) -> u32 {
        // SAFETY: a live scene.
        unsafe { sys::minkq_scene_geometry_count(self.raw.as_ptr()) }
    }

    /// Geometry `geometry`'s global ids of `element` (`minkq_scene_geometry_range`): its
    /// vertices, triangles or edges (derived ones when it derived them) in the numbering of
    /// the scene's pairs. [`Error::InvalidArgument`] for a geometry out of range.
    ///
    /// ```
    /// # use minkq::*;
    /// let rod = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
    /// let triangle = [[0.0f32, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]];
    /// let scene = Scene::from_geometries(&Device::cpu()?, &[
    ///     GeometryDesc::mesh(&triangle, &[[0, 1, 2]]).kinds(Kinds::EE),
    ///     GeometryDesc::codim(&rod, &[[0, 1], [1, 2]]).kinds(Kinds::EE),
    /// ])?;
    /// assert_eq!(scene.geometry_range(0, Element::Edge)?, 0..3); // derived from the triangle
    /// assert_eq!(scene.geometry_range(1, Element::Edge)?, 3..5);
    /// assert_eq!(scene.geometry_range(1, Element::Triangle)?, 1..1);
    /// let err = scene.geometry_range(2, Element::Vertex).unwrap_err();
    /// assert_eq!(err.message(), "geometry 2 is out of range: the scene has 2 geometries");
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn geometry_range(&self, geometry: u32, element: Element) -> Result<Range<usize>> {
        let (mut first, mut count) = (0usize, 0usize);
        // SAFETY: a live scene; two writable sizes.
        check(unsafe {
            sys::minkq_scene_geometry_range(self.raw.as_ptr(), geometry, element.raw(), &mut first, &mut count)
        })?;
        Ok(first..first + count)
    }

    /// The geometry of global id `id` of `element` and its id within that geometry, as
    /// (geometry, local id); `None` for an id out of range. Ranges as
    /// [`Scene::geometry_range`] gives them, looked up in O(log geometries).
    ///
    /// ```
    /// # use minkq::*;
    /// let a = [[0.0f32; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    /// let scene = Scene::from_geometries(&Device::cpu()?, &[GeometryDesc::mesh(&a, &[[0, 1, 2]]); 3])?;
    /// assert_eq!(scene.locate(Element::Vertex, 7), Some((2, 1)));
    /// assert_eq!(scene.locate(Element::Triangle, 1), Some((1, 0)));
    /// assert_eq!((scene.locate(Element::Vertex, 9), scene.locate(Element::Edge, -1)), (None, None));
    /// # Ok::<(), minkq::Error>(())
    /// ```
    pub fn locate(&self, element: Element, id: i32) -> Option<(u32, usize)> {
        let firsts = &self.layout.firsts[element.index()];
        let id = usize::try_from(id).ok()?;
        let (total, starts) = firsts.split_last()?;
        if id >= *total {
            return None;
        }
        // The last geometry starting at or before `id` (empty ones before it start there too).
        let g = starts.partition_point(|&first| first <= id) - 1;
        Some((g as u32, id - starts[g]))
    }

    /// Both sides of a pair of `kind` as (geometry, local id) ([`QueryKind::elements`] says
    /// which elements they are); `None` if either id is out of range. The example is at
    /// [`Scene::from_geometries`].
    pub fn locate_pair(&self, kind: QueryKind, pair: [i32; 2]) -> Option<[(u32, usize); 2]> {
        let [a, b] = kind.elements();
        Some([self.locate(a, pair[0])?, self.locate(b, pair[1])?])
    }

    /// The scene's count of `element`s.
    fn element_count(&self, element: Element) -> usize {
        match element {
            Element::Vertex => self.vertex_count(),
            Element::Triangle => self.triangle_count(),
            Element::Edge => self.edge_count(),
        }
    }
}

/// Geometry `g`'s C description, and whether its vertices are doubles (the flag, or a slice
/// of `[f64; 3]`).
fn raw_geometry(g: usize, desc: &GeometryDesc<'_>) -> Result<(sys::minkq_geometry_desc, bool)> {
    let float64 = desc.flags.contains(GeometryFlags::FLOAT64) || desc.vertices.precision() == Some(Precision::F64);
    let mut flags = desc.flags;
    if float64 {
        flags |= GeometryFlags::FLOAT64;
    }
    let world = match desc.world {
        None => -1,
        Some(world) => i32::try_from(world).map_err(|_| {
            Error::InvalidArgument(format!("geometry {g}: world {world} is over i32::MAX, the largest world id"))
        })?,
    };
    let mut raw = raw_defaults();
    raw.kinds = desc.kinds.bits();
    raw.flags = flags.bits();
    raw.world = world;
    raw.group = desc.group;
    raw.mask = desc.mask;
    raw.vertices = vertex_buffer(&format!("geometry {g}: create"), &desc.vertices, float64, Holder::Geometry)?;
    raw.triangles = desc.triangles.raw();
    raw.edges = desc.edges.raw();
    raw.thickness = desc.thickness.raw();
    Ok((raw, float64))
}
