"""Second-order motion of batched quantities along a trajectory: exact velocity and acceleration maps.

A mechanism's bodies move as functions of its pose ``x(t)``. For inverse dynamics by virtual work
we need, for every quantity ``y(x)`` (a point, an axis, a rotation, a joint value), its Jacobian
``J = dy/dx`` (the virtual displacements), its rate ``dy/dt = J xdot`` and its acceleration
``d2y/dt2 = J xddot + b`` where the *bias* ``b = D2y[xdot, xdot]`` collects the velocity-product
terms. A :class:`Jet` carries exactly that, and every operation on jets (sums, products, cross and
dot products, square roots, sines, matrix products) propagates it by the product and chain rules,
so a mechanism writes its body placements once, as ordinary formulas of the pose, and gets exact
first- and second-order kinematics (second-order forward-mode differentiation; Griewank & Walther,
*Evaluating Derivatives*, 2nd ed., SIAM 2008, ch. 13, restricted to one direction of second order).

Layout: ``value`` has the batch and quantity shape ``(..., *s)``; ``tangents`` has one more,
*leading*, axis of ``n + 1`` directions: ``tangents[k] = J e_k`` for the ``n`` pose coordinates
and ``tangents[n] = J xdot`` (the rate). Leading tangents make every bilinear rule the operation
itself: ``(a b)' = a' b + a b'`` is ``f(a.tangents, b) + f(a, b.tangents)`` with numpy
broadcasting. ``bias`` has the value's shape.

Angular velocity is not the derivative of a value; :class:`Spin` carries its Jacobian, rate and
bias (``omega = J_w xdot``, ``alpha = J_w xddot + b_w``), from a rotation jet
(:func:`spin_of_rotation`) or from a unit axis that does not spin about itself
(:func:`spin_of_axis`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from parakin.geometry import plane_rotation

Array = NDArray[np.float64]

__all__ = [
    "Jet",
    "Spin",
    "variable",
    "constant_like",
    "numeric",
    "dot",
    "cross",
    "norm",
    "normalize",
    "sqrt",
    "sin",
    "cos",
    "matvec",
    "matmul",
    "transpose",
    "stack",
    "spin_of_rotation",
    "spin_of_axis",
    "contract",
    "rotations",
    "euler_zyx",
    "rot_x",
    "rot_y",
    "rot_z",
    "skew",
    "vdot",
    "vcross",
    "vmatvec",
]


class _Motion:
    """What a :class:`Jet` and a :class:`Spin` share: ``tangents`` (n + 1, ..., *s) (the ``n`` pose
    directions, then the rate) and ``bias`` (..., *s), the value's shape."""

    tangents: Array
    bias: Array

    @property
    def rate(self) -> Array:
        """``dy/dt = J xdot`` (for a spin, ``omega`` (..., 3), rad/s)."""
        return self.tangents[-1]

    @property
    def jacobian(self) -> Array:
        """``dy/dx`` (for a spin, ``d omega / d xdot``) with the pose axis last, (..., *s, n)."""
        return np.moveaxis(self.tangents[:-1], 0, -1)

    def acceleration(self, xddot: ArrayLike) -> Array:
        """``d2y/dt2 = J xddot + bias`` (for a spin, the angular acceleration ``alpha``) for pose
        accelerations ``xddot`` (..., n)."""
        return contract(self.tangents[:-1], xddot, self.bias.ndim) + self.bias


