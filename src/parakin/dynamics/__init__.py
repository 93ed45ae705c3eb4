"""Dynamics of any mechanism that declares its bodies and masses (issue 27; docs/dynamics.md).

* :mod:`parakin.dynamics.jet`: exact velocity and acceleration maps of any formula of the pose;
* :mod:`parakin.dynamics.model`: inertia as data (:class:`RigidBody`, :class:`MassModel`) and the
  description of a mechanism's bodies (:class:`Bodies`), with builders for common legs;
* :mod:`parakin.dynamics.inverse`: actuator forces by virtual work, redundant drives included;
* :mod:`parakin.dynamics.forward`: the equations of motion, accelerations from forces, and a
  simulator;
* :mod:`parakin.dynamics.program`: each mechanism's dynamics recorded once as a straight-line
  program and replayed compiled (:mod:`parakin.dynamics._kernels`, numba, imported when first
  needed), the same arithmetic as the numpy functions it comes from;
* :mod:`parakin.dynamics.trajectory`: trajectories and the power-balance check;
* :mod:`parakin.dynamics.mujoco`, :mod:`parakin.dynamics.pinocchio`: the two independent checks,
  models generated from the same description.

The mechanism modules import :mod:`~parakin.dynamics.jet` and :mod:`~parakin.dynamics.model`
only (they import no mechanism); the names below are imported from their modules on first use.
"""

#: the public names of each module, imported on first use (PEP 562), so that a mechanism module
#: importing :mod:`~parakin.dynamics.jet` does not pay for the rest (a solve on the command line
#: needs none of it)
_JET = ("Jet", "Spin")
_MODEL = ("Bodies", "BodyGroup", "Closure", "MassModel", "RigidBody")
_INVERSE = (
    "InverseDynamics",
    "energy",
    "generalized_forces",
    "inverse_dynamics",
    "mass_matrix",
    "state",
)


def __getattr__(name: str):
    if name in _JET:
        from parakin.dynamics import jet as module
    elif name in _MODEL:
        from parakin.dynamics import model as module
    elif name in _INVERSE:
        from parakin.dynamics import inverse as module
    else:
        raise AttributeError(f"module 'parakin.dynamics' has no attribute {name!r}")
    return getattr(module, name)


def __dir__() -> list[str]:
    return sorted({*globals(), *_JET, *_MODEL, *_INVERSE})


__all__ = [*_JET, *_MODEL, *_INVERSE]
