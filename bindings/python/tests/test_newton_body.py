"""minkq.newton.ClothBodyContacts against a double-precision brute-force oracle
(newton_body_oracle.py) on a Newton model on Warp's CPU device: a cloth shell around a sphere
mesh on a moving body, beside a scaled static mesh shape. Zero false negatives, and every
reported pair within 1e-5 of its reach (minkq's leaf-exact bound), for the three kinds, before
and after the body and the cloth move; the body's vertices against Warp's own transforms."""

from __future__ import annotations

import numpy as np
import pytest

wp = pytest.importorskip("warp")
newton = pytest.importorskip("newton")

wp.config.quiet = True

import minkq.newton as mn  # noqa: E402
import newton_body_oracle as bo  # noqa: E402
from oracle import ee_contacts, vt_contacts  # noqa: E402

RADIUS = 0.01  # the soft contact gap
PARTICLE_RADIUS, MARGIN = 0.004, 0.002


def _sphere(radius: float, n: int):
    mesh = newton.Mesh.create_sphere(radius, num_latitudes=n, num_longitudes=n, compute_inertia=False)
    return np.asarray(mesh.vertices, np.float32), np.asarray(mesh.indices, np.int32)


def _model(cloth_worlds: bool = False):
    """A sphere cloth of radius 0.505 around a sphere mesh of radius 0.5 (another tessellation)
    on a body turned about z, and a static sphere mesh scaled to an ellipsoid beside it."""
    builder = newton.ModelBuilder()
    xyz, tris = _sphere(0.505, 12)
    builder.add_cloth_mesh(pos=wp.vec3(0.0, 0.0, 1.0), rot=wp.quat_identity(), scale=1.0, vel=wp.vec3(0.0),
                           vertices=xyz.tolist(), indices=tris.tolist(), density=0.1, particle_radius=PARTICLE_RADIUS)
    cfg = newton.ModelBuilder.ShapeConfig(margin=MARGIN)
    body = builder.add_body(xform=wp.transform(wp.vec3(0.0, 0.0, 1.0), wp.quat_from_axis_angle(wp.vec3(0.0, 0.0, 1.0), 0.3)))
    builder.add_shape_mesh(body, mesh=newton.Mesh(*_sphere(0.5, 16)), cfg=cfg)
    builder.add_shape_box(body, hx=0.1, hy=0.1, hz=0.1)  # not a mesh: left out
    builder.add_shape_mesh(
        -1, xform=wp.transform(wp.vec3(0.62, 0.0, 1.0), wp.quat_from_axis_angle(wp.vec3(0.0, 1.0, 0.0), 0.4)),
        mesh=newton.Mesh(*_sphere(1.0, 10), compute_inertia=False), scale=wp.vec3(0.15, 0.2, 0.3), cfg=cfg,
    )
    return builder.finalize(device="cpu")


@pytest.fixture(scope="module")
def model():
    return _model()


def _warp_vertices(model, state, shape: int) -> np.ndarray:
    """Shape ``shape``'s mesh vertices in world space by Warp's own transforms (float32)."""
    body = int(model.shape_body.numpy()[shape])
    xform = wp.transform(*np.split(model.shape_transform.numpy()[shape], [3]))
    if body >= 0:
        xform = wp.transform_multiply(wp.transform(*np.split(state.body_q.numpy()[body], [3])), xform)
    scale = wp.vec3(*model.shape_scale.numpy()[shape])
    return np.array([wp.transform_point(xform, wp.cw_mul(wp.vec3(*v), scale)) for v in model.shape_source[shape].vertices])


def _check(contacts, model, state, radius: float = RADIUS, thickness: bool = True) -> None:
    particles = state.particle_q.numpy()
    cloth = bo.side(particles, contacts.tri_indices, contacts.edge_indices,
                    model.particle_radius.numpy() if thickness else 0.0)
    bodies = []
    for s in contacts.shapes:
        xyz = contacts.shape_world_vertices(s, state)
        np.testing.assert_allclose(xyz, _warp_vertices(model, state, s), atol=2e-6)
        bodies.append((s, bo.side(xyz, model.shape_source[s].indices, contacts.shape_edges(s), MARGIN if thickness else 0.0)))
    truth = bo.truth(cloth, bodies, radius)
    pairs = contacts.detect(radius)
    for kind in bo.KINDS:
        found, t = getattr(pairs, kind), truth[kind]
        assert len(t.within()) > 0, kind  # the scene has contacts of every kind
        missed = bo.as_keys(t.within()) - bo.as_keys(found)
        assert not missed, f"{kind}: {len(missed)} contacts missed, e.g. {sorted(missed)[:5]}"
        extra = bo.as_keys(found) - bo.as_keys(t.rows)
        assert not extra, f"{kind}: {len(extra)} pairs beyond their reach, e.g. {sorted(extra)[:5]}"
        assert found.dtype == np.int32 and found.shape[1] == 3
        assert (found == found[np.lexsort(found.T[::-1])]).all()  # sorted rows


