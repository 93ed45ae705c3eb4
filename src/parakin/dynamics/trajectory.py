"""Trajectories in pose coordinates, and the power-balance check of any dynamics.

A trajectory is anything with ``state(t) -> (pose, rate, acceleration)`` (each (..., n) for times
``t`` (...)), e.g. :class:`Harmonic` (every pose coordinate a sine about a centre, the documented
test and figure trajectory), :class:`Sampled` (a table of poses, differentiated by a spline) or the
3-P(4S)'s :class:`parakin.mechanisms.p3p4s_dynamics.SineMotion`.

:func:`power_balance` checks actuator forces against energy: along a trajectory,
``f . qdot = dT/dt + dV/dt - P_ext`` where ``T`` and ``V`` are the kinetic and potential energy of
every body computed from positions and velocities alone, and ``dT/dt`` is taken by a sixth-order
central difference in time, so the accelerations of the inverse dynamics are checked against the
time derivative of the velocities.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike

from parakin.dynamics.inverse import energy, inverse_dynamics, state
from parakin.dynamics.model import MassModel
from parakin.errors import ShapeError
from parakin.mechanisms.base import Array, Mechanism, as_batch

__all__ = [
    "Trajectory",
    "Harmonic",
    "Sampled",
    "PowerBalance",
    "time_derivative",
    "power_balance",
    "read_trajectory",
]


class Trajectory(Protocol):
    def state(self, t: ArrayLike) -> tuple[Array, Array, Array]:
        """``(pose, rate, acceleration)`` at times ``t`` (...,), each (..., n)."""
        ...


@dataclass(frozen=True)
class Harmonic:
    """``x_k(t) = centre_k + amplitude_k sin(2 pi f_k t + phase_k)``: every pose coordinate a sine,
    derivatives exact. ``frequency`` (Hz) and ``phase`` (rad) broadcast to the pose size."""

    centre: tuple
    amplitude: tuple
    frequency: tuple
    phase: tuple = (0.0,)

    def __post_init__(self) -> None:
        c = np.asarray(self.centre, dtype=float)
        arrays = {}
        for key in ("amplitude", "frequency", "phase"):
            try:
                arrays[key] = np.broadcast_to(np.asarray(getattr(self, key), dtype=float), c.shape)
            except ValueError:
                raise ShapeError(
                    f"{key} {np.shape(getattr(self, key))} does not fit a pose {c.shape}"
                ) from None
        for key, a in [("centre", c), *arrays.items()]:
            if c.ndim != 1 or not np.all(np.isfinite(a)):
                raise ValueError(
                    f"{key} = {getattr(self, key)!r} must be finite, one value per pose coordinate"
                )
        if np.any(arrays["frequency"] < 0):
            raise ValueError(f"frequency = {self.frequency!r} Hz must be >= 0")
        object.__setattr__(self, "centre", tuple(c.tolist()))
        for key, a in arrays.items():
            object.__setattr__(self, key, tuple(a.tolist()))

    @classmethod
    def around(cls, mech: Mechanism, fraction: float, frequency: float) -> Harmonic:
        """About ``mech.home()``, coordinate k with amplitude ``fraction`` of half the width of
        :meth:`Mechanism.pose_bounds` and frequency ``frequency (k + 1)``, phase ``k`` rad: every
        coordinate moves, with different frequencies, so no two are in step."""
        lo, hi = mech.pose_bounds()
        k = np.arange(mech.n_pose)
        return cls(
            tuple(mech.home()),
            tuple(fraction * 0.5 * (hi - lo)),
            tuple(frequency * (k + 1.0)),
            tuple(k * 1.0),
        )

    @property
    def period(self) -> float:
        """The common period ``1 / min(f > 0)`` when the frequencies are multiples of it (s)."""
        f = np.asarray(self.frequency)
        return float(1.0 / np.min(f[f > 0])) if np.any(f > 0) else np.inf

    def state(self, t: ArrayLike) -> tuple[Array, Array, Array]:
        t = np.asarray(t, dtype=float)[..., None]
        if not np.isfinite(t).all():
            raise ValueError("time samples t must be finite")
        centre, amp, w, phase = self._arrays
        arg = w * t + phase
        s, c = np.sin(arg), np.cos(arg)
        return centre + amp * s, amp * w * c, -amp * w**2 * s

    @functools.cached_property
    def _arrays(self) -> tuple[Array, Array, Array, Array]:
        """Centre, amplitude, angular frequency and phase as arrays (made once: the simulator
        asks for the state at every stage)."""
        return (
            np.asarray(self.centre),
            np.asarray(self.amplitude),
            2 * np.pi * np.asarray(self.frequency),
            np.asarray(self.phase),
        )


@dataclass(frozen=True)
class Sampled:
    """A trajectory given as poses at times (a table): a cubic spline through the samples
    (``scipy.interpolate.CubicSpline``, not-a-knot ends) gives rates and accelerations, unless the
    table gives them (``rate``, ``acceleration``, each (k, n)), which are then interpolated."""

    t: Array
    pose: Array
    rate: Array | None = None
    acceleration: Array | None = None

    def state(self, t: ArrayLike) -> tuple[Array, Array, Array]:
        tt = np.asarray(t, dtype=float)
        if self.rate is not None and self.acceleration is not None and np.array_equal(tt, self.t):
            # the table's own samples, all given: nothing to interpolate (and no scipy to import)
            return self.pose.copy(), self.rate.copy(), self.acceleration.copy()
        from scipy.interpolate import CubicSpline

        spline = CubicSpline(self.t, self.pose, axis=0)
        x = spline(tt)
        v = spline(tt, 1) if self.rate is None else CubicSpline(self.t, self.rate, axis=0)(tt)
        a = (
            spline(tt, 2)
            if self.acceleration is None
            else CubicSpline(self.t, self.acceleration, axis=0)(tt)
        )
        return x, v, a


#: largest trajectory file (about 10^6 samples of a six-coordinate pose)
MAX_TRAJECTORY_BYTES = 1 << 27


def read_trajectory(path: str | Path, mech: Mechanism) -> Sampled:
    """A :class:`Sampled` trajectory from a CSV with a column ``t`` (s) and one column per pose
    coordinate (``mech.pose_names``, SI units), optionally ``d_<name>`` rates and ``dd_<name>``
    accelerations. Read within bounds (a regular UTF-8 file of at most
    :data:`MAX_TRAJECTORY_BYTES`); every error is one ValueError line that names the file: not a
    CSV, a missing column, a value that is not a finite number, a bad time axis."""
    import io

    import pandas as pd

    from parakin.io import read_text

    where = f"trajectory {path}"
    text = read_text(path, "trajectory", limit=MAX_TRAJECTORY_BYTES)
    try:
        frame = pd.read_csv(io.StringIO(text))
    except (pd.errors.ParserError, pd.errors.EmptyDataError, ValueError) as exc:
        raise ValueError(f"{where}: not a CSV table ({' '.join(str(exc).split())[:120]})") from None
    names = list(mech.pose_names)
    missing = [c for c in ["t", *names] if c not in frame.columns]
    if missing:
        raise ValueError(
            f"{where}: missing column(s) {missing}; a {mech.name} trajectory needs t, "
            f"{', '.join(names)}"
        )

    def numbers(cols: list[str]) -> Array:
        """The columns ``cols`` as floats (k, len(cols)), every value finite, or a ValueError
        naming the file, the line and the column."""
        values = frame[cols].apply(pd.to_numeric, errors="coerce").to_numpy(float)
        bad = ~np.isfinite(values)
        if bad.any():
            row, col = (int(v) for v in np.argwhere(bad)[0])
            raise ValueError(
                f"{where}, line {row + 2}: {cols[col]} = {frame[cols[col]].iloc[row]!r} is not "
                "a finite number"
            )
        return values

    t = numbers(["t"])[:, 0]
    if len(t) < 4 or not np.all(np.diff(t) > 0):
        raise ValueError(f"{where}: column t must hold at least 4 strictly increasing times")

    def columns(prefix: str) -> Array | None:
        cols = [prefix + n for n in names]
        if all(c in frame.columns for c in cols):
            return as_batch(numbers(cols), len(names), prefix + "pose")
        return None

    pose = as_batch(numbers(names), len(names), "pose")
    return Sampled(t, pose, columns("d_"), columns("dd_"))


#: central-difference weights of the first derivative, O(h^6): offsets -3..3
_D1_ORDER6 = np.array([-1.0, 9.0, -45.0, 0.0, 45.0, -9.0, 1.0]) / 60.0


def time_derivative(f: Callable, t: ArrayLike, step: float) -> Array:
    """``df/dt`` at ``t`` by the 6th-order central difference of ``f(t + k h)``, ``k = -3..3``.

    ``f`` maps a time array (...,) to an array (..., *rest); truncation error
    ``~ (omega h)^6 / 140`` relative for a harmonic signal of angular frequency omega.
    """
    if not (np.isfinite(step) and step > 0):
        raise ValueError(f"step = {step!r} s must be finite and > 0")
    t = np.asarray(t, dtype=float)
    out = 0.0
    for k, wk in zip(range(-3, 4), _D1_ORDER6):
        if wk:
            out = out + wk * f(t + k * step)
    return out / step


@dataclass(frozen=True)
class PowerBalance:
    """``sum_i f_i qdot_i`` against ``dE/dt`` along a trajectory (W)."""

    t: Array
    power: Array  #: actuator power sum_i f_i qdot_i (W)
    dEdt: Array  #: time derivative of the total energy of every body, less external power (W)

    @property
    def residual(self) -> Array:
        return self.power - self.dEdt

    @property
    def relative_error(self) -> float:
        """``max |power - dE/dt| / max |dE/dt|``."""
        scale = float(np.max(np.abs(self.dEdt)))
        if scale == 0:
            raise ValueError("dE/dt vanishes along the whole trajectory: relative error undefined")
        return float(np.max(np.abs(self.residual)) / scale)


def power_balance(
    mech: Mechanism,
    trajectory: Trajectory,
    t: ArrayLike,
    step: float,
    *,
    mass: MassModel | None = None,
    wrench: ArrayLike | None = None,
    active: ArrayLike | None = None,
) -> PowerBalance:
    """Actuator power of :func:`parakin.dynamics.inverse.inverse_dynamics` against the time
    derivative of the total energy (kinetic + potential, from positions and velocities only),
    less the power of a constant external ``wrench`` on the platform, at times ``t``; ``step``
    (s) of the sixth-order difference."""
    t = np.asarray(t, dtype=float)
    x, v, a = trajectory.state(t)
    res = inverse_dynamics(mech, x, v, a, mass=mass, wrench=wrench, active=active)

    def total(tt: Array) -> Array:
        xx, vv, _ = trajectory.state(tt)
        kinetic, potential = energy(state(mech, xx, vv, mass))
        return kinetic + potential

    dedt = time_derivative(total, t, step)
    if wrench is not None:
        p = state(mech, x, v, mass).platform()
        w = as_batch(wrench, 6, "wrench")
        ext = np.sum(p.centre.rate[..., 0, :] * w[..., :3], -1) + np.sum(
            p.spin.rate[..., 0, :] * w[..., 3:], -1
        )
        dedt = dedt - ext
    return PowerBalance(t, res.power, dedt)