@dataclass(frozen=True, eq=False)
class Jet(_Motion):
    """A batched quantity with its tangents along the pose directions and the rate, and its bias.

    ``value`` (..., *s); ``tangents`` (n + 1, ..., *s): ``J e_0 .. J e_{n-1}``, then ``J xdot``;
    ``bias`` (..., *s): ``d2y/dt2 - J xddot``.
    """

    value: Array
    tangents: Array
    bias: Array

    #: numpy defers to the jet's own operators (``array * jet`` is a jet, not an object array)
    __array_ufunc__ = None

    # ------------------------------------------------------------------ views
    @property
    def n(self) -> int:
        """Number of pose coordinates."""
        return self.tangents.shape[0] - 1

    @property
    def shape(self) -> tuple[int, ...]:
        return self.value.shape

    def reshape(self, shape: tuple[int, ...]) -> Jet:
        """The same jet with its value reshaped to ``shape`` (batch axes included)."""
        return Jet(
            self.value.reshape(shape),
            self.tangents.reshape((self.n + 1, *shape)),
            self.bias.reshape(shape),
        )

    def __getitem__(self, index) -> Jet:
        index = index if isinstance(index, tuple) else (index,)
        return Jet(self.value[index], self.tangents[(slice(None), *index)], self.bias[index])

    # ------------------------------------------------------------------ arithmetic
    def __add__(self, other) -> Jet:
        if isinstance(other, Jet):
            r = np.broadcast_shapes(self.shape, other.shape)
            return Jet(
                self.value + other.value,
                _pad(self, len(r)) + _pad(other, len(r)),
                self.bias + other.bias,
            )
        c = np.asarray(other, dtype=float)
        r = np.broadcast_shapes(self.shape, c.shape)
        value = self.value + c
        return Jet(
            value, np.broadcast_to(_pad(self, len(r)), (self.n + 1, *r)), _grow(self.bias, r)
        )

    __radd__ = __add__

    def __neg__(self) -> Jet:
        return Jet(-self.value, -self.tangents, -self.bias)

    def __sub__(self, other) -> Jet:
        return self + (-other)

    def __rsub__(self, other) -> Jet:
        return (-self) + other

    def __mul__(self, other) -> Jet:
        return _bilinear(np.multiply, self, other)

    __rmul__ = __mul__

    def __truediv__(self, other) -> Jet:
        if isinstance(other, Jet):
            return self * other.__rtruediv__(1.0)
        return self * (1.0 / np.asarray(other, dtype=float))

    def __rtruediv__(self, other) -> Jet:
        return _unary(self, lambda v: 1.0 / v, lambda v: -1.0 / v**2, lambda v: 2.0 / v**3) * other


@dataclass(frozen=True, eq=False)
class Spin(_Motion):
    """Angular velocity of a batch of bodies: ``tangents`` (n + 1, ..., 3) (``J_w e_k``, then the
    angular velocity ``omega``) and ``bias`` (..., 3) (``alpha = J_w xddot + bias``)."""

    tangents: Array
    bias: Array


# ---------------------------------------------------------------------------------------- making
def numeric(a: ArrayLike) -> Array:
    """``a`` as an array of floats, or as it is when it holds the symbols of a program being
    recorded (:mod:`parakin.dynamics.program`: object arrays)."""
    a = np.asarray(a)
    return a if a.dtype == object else a.astype(float, copy=False)


def variable(x: ArrayLike, xdot: ArrayLike) -> Jet:
    """The pose itself: value ``x`` (..., n), tangents the unit directions and ``xdot``, no bias."""
    x = numeric(x)
    xdot = np.broadcast_to(numeric(xdot), x.shape)
    n = x.shape[-1]
    eye = np.broadcast_to(np.eye(n).reshape((n,) + (1,) * (x.ndim - 1) + (n,)), (n, *x.shape))
    return Jet(x, np.concatenate([eye, xdot[None]], axis=0), np.zeros(x.shape))


def constant_like(value: ArrayLike, like: Jet) -> Jet:
    """A constant (zero tangents and bias) with ``like``'s number of directions."""
    v = np.asarray(value, dtype=float)
    return Jet(v, np.zeros((like.n + 1, *v.shape)), np.zeros(v.shape))


# ---------------------------------------------------------------------------------------- rules
def _grow(a: Array, shape: tuple[int, ...]) -> Array:
    return np.broadcast_to(a, shape)


