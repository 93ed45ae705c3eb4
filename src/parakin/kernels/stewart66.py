"""Kernels of the general 6-6 Gough-Stewart platform (:class:`parakin.mechanisms.Stewart66`).

The leg equations are the 3-6 platform's (:mod:`parakin.kernels.stewart36`: the same ZYX Euler
angles and origin as pose, the squared residual ``|T P_i + O - B_i|^2 - L_i^2``, its analytic
Jacobian, leg lengths as IK, every finite pose in the domain) over the six platform points
``p[0:18]`` and the six base points ``p[18:36]``; only the assembly test differs: the 6-6 tells no
assembly modes apart (all 40 are answers), where the 3-6 asks for the one above its base.
"""

from __future__ import annotations

from parakin.kernels._math import kernel
from parakin.kernels.frames import leg_vector, rotation_zyx
from parakin.kernels.stewart36 import _leg, _rotation, ik, in_domain, jacobian, residual

__all__ = [
    "_leg",
    "_rotation",
    "ik",
    "in_domain",
    "jacobian",
    "leg_vector",
    "on_assembly",
    "residual",
    "rotation_zyx",
]


@kernel
def on_assembly(p, x, q):
    """Every assembly (the caller checks finiteness)."""
    return x[0] == x[0]