def test_shapes_are_the_mesh_shapes_colliding_with_particles(model):
    contacts = mn.ClothBodyContacts(model)
    types = model.shape_type.numpy()
    assert contacts.shapes == [s for s in range(model.shape_count) if types[s] == int(newton.GeoType.MESH)]
    assert len(contacts.shapes) == 2
    assert contacts.scene.geometry_count == 3


def test_pairs_match_the_oracle_at_rest_and_after_motion(model):
    state = model.state()
    contacts = mn.ClothBodyContacts(model)
    contacts.update(state)
    _check(contacts, model, state)
    # The body turns and slides, the cloth is shaken: the static ellipsoid stays.
    q = state.body_q.numpy()
    q[0, :3] += (0.01, -0.005, 0.003)
    q[0, 3:] = np.array(wp.quat_from_axis_angle(wp.normalize(wp.vec3(1.0, 1.0, 0.0)), 0.2))
    state.body_q.assign(q)
    rng = np.random.default_rng(3)
    particles = state.particle_q.numpy()
    state.particle_q.assign(particles + rng.uniform(-0.004, 0.004, particles.shape).astype(np.float32))
    contacts.update(state)
    _check(contacts, model, state)
    contacts.rebuild(state)
    _check(contacts, model, state)


def test_without_thickness_the_band_is_the_radius(model):
    state = model.state()
    contacts = mn.ClothBodyContacts(model, thickness=False)
    _check(contacts, model, state, radius=0.012, thickness=False)


def test_self_contacts(model):
    state = model.state()
    contacts = mn.ClothBodyContacts(model, self_contacts=True)
    pairs = contacts.detect(RADIUS)
    assert mn.ClothBodyContacts(model).detect(RADIUS).self_edge_edge is None
    # The cloth's own pairs within r plus the two vertices' radii (every particle has the same).
    reach = RADIUS + 2 * PARTICLE_RADIUS
    xyz = state.particle_q.numpy()
    found_vt = set(map(tuple, pairs.self_vertex_triangle.tolist()))
    found_ee = set(map(tuple, pairs.self_edge_edge.tolist()))
    assert vt_contacts(xyz, contacts.tri_indices, reach * (1 - 1e-5)) <= found_vt <= vt_contacts(xyz, contacts.tri_indices, reach * (1 + 1e-5))
    edges = contacts.edge_indices
    assert ee_contacts(xyz, edges, reach * (1 - 1e-5)) <= found_ee <= ee_contacts(xyz, edges, reach * (1 + 1e-5))
    assert found_vt and found_ee


def test_worlds_filter_the_pairs():
    model = _model()
    # The cloth's particles in world 0, the moving sphere's shape in world 1: only the static
    # ellipsoid (world -1) meets the cloth.
    model.particle_world.assign(np.zeros(model.particle_count, np.int32))
    worlds = model.shape_world.numpy()
    worlds[0] = 1
    model.shape_world.assign(worlds)
    pairs = mn.ClothBodyContacts(model).detect(RADIUS)
    for kind in bo.KINDS:
        rows = getattr(pairs, kind)
        assert len(rows) and set(rows[:, 1].tolist()) == {2}, kind


def test_bad_input(model):
    contacts = mn.ClothBodyContacts(model)
    for bad in (-1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="radius: expected a finite number >= 0"):
            contacts.detect(bad)
    with pytest.raises(TypeError, match="radius"):
        contacts.detect("0.1")
    with pytest.raises(ValueError, match=r"shapes\[0\]: shape 1 is a BOX, not a mesh"):
        mn.ClothBodyContacts(model, shapes=[1])
    with pytest.raises(ValueError, match=r"shapes\[1\]: shape 7 is out of range \(the model has 3 shapes\)"):
        mn.ClothBodyContacts(model, shapes=[0, 7])
    with pytest.raises(ValueError, match=r"shapes\[1\]: shape 0 is listed twice"):
        mn.ClothBodyContacts(model, shapes=[0, 0])
    with pytest.raises(ValueError, match="shape: shape 1 is not one of this detector's mesh shapes"):
        contacts.shape_edges(1)
    builder = newton.ModelBuilder()
    builder.add_cloth_grid(pos=wp.vec3(0.0), rot=wp.quat_identity(), vel=wp.vec3(0.0), dim_x=2, dim_y=2,
                           cell_x=0.1, cell_y=0.1, mass=0.1)
    builder.add_shape_box(builder.add_body(), hx=0.1, hy=0.1, hz=0.1)
    with pytest.raises(ValueError, match="none of its 1 shapes is a mesh"):
        mn.ClothBodyContacts(builder.finalize(device="cpu"))
    state = model.state()
    state.body_q = None
    with pytest.raises(ValueError, match="state: has no body_q, but shape 0 is on body 0"):
        contacts.update(state)
    state = model.state()
    q = state.particle_q.numpy()
    q[5, 1] = np.nan
    state.particle_q.assign(q)
    with pytest.raises(Exception, match="geometry 0"):
        contacts.update(state)