def _pad(a: Jet, ndim: int) -> Array:
    """``a.tangents`` with singleton axes after the direction axis, so that it broadcasts against
    values of ``ndim`` dimensions (numpy aligns shapes from the right)."""
    t = a.tangents
    extra = ndim - a.value.ndim
    return t.reshape((t.shape[0],) + (1,) * extra + t.shape[1:]) if extra > 0 else t


def _bilinear(f: Callable, a, b, cores: tuple[int, int] = (0, 0)) -> Jet:
    """``f(a, b)`` for ``f`` bilinear (product, dot, cross, matrix product): value, tangents
    ``f(a', b) + f(a, b')`` and bias ``f(a_b, b) + 2 f(a_dot, b_dot) + f(a, b_b)``. ``cores``:
    how many trailing axes of each operand ``f`` consumes as a vector or matrix (the others are
    batch axes, aligned from the right when the tangents' direction axis is padded)."""
    ja, jb = isinstance(a, Jet), isinstance(b, Jet)
    if not (ja or jb):
        raise TypeError("a jet operation needs at least one Jet")
    av = a.value if ja else np.asarray(a, dtype=float)
    bv = b.value if jb else np.asarray(b, dtype=float)
    value = f(av, bv)
    batch = max(av.ndim - cores[0], bv.ndim - cores[1])
    if ja and jb:
        tangents = f(_pad(a, batch + cores[0]), bv) + f(av, _pad(b, batch + cores[1]))
        bias = f(a.bias, bv) + f(av, b.bias) + 2.0 * f(a.rate, b.rate)
    elif ja:
        tangents, bias = f(_pad(a, batch + cores[0]), bv), f(a.bias, bv)
    else:
        tangents, bias = f(av, _pad(b, batch + cores[1])), f(av, b.bias)
    return Jet(value, tangents, np.broadcast_to(bias, value.shape))


def _unary(a: Jet, f: Callable, df: Callable, d2f: Callable) -> Jet:
    """``f(a)`` elementwise: tangents ``f'(a) a'``, bias ``f'(a) a_b + f''(a) a_dot^2``."""
    v = a.value
    d1 = df(v)
    return Jet(f(v), d1 * a.tangents, d1 * a.bias + d2f(v) * a.rate**2)


# ---------------------------------------------------------------------------------------- functions
def vdot(u: Array, v: Array) -> Array:
    """``u . v`` over the last axis of plain arrays (broadcast)."""
    return _dot(u, v)


def vcross(u: Array, v: Array) -> Array:
    """``u x v`` over the last axis of plain arrays of 3-vectors (broadcast)."""
    return _cross(u, v)


def vmatvec(m: Array, v: Array) -> Array:
    """``m @ v`` for plain arrays of 3x3 matrices and 3-vectors (broadcast)."""
    return _matvec(m, v)


def _dot(u: Array, v: Array) -> Array:
    # written out for 3-vectors: several times faster than a reduction over a short axis
    if u.shape[-1] == 3 and v.shape[-1] == 3:
        return u[..., 0] * v[..., 0] + u[..., 1] * v[..., 1] + u[..., 2] * v[..., 2]
    return np.sum(u * v, axis=-1)


def _cross(u: Array, v: Array) -> Array:
    u0, u1, u2, v0, v1, v2 = u[..., 0], u[..., 1], u[..., 2], v[..., 0], v[..., 1], v[..., 2]
    return np.stack([u1 * v2 - u2 * v1, u2 * v0 - u0 * v2, u0 * v1 - u1 * v0], axis=-1)


def dot(a, b) -> Jet:
    """``a . b`` over the last axis."""
    return _bilinear(_dot, a, b, (1, 1))


def cross(a, b) -> Jet:
    """``a x b`` over the last axis (3-vectors)."""
    return _bilinear(_cross, a, b, (1, 1))


def sqrt(a: Jet) -> Jet:
    """Elementwise square root (``a > 0``)."""
    return _unary(a, np.sqrt, lambda v: 0.5 / np.sqrt(v), lambda v: -0.25 / v**1.5)


