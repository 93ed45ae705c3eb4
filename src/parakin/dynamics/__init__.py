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
only (they import no mechanism), so the order of imports here keeps the graph acyclic.
"""

from parakin.dynamics.inverse import (  # noqa: I001 (after the modules the mechanisms import)
    InverseDynamics,
    energy,
    generalized_forces,
    inverse_dynamics,
    mass_matrix,
    state,
)
from parakin.dynamics.jet import Jet, Spin
from parakin.dynamics.model import Bodies, BodyGroup, Closure, MassModel, RigidBody

__all__ = [
    "Jet",
    "Spin",
    "Bodies",
    "BodyGroup",
    "Closure",
    "MassModel",
    "RigidBody",
    "InverseDynamics",
    "energy",
    "generalized_forces",
    "inverse_dynamics",
    "mass_matrix",
    "state",
]
