"""The worked example of docs/kernels.md: one-source kernels of the toy two-leg mechanism of
``toy_study.py`` (a point (x, y) held by two telescopic legs from pivots at (-a, 0) and (a, 0)).
Exercised by ``tests/test_kernels.py::test_worked_example_of_the_docs``."""

from parakin.kernels._math import kernel, nan, sqrt, where


@kernel
def _legs(p, x):
    """The two leg vectors' components from the pivots ``(-a, 0)``, ``(a, 0)``; ``p = (a,)``."""
    return x[0] + p[0], x[0] - p[0], x[1]


@kernel
def residual(p, x, q, out):
    """Leg lengths minus the joints."""
    u, v, y = _legs(p, x)
    out[0] = sqrt(u * u + y * y) - q[0]
    out[1] = sqrt(v * v + y * y) - q[1]


@kernel
def jacobian(p, x, q, out):
    """``d residual / d (x, y)``: the unit leg vectors."""
    u, v, y = _legs(p, x)
    n1, n2 = sqrt(u * u + y * y), sqrt(v * v + y * y)
    out[0, 0], out[0, 1] = u / n1, y / n1
    out[1, 0], out[1, 1] = v / n2, y / n2


@kernel
def ik(p, x, out):
    """Leg lengths; False (and NaN) on the base line ``y <= 0`` (below: the mirror assembly)."""
    u, v, y = _legs(p, x)
    ok = y > 0
    out[0] = where(ok, sqrt(u * u + y * y), nan)
    out[1] = where(ok, sqrt(v * v + y * y), nan)
    return ok


@kernel
def in_domain(p, x):
    """Above the base line."""
    return x[1] > 0


@kernel
def on_assembly(p, x, q):
    """Every pose of the domain is the working assembly."""
    return x[1] > 0