def sin(a: Jet) -> Jet:
    return _unary(a, np.sin, np.cos, lambda v: -np.sin(v))


def cos(a: Jet) -> Jet:
    return _unary(a, np.cos, lambda v: -np.sin(v), lambda v: -np.cos(v))


def norm(a: Jet) -> Jet:
    """Euclidean norm over the last axis (nonzero vectors)."""
    return sqrt(dot(a, a))


def normalize(a: Jet) -> tuple[Jet, Jet]:
    """``(a / |a|, |a|)``."""
    length = norm(a)
    return a / length[..., None], length


def _matvec(m: Array, v: Array) -> Array:
    return m[..., 0] * v[..., None, 0] + m[..., 1] * v[..., None, 1] + m[..., 2] * v[..., None, 2]


def matvec(m, v) -> Jet:
    """``m @ v`` for matrices (..., 3, 3) and vectors (..., 3), either a jet or a constant."""
    return _bilinear(_matvec, m, v, (2, 1))


def matmul(a, b) -> Jet:
    """``a @ b`` for stacks of matrices."""
    return _bilinear(np.matmul, a, b, (2, 2))


def transpose(a: Jet) -> Jet:
    """Swap the last two axes."""
    return Jet(
        np.swapaxes(a.value, -1, -2), np.swapaxes(a.tangents, -1, -2), np.swapaxes(a.bias, -1, -2)
    )


def stack(parts: Sequence[Jet | ArrayLike], axis: int = -1) -> Jet:
    """``np.stack`` of jets (constants allowed) along ``axis`` (counted in the value's axes)."""
    like = next(p for p in parts if isinstance(p, Jet))
    jets = [p if isinstance(p, Jet) else constant_like(p, like) for p in parts]
    shape = np.broadcast_shapes(*(j.shape for j in jets))
    full = [j + np.zeros(shape) if j.shape != shape else j for j in jets]
    ax = axis if axis >= 0 else len(shape) + 1 + axis
    return Jet(
        np.stack([j.value for j in full], axis=ax),
        np.stack([j.tangents for j in full], axis=ax + 1),
        np.stack([j.bias for j in full], axis=ax),
    )


def contract(tangents: Array, xddot: ArrayLike, ndim: int) -> Array:
    """``sum_k tangents[k] xddot[..., k]`` for ``tangents`` (n, ..., *s) of a value of ``ndim`` axes
    and ``xddot`` (..., n) (the batch axes of ``xddot`` lead those of the value)."""
    xdd = np.moveaxis(numeric(xddot), -1, 0)
    batch = xdd.ndim - 1
    xdd = xdd.reshape(xdd.shape + (1,) * (ndim - batch))
    return np.einsum("k...,k...->...", tangents, xdd)


# ---------------------------------------------------------------------------------------- spin
def _vee_antisymmetric(m: Array) -> Array:
    """The axial vector of the antisymmetric part of ``m`` (..., 3, 3)."""
    return 0.5 * np.stack(
        [m[..., 2, 1] - m[..., 1, 2], m[..., 0, 2] - m[..., 2, 0], m[..., 1, 0] - m[..., 0, 1]],
        axis=-1,
    )


def spin_of_rotation(rotation: Jet) -> Spin:
    """Angular velocity of a body whose orientation is the rotation jet ``R`` (..., 3, 3):
    ``omega = vee(Rdot R^T)``; ``alpha = vee(Rddot R^T)`` (``Rdot Rdot^T`` is symmetric), so the
    tangents are ``vee(R' R^T)`` and the bias ``vee(b_R R^T)``."""
    rt = np.swapaxes(rotation.value, -1, -2)
    return Spin(_vee_antisymmetric(rotation.tangents @ rt), _vee_antisymmetric(rotation.bias @ rt))


def spin_of_axis(axis: Jet) -> Spin:
    """Angular velocity of an axisymmetric body along the unit ``axis`` (..., 3) that does not spin
    about it: ``omega = n x ndot`` and ``alpha = n x nddot`` (``ndot x ndot = 0``)."""
    n = axis.value
    return Spin(_cross(n, axis.tangents), _cross(n, axis.bias))


