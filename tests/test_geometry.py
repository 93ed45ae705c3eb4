"""Rotations and skew matrices: orthogonality, composition order, inverses, Rodrigues."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from parakin import geometry as g

angles = st.floats(-np.pi, np.pi, allow_nan=False)
vec3 = arrays(np.float64, 3, elements=st.floats(-10, 10, allow_nan=False))


def test_elementary_rotations_by_hand():
    c, s = np.cos(0.3), np.sin(0.3)
    assert np.allclose(g.rot_z(0.3), [[c, -s, 0], [s, c, 0], [0, 0, 1]])
    assert np.allclose(g.rot_y(0.3), [[c, 0, s], [0, 1, 0], [-s, 0, c]])
    assert np.allclose(g.rot_x(0.3), [[1, 0, 0], [0, c, -s], [0, s, c]])
    # a quarter turn about z takes x to y
    assert np.allclose(g.rot_z(np.pi / 2) @ [1, 0, 0], [0, 1, 0])


def test_batched_shapes_and_orthogonality(rng):
    a = rng.uniform(-np.pi, np.pi, size=(4, 5, 3))
    r = g.euler_zyx(a[..., 0], a[..., 1], a[..., 2])
    assert r.shape == (4, 5, 3, 3)
    assert np.allclose(r @ np.swapaxes(r, -1, -2), np.eye(3), atol=1e-14)
    assert np.allclose(np.linalg.det(r), 1.0)


def test_euler_order():
    a, b, c = 0.1, -0.4, 0.7
    assert np.allclose(g.euler_zyx(a, b, c), g.rot_z(a) @ g.rot_y(b) @ g.rot_x(c))
    assert np.allclose(g.euler_xyz(a, b, c), g.rot_x(a) @ g.rot_y(b) @ g.rot_z(c))
    assert not np.allclose(g.euler_zyx(a, b, c), g.euler_xyz(a, b, c))


@settings(max_examples=200, deadline=None)
@given(angles, st.floats(-1.5, 1.5), angles)
def test_euler_round_trips(a, b, c):
    assert np.allclose(g.euler_zyx_from_matrix(g.euler_zyx(a, b, c)), [a, b, c], atol=1e-9)
    assert np.allclose(g.euler_xyz_from_matrix(g.euler_xyz(a, b, c)), [a, b, c], atol=1e-9)


@settings(max_examples=200, deadline=None)
@given(vec3, vec3)
def test_skew_is_cross_product(v, w):
    assert np.allclose(g.skew(v) @ w, np.cross(v, w))
    assert np.allclose(g.unskew(g.skew(v)), v)


def test_axis_angle_matches_elementary_and_batches(rng):
    assert np.allclose(g.axis_angle([0, 0, 2.0], 0.7), g.rot_z(0.7))
    assert np.allclose(g.axis_angle([1, 0, 0], -1.1), g.rot_x(-1.1))
    axes = rng.normal(size=(6, 3))
    t = rng.uniform(-3, 3, size=6)
    r = g.axis_angle(axes, t)
    # the axis is fixed and the rotation angle is |t|: trace = 1 + 2 cos t
    assert np.allclose(np.einsum("nij,nj->ni", r, axes), axes)
    assert np.allclose(np.trace(r, axis1=-2, axis2=-1), 1 + 2 * np.cos(t))


def test_unit_rejects_zero_vector():
    with pytest.raises(ValueError, match="zero vector"):
        g.unit([0.0, 0.0, 0.0])
