"""The closed-form wrench cone against the corner forces it replaces (a linear program)."""

import numpy as np
import pytest
from scipy.optimize import linprog

from dgraph.entities.contacts.contact6d import corner_positions, force_generator
from dgraph.entities.contacts.wrench_cone import corner_force_metric, wrench_cone

SOLES = [(0.10, 0.11, 0.069, 0.3 / np.sqrt(2.0)),  # TALOS, the inscribed pyramid of mu = 0.3
         (0.05, 0.20, 0.03, 0.8)]                 # long, narrow, far off its centre, high friction


def pyramid_edges(mu: float) -> np.ndarray:
    """The four edges of ``|f_x|, |f_y| <= mu f_z`` (rows)."""
    return np.array([[sx * mu, sy * mu, 1.0] for sx in (1.0, -1.0) for sy in (1.0, -1.0)])


def corner_forces_exist(wrench: np.ndarray, front: float, back: float, half_width: float, mu: float) -> bool:
    """Whether four corner forces in their pyramids exert ``wrench`` (an LP in the edge weights)."""
    generator = force_generator(corner_positions(front, back, half_width))
    edges = pyramid_edges(mu)
    rays = np.hstack([generator[:, 3 * i:3 * i + 3] @ edges.T for i in range(4)])  # 6 x 16
    result = linprog(np.zeros(16), A_eq=rays, b_eq=wrench, bounds=(0, None), method="highs")
    return result.status == 0


@pytest.mark.parametrize(("front", "back", "half_width", "mu"), SOLES)
def test_every_corner_force_in_its_pyramid_gives_a_wrench_in_the_cone(front, back, half_width, mu):
    cone = wrench_cone(front, back, half_width, mu)
    generator = force_generator(corner_positions(front, back, half_width))
    for i in range(4):
        for edge in pyramid_edges(mu):
            assert (cone @ (generator[:, 3 * i:3 * i + 3] @ edge) <= 1e-12).all()
    rng = np.random.default_rng(0)
    normal = rng.exponential(size=(200, 4, 1))
    forces = np.concatenate([mu * normal * rng.uniform(-1.0, 1.0, size=(200, 4, 2)), normal], axis=2)  # in the pyramids
    assert (np.einsum("rk,nk->nr", cone, forces.reshape(200, 12) @ generator.T) <= 1e-12).all()


@pytest.mark.parametrize(("front", "back", "half_width", "mu"), SOLES)
def test_every_wrench_in_the_cone_comes_from_corner_forces(front, back, half_width, mu):
    """The vertices of the cone's slice at f_z = 1 (maxima of random directions) are all
    reachable with corner forces: then so is the whole cone, it is not larger than the corners'."""
    cone = wrench_cone(front, back, half_width, mu)
    rng = np.random.default_rng(1)
    unit_fz = np.array([[0.0, 0.0, 1.0, 0.0, 0.0, 0.0]])
    vertices = set()
    for direction in rng.normal(size=(300, 6)):
        result = linprog(-direction, A_ub=cone, b_ub=np.zeros(16), A_eq=unit_fz, b_eq=[1.0],
                         bounds=(None, None), method="highs")
        assert result.status == 0
        vertices.add(tuple(np.round(result.x, 9)))
    assert len(vertices) >= 16  # the slice is a polytope with many vertices: they were found
    for vertex in vertices:
        assert corner_forces_exist(np.array(vertex), front, back, half_width, mu), vertex
    outside = np.array([mu * 1.01, 0.0, 1.0, 0.0, 0.0, 0.0])  # just past the friction face
    assert (cone @ outside > 0).any() and not corner_forces_exist(outside, front, back, half_width, mu)


def test_the_metric_is_the_least_corner_force_norm():
    generator = force_generator(corner_positions(0.10, 0.11, 0.069))
    metric = corner_force_metric(generator)
    wrench = np.array([3.0, -2.0, 400.0, 5.0, -7.0, 1.5])
    least_norm = np.linalg.lstsq(generator, wrench, rcond=None)[0]  # the minimum-norm solution of T f = w
    np.testing.assert_allclose(generator @ least_norm, wrench, atol=1e-9)
    assert wrench @ metric @ wrench == pytest.approx(least_norm @ least_norm, rel=1e-12)