# ---------------------------------------------------------------------------------------- rotations
def _elementary(angle: Jet, i: int, j: int) -> Jet:
    """Rotation by ``angle`` (...,) in the plane of axes ``i``, ``j`` (right-handed about the third)."""
    c, s = cos(angle), sin(angle)
    one, zero = (
        constant_like(np.ones(angle.shape), angle),
        constant_like(np.zeros(angle.shape), angle),
    )
    rows = [[one, zero, zero], [zero, one, zero], [zero, zero, one]]
    rows[i][i], rows[i][j], rows[j][i], rows[j][j] = c, -s, s, c
    return stack([stack(row, axis=-1) for row in rows], axis=-2)


def rot_x(angle: Jet) -> Jet:
    """Rotation about x by ``angle`` (...,), as a jet (..., 3, 3)."""
    return _elementary(angle, 1, 2)


def rot_y(angle: Jet) -> Jet:
    """Rotation about y by ``angle`` (...,), as a jet (..., 3, 3)."""
    return _elementary(angle, 2, 0)


def rot_z(angle: Jet) -> Jet:
    """Rotation about z by ``angle`` (...,), as a jet (..., 3, 3)."""
    return _elementary(angle, 0, 1)


def _skew_times(w: Array, r: Array) -> Array:
    """``[w]x r`` for vectors (..., 3) and matrices (..., 3, 3): each column crossed with ``w``."""
    return np.swapaxes(_cross(w[..., None, :], np.swapaxes(r, -1, -2)), -1, -2)


def rotations(angles: Sequence[Jet], axes: str) -> Jet:
    """``R = R_{axes[0]}(angles[0]) R_{axes[1]}(angles[1]) ...`` (e.g. ``axes="zyx"``: Z-Y-X Euler
    angles) as a jet, from the world axes ``u_k`` of the successive turns rather than by products
    of matrix jets: ``dR = [sum_k u_k da_k]x R``, and ``Rddot = [alpha]x R + [omega]x [omega]x R``
    with ``alpha = sum_k u_k a_k'' + (omega_{<k} x u_k) a_k'``."""
    elementary = {"x": (1, 2), "y": (2, 0), "z": (0, 1)}
    like = angles[0]
    shape = like.shape
    partial = np.broadcast_to(np.eye(3), shape + (3, 3))
    w = np.zeros((like.n + 1, *shape, 3))  # sum_k u_k (tangent of a_k)
    bias_alpha = np.zeros(shape + (3,))
    omega_before = np.zeros(shape + (3,))
    for angle, name in zip(angles, axes):
        i = "xyz".index(name)
        u = partial[..., :, i]
        rate = angle.rate[..., None]
        w = w + u * angle.tangents[..., None]
        bias_alpha = bias_alpha + u * angle.bias[..., None] + _cross(omega_before, u) * rate
        omega_before = omega_before + u * rate
        partial = partial @ plane_rotation(angle.value, *elementary[name])
    omega = w[-1]
    bias = _skew_times(bias_alpha, partial) + _skew_times(omega, _skew_times(omega, partial))
    return Jet(partial, _skew_times(w, partial), bias)


def euler_zyx(a: Jet, b: Jet, c: Jet) -> Jet:
    """``Rz(a) Ry(b) Rx(c)`` (the Z-Y-X Euler angles of :func:`parakin.geometry.euler_zyx`)."""
    return rotations([a, b, c], "zyx")


def skew(v: Jet) -> Jet:
    """The cross-product matrix of ``v`` (..., 3) as a jet (..., 3, 3): ``skew(v) u = v x u``."""
    zero = constant_like(np.zeros(v.shape[:-1]), v)
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    return stack([stack([zero, -z, y]), stack([z, zero, -x]), stack([-y, x, zero])], axis=-2)
