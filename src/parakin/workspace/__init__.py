"""Workspaces and singularity loci of any mechanism (issue 44; method: docs/workspace.md).

A :class:`Region` (:func:`make_region`) says which pose coordinates span the workspace, the given
values of the others, the box, the joint limits, the orientation box, the dexterity bound and the
legs' clearance; then

* :func:`classify` -- which poses of a batch are in the constant-orientation and dexterous
  workspaces (compiled on every core for large batches, :mod:`parakin.workspace.compiled`);
* :func:`volumes` -- Monte-Carlo volumes with their standard errors (constant-orientation,
  dexterous, reachable), :func:`fit_box` the box that holds the workspace;
* :func:`certify` -- interval-analysis inner and outer bounds (:mod:`parakin.workspace.interval`);
* :func:`boundary_rays` -- the boundary along rays, bisected to 1e-9, with the active constraint;
* :func:`locate` -- singular points (det A and det B sign changes, the IK domain's edges) on a
  grid, bisected to 1e-9 and verified by the smallest singular value;
* :func:`sample_reachable` -- reachable poses drawn from a box (rejection sampling).

Generic: only the :class:`~parakin.mechanisms.base.Mechanism` protocol (and the optional hooks
named in :mod:`parakin.workspace.region` and :mod:`parakin.workspace.legs`) is used.
"""

from parakin.workspace.boundary import (
    Rays,
    boundary_rays,
    fibonacci_directions,
    ray_volume,
    sphere_grid,
)
from parakin.workspace.classify import (
    Classes,
    classify,
    condition_numbers,
    jacobian_dets,
    joints_of,
)
from parakin.workspace.interval import Bounds, certify
from parakin.workspace.legs import leg_segments, min_leg_distance, segment_distance
from parakin.workspace.region import (
    DEFAULT_COND_MAX,
    DEFAULT_STROKE,
    Region,
    declared_joint_limits,
    default_axes,
    make_region,
)
from parakin.workspace.sampling import sample_reachable
from parakin.workspace.singular import LOCATE_TOL, VERIFY_REL, Loci, locate, plane_grid
from parakin.workspace.volume import KINDS, Estimate, fit_box, grid_points, volumes

__all__ = [
    "DEFAULT_COND_MAX",
    "DEFAULT_STROKE",
    "KINDS",
    "LOCATE_TOL",
    "VERIFY_REL",
    "Bounds",
    "Classes",
    "Estimate",
    "Loci",
    "Rays",
    "Region",
    "boundary_rays",
    "certify",
    "classify",
    "condition_numbers",
    "declared_joint_limits",
    "default_axes",
    "fibonacci_directions",
    "fit_box",
    "grid_points",
    "jacobian_dets",
    "joints_of",
    "leg_segments",
    "locate",
    "make_region",
    "min_leg_distance",
    "plane_grid",
    "ray_volume",
    "sample_reachable",
    "segment_distance",
    "sphere_grid",
    "volumes",
]
