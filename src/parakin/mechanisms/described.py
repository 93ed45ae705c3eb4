"""A mechanism is a file: any leg-driven parallel mechanism described in YAML or JSON.

:func:`from_file` reads a description such as::

    name: delta
    platform: translational        # spatial (x y z + 3 angles) | translational (x y z) | planar (x y phi)
    home: [0.0, 0.0, -0.9]         # the default start of numeric FK (a reachable, regular pose)
    legs:
      - type: crank-rod            # length | slider-rod | crank-rod
        base: [0.2, 0.0, 0.0]      # base anchor: leg base, slider origin or crank centre
        axis: [0.0, 1.0, 0.0]      # crank axis or slider direction (not for length legs)
        zero: [1.0, 0.0, 0.0]      # crank's zero-angle direction (crank-rod)
        crank: 0.25                # crank radius (crank-rod)
        rod: 0.6                   # rod length (slider-rod, crank-rod)
        platform: [0.05, 0.0, 0.0] # anchor in the platform frame
        branch: 1                  # which of the leg's two IK solutions (slider-rod, crank-rod)
        limits: [-1.0, 2.0]        # optional joint limits

and returns a :class:`Described` mechanism: closed-form IK on each leg's branch, the analytic
Jacobians, every FK solver compiled through the one generic kernel :mod:`parakin.kernels.legs`
(the leg types and their numbers are its parameters: no code per mechanism), all real assemblies
(:meth:`Described.fk_all`: exact for translational and planar platforms, by the certified 6-6
homotopy of :class:`parakin.mechanisms.stewart66.Stewart66` for spatial ones), the near-singular
flag of the solvers, drawings (:meth:`Described.skeleton`) and, where the file declares masses,
dynamics. docs/mechanism_file.md is the user's guide: schema, conventions, branches, limits.

Joints: a length leg's length (m), a slider's position along its unit axis from the base anchor
(m), a crank's angle right-handed about its axis from ``zero`` (rad, in ``(-pi, pi]``).
"""

from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass
from functools import cached_property
from types import ModuleType
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from parakin.geometry import euler_zyx
from parakin.kernels import Kernel, evaluate
from parakin.kernels import legs as kernels
from parakin.mechanisms.base import (
    Array,
    Mechanism,
    Skeleton,
    as_batch,
    raise_first,
    wrap_angles,
)

if TYPE_CHECKING:  # the dynamics are imported where they are used: a solve does not need them
    from parakin.dynamics.jet import Jet
    from parakin.dynamics.model import Bodies, BodyGroup, Closure, MassModel, RigidBody

    #: what :meth:`Described.bodies` gathers by leg index: its joint as a jet and the body that
    #: drives it; the rods' lower ends: (leg, point as a jet, the body the rod hangs on)
    _Drives = dict[int, tuple[Jet, str]]
    _Ends = list[tuple[int, Jet, str]]

__all__ = [
    "LEG_TYPES",
    "PLATFORMS",
    "Described",
    "DescriptionError",
    "Leg",
    "from_dict",
    "from_file",
]

#: platform type -> (pose names, SI units): what the pose of each platform type is
PLATFORMS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "spatial": (("x", "y", "z", "alpha", "beta", "gamma"), ("m", "m", "m", "rad", "rad", "rad")),
    "translational": (("x", "y", "z"), ("m", "m", "m")),
    "planar": (("x", "y", "phi"), ("m", "m", "rad")),
}
#: leg type -> (fields it requires, fields it may have besides ``type``, ``limits``, ``name``)
LEG_TYPES: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "length": (("base", "platform"), ()),
    "slider-rod": (("base", "axis", "rod", "platform"), ("branch",)),
    "crank-rod": (("base", "axis", "zero", "crank", "rod", "platform"), ("branch",)),
}
#: the default branch of each leg type with two: -1 for both. A slider at ``b - sqrt(...)``: behind
#: the foot of its anchor along the axis, its rod leaning forward along the guide (the 3-P(4S)'s
#: working mode). A crank at ``phi - acos(...)``: turned back (about its axis) from the anchor's
#: direction; for a Delta whose positive angles turn the cranks down from the outward horizontal
#: (Williams' convention) this is the knee out
DEFAULT_BRANCH = {"slider-rod": -1, "crank-rod": -1}
#: the kernel's code of each leg and platform type
_LEG_CODE = {
    "length": kernels.LENGTH,
    "slider-rod": kernels.SLIDER_ROD,
    "crank-rod": kernels.CRANK_ROD,
}
_PLATFORM_CODE = {
    "spatial": kernels.SPATIAL,
    "translational": kernels.TRANSLATIONAL,
    "planar": kernels.PLANAR,
}
#: the largest description file read (bytes); its YAML is bounded as a config's
#: (:func:`parakin.config.check_bounds`: values, depth, self-reference)
MAX_FILE_BYTES = 1 << 20
#: largest magnitude of a length in a description (m): far beyond any real mechanism
LENGTH_LIMIT = 1e6
#: the body kinds each leg type moves (their masses under ``masses``)
_BODY_KINDS = {
    "length": ("cylinder", "piston"),
    "slider-rod": ("slider", "rod"),
    "crank-rod": ("crank", "rod"),
}
#: a slider's default inertia: a cube of this side (m); it only translates, so its inertia
#: never enters the dynamics
_SLIDER_SIDE = 0.05
#: Newton steps that polish each root of the planar polynomial on the closure equations
_POLISH = 8
#: samples of the planar polynomial (its coefficients, degree <= 4 each way, come exactly from 9)
_SAMPLES = 16


class DescriptionError(ValueError):
    """A description that cannot be read: one line naming the file, the field and what is wrong."""


@dataclass(frozen=True)
class Leg:
    """One leg of a described mechanism (SI units). ``axis`` and ``zero`` are unit vectors
    (``zero`` perpendicular to ``axis``); ``branch`` is +1 or -1 (0 for a length leg, which has
    one); ``limits`` the joint's ``(lower, upper)`` or None."""

    type: str
    base: tuple[float, float, float]
    platform: tuple[float, float, float]
    axis: tuple[float, float, float] | None = None
    zero: tuple[float, float, float] | None = None
    crank: float | None = None
    rod: float | None = None
    branch: int = 0
    limits: tuple[float, float] | None = None
    name: str = ""

    @property
    def joint_unit(self) -> str:
        return "rad" if self.type == "crank-rod" else "m"

    def to_dict(self) -> dict[str, Any]:
        """The leg as a description writes it (only the fields it has)."""
        out: dict[str, Any] = {"type": self.type}
        for key in ("name", "base", "axis", "zero", "crank", "rod", "platform", "branch", "limits"):
            value = getattr(self, key)
            if value is None or (key == "branch" and self.type == "length") or value == "":
                continue
            out[key] = list(value) if isinstance(value, tuple) else value
        return out


# ---------------------------------------------------------------------------- reading
def from_file(path: str | os.PathLike) -> Described:
    """The mechanism described in the YAML or JSON file ``path`` (see the module docstring and
    docs/mechanism_file.md). A malformed file raises :class:`DescriptionError`: one line that
    names the file and the field. The file is read within bounds: at most
    :data:`MAX_FILE_BYTES`, and its YAML (``yaml.safe_load``: no tags, no code) expanded within
    the bounds of :func:`parakin.config.check_bounds` (aliases counted, not expanded)."""
    import yaml

    from parakin.config import check_bounds
    from parakin.errors import ConfigError
    from parakin.io import read_text

    where = os.fspath(path)
    try:
        size = os.stat(where).st_size
    except OSError as exc:
        raise DescriptionError(f"{where}: cannot read the file ({exc.strerror or exc})") from None
    if size > MAX_FILE_BYTES:
        raise DescriptionError(f"{where}: {size} bytes, more than the limit {MAX_FILE_BYTES}")
    try:
        data = yaml.safe_load(read_text(where, "mechanism file"))
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        at = f" (line {mark.line + 1}, column {mark.column + 1})" if mark is not None else ""
        what = getattr(exc, "problem", None) or "not valid YAML or JSON"
        raise DescriptionError(f"{where}: not valid YAML or JSON{at}: {what}") from None
    except RecursionError:
        raise DescriptionError(f"{where}: nested too deeply") from None
    except ValueError as exc:  # not UTF-8 (read_text names the file)
        raise DescriptionError(str(exc)) from None
    try:
        check_bounds(data, where)
    except ConfigError as exc:
        raise DescriptionError(str(exc)) from None
    return from_dict(data, where)


def from_dict(data: Any, source: str = "description") -> Described:
    """The mechanism described by the mapping ``data`` (what :func:`from_file` reads); errors name
    ``source`` and the field."""
    if not isinstance(data, dict):
        raise DescriptionError(
            f"{source}: expected a mapping with name, platform and legs, got {type(data).__name__}"
        )
    known = {"name", "platform", "legs", "home", "bounds", "masses", "description"}
    _no_unknown(data, known, source, nested=False)
    name = data.get("name")
    if not isinstance(name, str) or not name.strip():
        raise DescriptionError(f"{source}: name: expected a non-empty text, got {name!r:.60}")
    platform = data.get("platform")
    if not isinstance(platform, str) or platform not in PLATFORMS:
        raise DescriptionError(
            f"{source}: platform: expected one of {', '.join(PLATFORMS)}, got {platform!r:.60}"
        )
    n_pose = len(PLATFORMS[platform][0])
    legs = data.get("legs")
    if not isinstance(legs, list):
        raise DescriptionError(f"{source}: legs: expected a list of legs, got {legs!r:.60}")
    if len(legs) != n_pose:
        raise DescriptionError(
            f"{source}: legs: a {platform} platform ({n_pose} pose coordinates) needs "
            f"{n_pose} legs, got {len(legs)}"
        )
    parsed = tuple(_leg(leg, f"{source}: legs[{i}]") for i, leg in enumerate(legs))
    units = PLATFORMS[platform][1]
    home = None
    if data.get("home") is not None:
        home = tuple(_numbers(data["home"], n_pose, f"{source}: home", units))
    bounds = None
    if data.get("bounds") is not None:
        bounds = _bounds(data["bounds"], n_pose, units, f"{source}: bounds")
    masses = None
    if data.get("masses") is not None:
        masses = _masses(data["masses"], parsed, f"{source}: masses")
    text = data.get("description", "")
    if not isinstance(text, str):
        raise DescriptionError(f"{source}: description: expected a text, got {text!r:.60}")
    try:
        return Described(
            name=name.strip(),
            platform=platform,
            legs=parsed,
            home_pose=home,
            bounds=bounds,
            masses=masses,
            description=text,
            source=source,
        )
    except DescriptionError:
        raise
    except ValueError as exc:
        raise DescriptionError(f"{source}: {exc}") from None


def _no_unknown(data: dict, known: set[str], where: str, nested: bool = True) -> None:
    """A DescriptionError naming the first field of ``data`` not in ``known``: ``where.field``
    (``where: field`` at the top level, where ``where`` is the file)."""
    unknown = sorted(str(k) for k in set(data) - known)
    if unknown:
        field = f"{where}.{unknown[0]}" if nested else f"{where}: {unknown[0]}"
        raise DescriptionError(f"{field}: unknown field (known: {', '.join(sorted(known))})")


def _number(value: Any, where: str, unit: str = "m") -> float:
    """A finite number, or a quantity text with a unit (``35deg``, ``120mm``) converted to SI."""
    from parakin.units import parse_quantity

    if isinstance(value, bool) or value is None:
        raise DescriptionError(f"{where}: expected a number, got {value!r:.60}")
    try:
        v = parse_quantity(value) if isinstance(value, str) else float(value)
    except (TypeError, ValueError):
        raise DescriptionError(f"{where}: expected a number ({unit}), got {value!r:.60}") from None
    if not math.isfinite(v) or abs(v) > LENGTH_LIMIT:
        raise DescriptionError(
            f"{where}: {value!r:.60} must be a finite number of magnitude <= {LENGTH_LIMIT:g}"
        )
    return v


def _numbers(
    value: Any, size: int, where: str, units: tuple[str, ...] | None = None
) -> list[float]:
    if not isinstance(value, (list, tuple)) or len(value) != size:
        raise DescriptionError(f"{where}: expected a list of {size} numbers, got {value!r:.60}")
    units = units or ("m",) * size
    return [_number(v, f"{where}[{k}]", units[k]) for k, v in enumerate(value)]


def _point(value: Any, where: str) -> tuple[float, float, float]:
    """A point of 3 coordinates (m); 2 are read as ``(x, y, 0)`` (planar mechanisms)."""
    if isinstance(value, (list, tuple)) and len(value) == 2:
        value = [*value, 0.0]
    x, y, z = _numbers(value, 3, where)
    return x, y, z


def _direction(value: Any, where: str) -> Array:
    v = np.array(_point(value, where))
    norm = float(np.linalg.norm(v))
    if not norm > 0:
        raise DescriptionError(f"{where}: a direction must not be zero")
    return v / norm


def _positive(value: Any, where: str) -> float:
    v = _number(value, where)
    if not v > 0:
        raise DescriptionError(f"{where}: expected a length > 0 (m), got {value!r:.60}")
    return v


def _leg(data: Any, where: str) -> Leg:
    if not isinstance(data, dict):
        raise DescriptionError(f"{where}: expected a mapping with a type, got {data!r:.60}")
    kind = data.get("type")
    if not isinstance(kind, str) or kind not in LEG_TYPES:
        raise DescriptionError(
            f"{where}.type: expected one of {', '.join(LEG_TYPES)}, got {kind!r:.60}"
        )
    required, optional = LEG_TYPES[kind]
    _no_unknown(data, {"type", "limits", "name", *required, *optional}, where)
    for key in required:
        if data.get(key) is None:
            raise DescriptionError(
                f"{where}.{key}: missing (a {kind} leg needs {', '.join(required)})"
            )
    fields: dict[str, Any] = {
        "type": kind,
        "base": _point(data["base"], f"{where}.base"),
        "platform": _point(data["platform"], f"{where}.platform"),
    }
    if "axis" in required:
        axis = _direction(data["axis"], f"{where}.axis")
        fields["axis"] = tuple(axis.tolist())
    if "zero" in required:
        zero = _direction(data["zero"], f"{where}.zero")
        cosine = float(zero @ axis)
        if abs(cosine) > 1e-6:
            raise DescriptionError(
                f"{where}.zero: must be perpendicular to axis (they make "
                f"{math.degrees(math.acos(max(-1.0, min(1.0, cosine)))):.6g} deg)"
            )
        zero = zero - cosine * axis  # exactly perpendicular: the angle is measured in the plane
        fields["zero"] = tuple((zero / np.linalg.norm(zero)).tolist())
    if "crank" in required:
        fields["crank"] = _positive(data["crank"], f"{where}.crank")
    if "rod" in required:
        fields["rod"] = _positive(data["rod"], f"{where}.rod")
    if "branch" in optional:
        branch = data.get("branch", DEFAULT_BRANCH[kind])
        if isinstance(branch, bool) or branch not in (1, -1):
            raise DescriptionError(f"{where}.branch: expected +1 or -1, got {branch!r:.60}")
        fields["branch"] = int(branch)
    unit = "rad" if kind == "crank-rod" else "m"
    if data.get("limits") is not None:
        lo, hi = _numbers(data["limits"], 2, f"{where}.limits", (unit, unit))
        if not lo < hi:
            raise DescriptionError(f"{where}.limits: lower {lo:g} must be < upper {hi:g} ({unit})")
        if kind == "crank-rod" and hi - lo >= 2 * math.pi:
            raise DescriptionError(
                f"{where}.limits: span {hi - lo:.6g} rad is a whole turn or more"
            )
        fields["limits"] = (lo, hi)
    name = data.get("name", "")
    if not isinstance(name, str):
        raise DescriptionError(f"{where}.name: expected a text, got {name!r:.60}")
    fields["name"] = name
    return Leg(**fields)


def _bounds(value: Any, n: int, units: tuple[str, ...], where: str) -> tuple[tuple, tuple]:
    if isinstance(value, dict):
        _no_unknown(value, {"lower", "upper"}, where)
        value = [value.get("lower"), value.get("upper")]
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        raise DescriptionError(f"{where}: expected [lower, upper] (two lists of {n} numbers)")
    lo = _numbers(value[0], n, f"{where}.lower", units)
    hi = _numbers(value[1], n, f"{where}.upper", units)
    for k in range(n):
        if not lo[k] < hi[k]:
            raise DescriptionError(
                f"{where}: lower[{k}] = {lo[k]:g} must be < upper[{k}] = {hi[k]:g}"
            )
    return tuple(lo), tuple(hi)


def _masses(value: Any, legs: tuple[Leg, ...], where: str) -> tuple:
    """``((kind, mass, inertia or None, com or None), ..., ("gravity", g))`` from the ``masses``
    mapping: each body kind a number (kg; default shape) or ``{mass, inertia, com}``."""
    if not isinstance(value, dict):
        raise DescriptionError(f"{where}: expected a mapping of body kinds to masses")
    needed = ["platform"] + [k for leg in legs for k in _BODY_KINDS[leg.type]]
    needed = list(dict.fromkeys(needed))
    _no_unknown(value, {*needed, "gravity"}, where)
    out = []
    for kind in needed:
        body = value.get(kind)
        at = f"{where}.{kind}"
        if body is None:
            raise DescriptionError(f"{at}: missing (this mechanism moves {', '.join(needed)})")
        if not isinstance(body, dict):
            body = {"mass": body}
        _no_unknown(body, {"mass", "inertia", "com"}, at)
        mass = _number(body.get("mass"), f"{at}.mass", "kg")
        if not mass > 0:
            raise DescriptionError(f"{at}.mass: expected a mass > 0 (kg), got {mass:g}")
        inertia = None
        if body.get("inertia") is not None:
            raw = body["inertia"]
            if isinstance(raw, list) and len(raw) == 3 and all(isinstance(r, list) for r in raw):
                inertia = tuple(
                    tuple(_numbers(r, 3, f"{at}.inertia", ("kg m^2",) * 3)) for r in raw
                )
            else:
                inertia = tuple(_numbers(raw, 3, f"{at}.inertia", ("kg m^2",) * 3))
        com = None if body.get("com") is None else _point(body["com"], f"{at}.com")
        out.append((kind, mass, inertia, com))
    gravity = (0.0, 0.0, -9.81)
    if value.get("gravity") is not None:
        gravity = tuple(_numbers(value["gravity"], 3, f"{where}.gravity", ("m/s^2",) * 3))
    return (*out, ("gravity", gravity))


# ---------------------------------------------------------------------------- the mechanism
@dataclass(frozen=True)
class Described(Mechanism, register=False):
    """A leg-driven parallel mechanism from its description (:func:`from_file`,
    :func:`from_dict`). Not registered: a file names it (``--mechanism FILE`` on the command
    line), so the registry, the solver atlas and the record never change with a file."""

    name: str
    platform: str
    legs: tuple[Leg, ...]
    home_pose: tuple[float, ...] | None = None
    bounds: tuple[tuple[float, ...], tuple[float, ...]] | None = None
    masses: tuple | None = None
    description: str = dataclasses.field(default="", compare=False)
    source: str = dataclasses.field(default="", compare=False)

    #: the one kernel of every described mechanism: the leg types are its parameters
    kernels: ClassVar[ModuleType] = kernels
    #: the units a paper would print (no paper: millimetres and degrees, the usual ones)
    _PAPER: ClassVar[dict[str, str]] = {"m": "mm", "rad": "deg"}

    def __post_init__(self) -> None:
        if self.platform not in PLATFORMS:
            raise ValueError(f"platform {self.platform!r} is not one of {', '.join(PLATFORMS)}")
        names, units = PLATFORMS[self.platform]
        if len(self.legs) != len(names):
            raise ValueError(f"legs: a {self.platform} platform needs {len(names)} legs")
        set_ = object.__setattr__
        set_(self, "pose_names", names)
        set_(self, "pose_units", units)
        joint_names = []
        for i, leg in enumerate(self.legs):
            label = leg.name or {"length": "l", "slider-rod": "s", "crank-rod": "theta"}[leg.type]
            joint_names.append(label if leg.name else f"{label}{i + 1}")
        if len(set(joint_names)) != len(joint_names):
            raise ValueError(f"legs: joint names {joint_names} must differ (the legs' name fields)")
        set_(self, "joint_names", tuple(joint_names))
        set_(self, "joint_units", tuple(leg.joint_unit for leg in self.legs))
        set_(self, "paper_pose_units", tuple(self._PAPER[u] for u in units))
        set_(self, "paper_joint_units", tuple(self._PAPER[u] for u in self.joint_units))
        home = self.home()
        if not bool(self.in_domain(home)):
            raise ValueError(
                f"home: the pose {tuple(np.round(home, 6).tolist())} is outside the workspace "
                "(some leg cannot reach its anchor, or a joint is beyond its limits): give a "
                "reachable home pose"
            )
        cond = float(np.linalg.cond(self._jacobian_at(home)))
        if not cond < 1e10:
            raise ValueError(
                f"home: the pose {tuple(np.round(home, 6).tolist())} is singular (condition "
                f"number of d residual / d pose {cond:.3g}): give a regular home pose"
            )
        lo, hi = self.pose_bounds()
        if not np.all((lo <= home) & (home <= hi)):
            raise ValueError("bounds: the box must contain the home pose")

    # ------------------------------------------------------------------ geometry as arrays
    @cached_property
    def base_points(self) -> Array:
        """Base anchors (m, 3): leg bases, slider origins, crank centres."""
        return np.array([leg.base for leg in self.legs], dtype=float)

    @cached_property
    def anchor_points(self) -> Array:
        """Platform anchors (m, 3) in the platform frame."""
        return np.array([leg.platform for leg in self.legs], dtype=float)

    @cached_property
    def _types(self) -> NDArray[np.str_]:
        return np.array([leg.type for leg in self.legs])

    @cached_property
    def _axes(self) -> Array:
        return np.array([leg.axis or (0.0, 0.0, 1.0) for leg in self.legs], dtype=float)

    @cached_property
    def _zeros(self) -> Array:
        return np.array([leg.zero or (1.0, 0.0, 0.0) for leg in self.legs], dtype=float)

    @cached_property
    def _sides(self) -> Array:
        return np.cross(self._axes, self._zeros)

    @cached_property
    def _cranks(self) -> Array:
        return np.array([leg.crank or 0.0 for leg in self.legs], dtype=float)

    @cached_property
    def _rods(self) -> Array:
        return np.array([leg.rod or 0.0 for leg in self.legs], dtype=float)

    @cached_property
    def size(self) -> float:
        """Characteristic length (m): RMS distance of the base anchors from their centroid."""
        b = self.base_points - self.base_points.mean(0)
        return float(np.sqrt(np.mean(np.sum(b * b, -1)))) or 1.0

    # ------------------------------------------------------------------ the kernel's parameters
    def _params(self, home_sign: float) -> Array:
        records = []
        for leg in self.legs:
            lo, hi = leg.limits or (0.0, 0.0)
            axis = leg.axis or (0.0, 0.0, 0.0)
            zero = leg.zero or (0.0, 0.0, 0.0)
            records.append(
                {
                    "kind": _LEG_CODE[leg.type],
                    "base": leg.base,
                    "axis": axis,
                    "zero": zero,
                    "side": tuple(np.cross(axis, zero).tolist()),
                    "crank": leg.crank or 0.0,
                    "rod": leg.rod or 0.0,
                    "anchor": leg.platform,
                    "branch": float(leg.branch),
                    "limited": 1.0 if leg.limits is not None else 0.0,
                    "lower": lo,
                    "upper": hi,
                }
            )
        return kernels.PARAMS.pack(
            records,
            platform=_PLATFORM_CODE[self.platform],
            legs=float(len(self.legs)),
            home_sign=home_sign,
        )

    def _jacobian_at(self, pose: Array) -> Array:
        """``d residual / d pose`` at ``pose`` with its own joints (no assembly sign needed)."""
        k = Kernel(kernels, self._params(1.0), self.n_pose, self.n_joints)
        q, _ = evaluate(k, "ik", pose)
        return evaluate(k, "jacobian", pose, q)

    def kernel_params(self) -> Array:
        """The platform type, the number of legs, the sign of ``det(d residual / d pose)`` at home
        (the working assembly of a translational or planar platform) and one record per leg
        (:data:`parakin.kernels.legs.LEG`)."""
        sign = 0.0
        if self.platform != "spatial":
            with np.errstate(invalid="ignore"):  # a home outside the domain: NaN, named later
                sign = float(np.sign(np.linalg.det(self._jacobian_at(self.home()))))
        return self._params(sign)

    # ------------------------------------------------------------------ what a mechanism declares
    def home(self) -> Array:
        """The declared ``home`` pose, else the origin pose (all zeros)."""
        if self.home_pose is not None:
            return np.array(self.home_pose, dtype=float)
        return np.zeros(len(self.pose_names))

    def pose_bounds(self) -> tuple[Array, Array]:
        """The declared ``bounds``, else home plus or minus a fifth of :attr:`size` in position
        and 20 deg in angle."""
        if self.bounds is not None:
            return np.array(self.bounds[0]), np.array(self.bounds[1])
        half = np.array(
            [np.deg2rad(20.0) if u == "rad" else 0.2 * self.size for u in self.pose_units]
        )
        return self.home() - half, self.home() + half

    def parameters(self) -> dict[str, Any]:
        """The description as plain data (what a file would hold; JSON-ready)."""
        return self.to_dict()

    def to_dict(self) -> dict[str, Any]:
        """The description, in the schema :func:`from_dict` reads (SI units)."""
        out: dict[str, Any] = {
            "name": self.name,
            "platform": self.platform,
            "legs": [leg.to_dict() for leg in self.legs],
        }
        if self.home_pose is not None:
            out["home"] = list(self.home_pose)
        if self.bounds is not None:
            out["bounds"] = {"lower": list(self.bounds[0]), "upper": list(self.bounds[1])}
        if self.masses is not None:
            masses: dict[str, Any] = {}
            for entry in self.masses:
                if entry[0] == "gravity":
                    masses["gravity"] = list(entry[1])
                    continue
                kind, mass, inertia, com = entry
                body: dict[str, Any] = {"mass": mass}
                if inertia is not None:
                    body["inertia"] = [list(r) if isinstance(r, tuple) else r for r in inertia]
                if com is not None:
                    body["com"] = list(com)
                masses[kind] = body
            out["masses"] = masses
        if self.description:
            out["description"] = self.description
        return out

    # ------------------------------------------------------------------ kinematics beyond the kernel
    def platform_frame(self, pose: ArrayLike) -> tuple[Array, Array]:
        """The platform's position ``t`` (..., 3) and rotation ``R`` (..., 3, 3)."""
        x = as_batch(pose, self.n_pose, "pose")
        zeros = np.zeros(x.shape[:-1])
        if self.platform == "spatial":
            return x[..., :3], euler_zyx(x[..., 3], x[..., 4], x[..., 5])
        if self.platform == "planar":
            t = np.stack([x[..., 0], x[..., 1], zeros], -1)
            return t, euler_zyx(x[..., 2], zeros, zeros)
        return x.copy(), np.broadcast_to(np.eye(3), (*x.shape[:-1], 3, 3)).copy()

    def platform_world(self, pose: ArrayLike) -> Array:
        """The platform anchors in the fixed frame (..., m, 3)."""
        t, r = self.platform_frame(pose)
        return t[..., None, :] + np.einsum("...ij,kj->...ki", r, self.anchor_points)

    def spheres(self, joints: ArrayLike) -> tuple[Array, Array]:
        """For joints (..., m): each leg's sphere, centre ``c(q)`` (..., m, 3) and radius
        ``rho(q)`` (..., m): the platform anchor of leg ``i`` lies on sphere ``i``. A length leg's
        is its base anchor and its length; a slider's the slider point and the rod; a crank's the
        crank tip and the rod."""
        q = as_batch(joints, self.n_joints, "joints")
        qq = q[..., None]
        t = self._types
        slider, crank = (t == "slider-rod")[:, None], (t == "crank-rod")[:, None]
        arm = np.cos(qq) * self._zeros + np.sin(qq) * self._sides
        centre = self.base_points + np.where(
            slider, qq * self._axes, np.where(crank, self._cranks[:, None] * arm, 0.0)
        )
        radius = np.where(t == "length", q, self._rods)
        return centre, radius

    def joint_rates(self, pose: ArrayLike, joints: ArrayLike) -> Array:
        """``d c_i / d q_i`` (..., m, 3): how each joint moves its sphere's centre (zero for a length
        leg, whose joint is the radius)."""
        q = as_batch(joints, self.n_joints, "joints")[..., None]
        t = self._types
        turn = -np.sin(q) * self._zeros + np.cos(q) * self._sides
        return np.where(
            (t == "slider-rod")[:, None],
            self._axes,
            np.where((t == "crank-rod")[:, None], self._cranks[:, None] * turn, 0.0),
        )

    def jacobian_joints(self, pose: ArrayLike, joints: ArrayLike) -> Array:
        """``d residual / d joints``, diagonal: ``-1`` for a length leg, ``-v . dc/dq / L`` for a rod
        leg (``v`` from the sphere's centre to the anchor)."""
        x = as_batch(pose, self.n_pose, "pose")
        q = as_batch(joints, self.n_joints, "joints")
        centre, _ = self.spheres(q)
        v = self.platform_world(x) - centre
        rate = np.einsum("...ij,...ij->...i", v, self.joint_rates(x, q))
        diag = np.where(
            self._types == "length", -1.0, -rate / np.where(self._rods > 0, self._rods, 1.0)
        )
        return diag[..., None] * np.eye(self.n_joints)

    # ------------------------------------------------------------------ which joints can assemble
    def check_joints(self, joints: ArrayLike) -> None:
        """Raise UnreachableError where ``joints`` cannot be assembled as this mechanism works: a
        joint beyond its limits, a leg length not > 0, two legs whose spheres cannot hold their
        anchors at the anchors' fixed distance (a necessary condition for every platform type),
        and, for a translational or planar platform (where every assembly is found exactly), no
        real assembly, or none on the legs' branches and home's assembly mode (where no solver
        can succeed)."""
        given = as_batch(joints, self.n_joints, "joints")
        shape = given.shape[:-1]
        q = given.reshape(-1, self.n_joints)

        def fail(mask: NDArray[np.bool_], message) -> None:
            """``message(i)`` of the first flat row ``i`` where ``mask (N,)`` holds, at its place
            in the caller's batch."""
            raise_first(
                mask.reshape(shape),
                shape,
                lambda idx: message(int(np.ravel_multi_index(idx, shape)) if shape else 0),
            )

        def row(i: int) -> tuple:
            return tuple(np.round(q[i], 6).tolist())

        for k, leg in enumerate(self.legs):
            name, unit = self.joint_names[k], leg.joint_unit
            if leg.type == "length":
                fail(
                    ~(q[:, k] > 0),
                    lambda i, k=k, name=name: (
                        f"joint {name} = {q[i, k]:g} m must be > 0 (a leg length)"
                    ),
                )
            if leg.limits is None:
                continue
            lo, hi = leg.limits
            if unit == "rad":  # an angle: within the arc from lo to hi, whatever the turn
                gap = q[:, k] - lo
                inside = gap - 2 * np.pi * np.floor(gap / (2 * np.pi)) <= hi - lo
            else:
                inside = (lo <= q[:, k]) & (q[:, k] <= hi)
            fail(
                ~inside,
                lambda i, k=k, name=name, lo=lo, hi=hi, unit=unit: (
                    f"joint {name} = {q[i, k]:.6g} {unit} is outside its limits "
                    f"[{lo:g}, {hi:g}] {unit} (legs[{k}].limits)"
                ),
            )
        self._check_pairs(q, fail, row)
        if self.platform != "spatial":
            with np.errstate(all="ignore"):
                sols, _ = self.real_solutions(q)
            none = ~np.any(np.all(np.isfinite(sols), axis=-1), axis=-1)
            fail(
                none,
                lambda i: (
                    f"joints {row(i)} cannot be assembled: no real assembly of the "
                    f"{self.platform} platform exists"
                ),
            )
            fail(
                ~np.any(self._working(sols, q), axis=-1),
                lambda i: (
                    f"joints {row(i)} assemble only with a leg on its other branch or in the "
                    "other assembly mode, never as this mechanism works (fk --all lists every "
                    "assembly)"
                ),
            )

    def _check_pairs(self, q: Array, fail, row) -> None:
        """A rigid platform holds every two anchors a fixed distance apart: for each pair of legs,
        some points of their spheres must lie that far apart (for a translational platform, whose
        position lies on every sphere moved back by its anchor: those moved spheres must meet).
        ``q`` (N, m); ``fail(mask, message)`` raises for the first row of ``mask``."""
        centre, radius = self.spheres(q)
        r = np.abs(radius)
        a = self.anchor_points
        slack = 1e-9 * max(1.0, self.size)
        for i in range(self.n_joints):
            for j in range(i + 1, self.n_joints):
                ri, rj = r[:, i], r[:, j]
                if self.platform == "translational":
                    gap = np.linalg.norm((centre[:, i] - a[i]) - (centre[:, j] - a[j]), axis=-1)
                    bad = (gap > ri + rj + slack) | (gap < np.abs(ri - rj) - slack)

                    def message(n, i=i, j=j, gap=gap, ri=ri, rj=rj) -> str:
                        return (
                            f"joints {row(n)} cannot be assembled: legs {i + 1} and {j + 1} put "
                            f"the platform on spheres of radii {ri[n]:.6g} and {rj[n]:.6g} m "
                            f"whose centres are {gap[n]:.6g} m apart: they do not meet"
                        )
                else:
                    gap = np.linalg.norm(centre[:, i] - centre[:, j], axis=-1)
                    lo = np.maximum(0.0, np.maximum(gap - ri - rj, np.abs(ri - rj) - gap))
                    hi = gap + ri + rj
                    held = float(np.linalg.norm(a[i] - a[j]))
                    bad = (held < lo - slack) | (held > hi + slack)

                    def message(n, i=i, j=j, lo=lo, hi=hi, held=held) -> str:
                        return (
                            f"joints {row(n)} cannot be assembled: legs {i + 1} and {j + 1} hold "
                            f"their anchors {lo[n]:.6g} to {hi[n]:.6g} m apart, the platform "
                            f"holds them {held:.6g} m apart"
                        )

                fail(bad, message)

    # ------------------------------------------------------------------ every assembly
    def fk_all(self, joints: ArrayLike) -> Array:
        """Every real assembly of ``joints`` (..., m) as poses (..., k, n), NaN-padded: the two
        points of a translational platform's three-sphere intersection, the up to six roots of a
        planar platform's polynomial, the certified solutions of a spatial platform's 6-6
        homotopy. Assemblies with a leg on its other branch are included
        (:meth:`assembly_label` says which)."""
        q = as_batch(joints, self.n_joints, "joints")
        sols, _ = self.real_solutions(q.reshape(-1, self.n_joints))
        return sols.reshape(*q.shape[:-1], *sols.shape[1:])

    def real_solutions(self, joints: ArrayLike) -> tuple[Array, NDArray[np.bool_]]:
        """:meth:`fk_all` of flat joints (N, m), and per input whether the method guarantees that
        every real assembly was found: the closed forms unless degenerate (collinear sphere
        centres; a root of the planar polynomial where its linear solve is singular), the 6-6
        homotopy's certificate."""
        q = np.atleast_2d(as_batch(joints, self.n_joints, "joints"))
        if self.platform == "translational":
            return self._translational(q)
        if self.platform == "planar":
            return self._planar(q)
        return self._spatial(q)

    def _translational(self, q: Array) -> tuple[Array, NDArray[np.bool_]]:
        """Three spheres (centres ``c_i - a_i``, radii ``rho_i``) meet in the platform's position:
        subtracting the first from the others leaves a line, which meets the first in two points."""
        centre, radius = self.spheres(q)
        s = centre - self.anchor_points  # (N, 3, 3)
        rel = s[:, 1:] - s[:, :1]  # (N, 2, 3), positions relative to the first centre
        rhs = 0.5 * (np.einsum("nij,nij->ni", rel, rel) - radius[:, 1:] ** 2 + radius[:, :1] ** 2)
        u = np.cross(rel[:, 0], rel[:, 1])
        uu = np.einsum("ni,ni->n", u, u)
        scale = np.einsum("nij,nij->n", rel, rel)
        regular = uu > 1e-20 * scale**2
        gram = rel @ np.swapaxes(rel, -1, -2)
        with np.errstate(all="ignore"):
            gram = np.where(regular[:, None, None], gram, np.eye(2))
            p0 = np.einsum("nij,ni->nj", rel, np.linalg.solve(gram, rhs[..., None])[..., 0])
            half_b = np.einsum("ni,ni->n", u, p0)
            disc = half_b**2 - uu * (np.einsum("ni,ni->n", p0, p0) - radius[:, 0] ** 2)
            root = np.sqrt(disc)
            t = np.stack([(-half_b + root) / uu, (-half_b - root) / uu], -1)
            points = s[:, None, 0] + p0[:, None] + t[..., None] * u[:, None]
        ok = regular & (disc >= 0)
        points = np.where(ok[:, None, None], points, np.nan)
        # a tangent contact is one assembly, not two
        same = np.all(np.abs(points[:, 0] - points[:, 1]) <= 1e-12 * max(1.0, self.size), -1)
        points[same, 1] = np.nan
        return points, regular

    def _planar(self, q: Array) -> tuple[Array, NDArray[np.bool_]]:
        """The planar platform's assemblies. With ``g_i(phi) = R(phi) a_i - c_i`` (in the plane),
        subtracting leg 1's circle from legs 2 and 3 gives ``M(phi) (x, y) = e(phi) / 2``;
        substituting ``(x, y) = adj(M) e / 2 det(M)`` into leg 1 leaves
        ``F(phi) = |N|^2 / 4 + D N . g_1 + D^2 (|g_1|^2 - r_1^2) = 0`` (``N = adj(M) e``,
        ``D = det M``), a trigonometric polynomial of degree at most 4 in ``phi`` (for the 3-RPR
        the classical sextic: the top degree cancels). Its coefficients come exactly from 16
        samples (an FFT); its roots on the unit circle ``z = e^(i phi)`` (companion eigenvalues)
        are the assemblies, each polished by Newton on the closure equations. Batched: one
        eigenvalue call per polynomial degree, one polish of every candidate of every input."""
        n = len(q)
        centre, radius = self.spheres(q)
        a = self.anchor_points
        eff = radius**2 - (a[:, 2] - centre[..., 2]) ** 2  # (N, 3): circle radii squared, in plane
        phi = 2 * np.pi * np.arange(_SAMPLES) / _SAMPLES
        coef = self._planar_poly(self._g(phi[None], centre), eff)  # (N, 9), ascending in z
        size = np.max(np.abs(coef), axis=-1)
        complete = np.isfinite(size) & (size > 0)
        used = complete & np.all(eff >= 0, axis=-1)  # a circle of negative radius: no assembly
        big = np.abs(coef) > 1e-11 * size[:, None]
        lo = np.argmax(big, axis=-1)
        hi = coef.shape[-1] - 1 - np.argmax(big[:, ::-1], axis=-1)
        rows, roots = [], []
        for low, high in sorted({(int(a_), int(b_)) for a_, b_, u in zip(lo, hi, used) if u}):
            if high == low:
                continue
            group = np.flatnonzero(used & (lo == low) & (hi == high))
            c = coef[group, low : high + 1]
            deg = high - low
            comp = np.zeros((len(group), deg, deg), dtype=complex)
            comp[:, 0, :] = -c[:, -2::-1] / c[:, -1:]
            comp[:, np.arange(1, deg), np.arange(deg - 1)] = 1.0
            z = np.linalg.eigvals(comp)  # (k, deg)
            on = np.abs(np.abs(z) - 1.0) < 1e-3
            rows.append(np.broadcast_to(group[:, None], z.shape)[on])
            roots.append(z[on])
        if not rows or not sum(len(r) for r in rows):
            return np.full((n, 8, 3), np.nan), complete
        row = np.concatenate(rows)
        z = np.concatenate(roots)
        angle = np.angle(z)
        g = self._g(angle, centre[row])  # (K, 3, 2)
        m = g[:, 1:] - g[:, :1]
        e = (eff[row, 1:] - eff[row, :1]) - (np.sum(g[:, 1:] ** 2, -1) - np.sum(g[:, :1] ** 2, -1))
        det = m[:, 0, 0] * m[:, 1, 1] - m[:, 0, 1] * m[:, 1, 0]
        # at a root where the linear solve is singular, (x, y) is not unique: no guarantee there
        singular = np.abs(det) <= 1e-9 * np.max(np.abs(m), axis=(1, 2)) ** 2
        complete[np.unique(row[singular])] = False
        with np.errstate(all="ignore"):
            xy = np.stack(
                [
                    m[:, 1, 1] * e[:, 0] - m[:, 0, 1] * e[:, 1],
                    -m[:, 1, 0] * e[:, 0] + m[:, 0, 0] * e[:, 1],
                ],
                -1,
            ) / (2 * det[:, None])
        poses = self._polish(np.concatenate([xy, angle[:, None]], -1), q[row])
        order = np.argsort(row, kind="stable")
        counts = np.bincount(row, minlength=n)
        slot = np.empty(len(row), dtype=np.intp)  # candidate k of its input
        slot[order] = np.arange(len(row)) - np.repeat(np.cumsum(counts) - counts, counts)
        cand = np.full((n, 8, 3), np.nan)
        cand[row, slot] = poses
        cand_z = np.full((n, 8), np.inf + 0j)
        cand_z[row, slot] = z
        found = self._distinct_rows(cand)
        n_found = np.sum(np.isfinite(found[..., 0]), -1)
        # a root that polished into no assembly of its own, unless two roots merged (a double root)
        with np.errstate(invalid="ignore"):
            gap = np.abs(cand_z[:, :, None] - cand_z[:, None, :])
        gap[:, np.arange(8), np.arange(8)] = np.inf
        merged = np.any(np.nan_to_num(gap, nan=np.inf) < 1e-4, axis=(1, 2))
        complete &= (n_found == counts) | merged
        return found, complete

    def _g(self, phi: Array, centre: Array) -> Array:
        """``g_i(phi) = R(phi) a_i - c_i`` in the plane, per angle: ``phi`` (1, S) with ``centre``
        (N, 3, 3) gives (N, S, 3, 2); ``phi`` (K,) with ``centre`` (K, 3, 3) gives (K, 3, 2)."""
        a = self.anchor_points
        c, s = np.cos(phi)[..., None], np.sin(phi)[..., None]
        turned = np.stack([c * a[:, 0] - s * a[:, 1], s * a[:, 0] + c * a[:, 1]], -1)
        if phi.ndim == 2:  # (1, S, 3, 2) against (N, 1, 3, 2)
            return turned - centre[:, None, :, :2]
        return turned - centre[..., :2]

    def _distinct_rows(self, cand: Array) -> Array:
        """``cand (N, k, n)`` with every repeat of an earlier candidate's pose (angles modulo a
        turn) made NaN, the finite ones first."""
        d = self.pose_difference(cand[:, :, None, :], cand[:, None, :, :])
        with np.errstate(invalid="ignore"):
            same = np.max(np.abs(d), -1) < 1e-7 * max(1.0, self.size)
        earlier = np.tril(np.ones(cand.shape[1], dtype=bool), -1)  # [i, j]: j before i
        repeat = np.any(same & earlier, axis=-1)
        out = np.where(repeat[..., None], np.nan, cand)
        key = np.where(np.isfinite(out[..., 0]), 0, 1)
        return np.take_along_axis(out, np.argsort(key, -1, kind="stable")[..., None], 1)

    @staticmethod
    def _planar_poly(g: Array, eff: Array) -> Array:
        """Coefficients ``(N, 9)`` of ``z^4 F(phi)`` in ascending powers of ``z = e^(i phi)`` from the
        samples ``g (N, S, 3, 2)`` of :meth:`_g` (see :meth:`_planar`)."""
        m = g[:, :, 1:] - g[:, :, :1]  # rows g_2 - g_1, g_3 - g_1
        gg = np.sum(g * g, -1)  # (N, S, 3)
        e = (eff[:, None, 1:] - eff[:, None, :1]) - (gg[..., 1:] - gg[..., :1])
        det = m[..., 0, 0] * m[..., 1, 1] - m[..., 0, 1] * m[..., 1, 0]
        n0 = m[..., 1, 1] * e[..., 0] - m[..., 0, 1] * e[..., 1]
        n1 = -m[..., 1, 0] * e[..., 0] + m[..., 0, 0] * e[..., 1]
        f = 0.25 * (n0 * n0 + n1 * n1) + det * (n0 * g[..., 0, 0] + n1 * g[..., 0, 1])
        f = f + det**2 * (gg[..., 0] - eff[:, None, 0])
        spectrum = np.fft.fft(f, axis=-1) / f.shape[-1]  # F = sum_k f_k e^(i k phi), k = -4..4
        return np.concatenate([spectrum[:, -4:], spectrum[:, :5]], axis=-1)

    def _polish(self, poses: Array, q: Array) -> Array:
        """Newton on the closure equations from each candidate pose (K, n) for its joints (K, m)
        (rows that do not converge to a residual within ``1e-9 size`` become NaN)."""
        x = poses.copy()
        qq = np.broadcast_to(q, (len(x), self.n_joints))
        with np.errstate(all="ignore"):
            for _ in range(_POLISH):
                fin = np.all(np.isfinite(x), -1)
                if not fin.any():
                    break
                xf = np.where(fin[:, None], x, self.home())
                r = self.residual(xf, qq)
                jac = self.jacobian_pose(xf, qq)
                det = np.linalg.det(jac)
                ok = fin & np.isfinite(det) & (np.abs(det) > 0)
                step = np.linalg.solve(
                    np.where(ok[:, None, None], jac, np.eye(self.n_pose)), r[..., None]
                )[..., 0]
                x = np.where(ok[:, None], x - step, x)
            fin = np.all(np.isfinite(x), -1)
            res = np.full(len(x), np.inf)
            if fin.any():
                res[fin] = np.max(np.abs(self.residual(x[fin], qq[fin])), -1)
        x[~(res <= 1e-9 * max(1.0, self.size))] = np.nan
        return wrap_angles(x, self.pose_units)

    def _spatial(self, q: Array) -> tuple[Array, NDArray[np.bool_]]:
        """Six spheres hold six anchors: a 6-6 Gough-Stewart platform with base points the
        spheres' centres and leg lengths their radii, solved by
        :meth:`parakin.mechanisms.stewart66.Stewart66.fk_all` (certified parameter homotopy).
        Length legs keep their centres, so one platform solves every input; a rod leg's centre
        moves with its joint, so each input is a platform of its own (its start system first)."""
        from parakin.mechanisms.stewart66 import Stewart66

        n = len(q)
        centre, radius = self.spheres(q)
        out = np.full((n, 40, 6), np.nan)
        complete = np.zeros(n, dtype=bool)
        platform = [tuple(p) for p in self.anchor_points.tolist()]
        fixed = bool(np.all(self._types == "length"))
        groups = [np.arange(n)] if fixed else [np.array([i]) for i in range(n)]
        for rows in groups:
            geometry = (
                self._hexapod
                if fixed
                else Stewart66(
                    base=[tuple(b) for b in centre[rows[0]].tolist()],
                    platform=platform,
                    allow_coincident=True,
                )
            )
            info = geometry.fk_all(radius[rows], return_info=True)
            poses = info.poses  # (k, 40, 6): alpha, beta, gamma, X, Y, Z
            out[rows] = np.concatenate([poses[..., 3:], poses[..., :3]], -1)
            complete[rows] = info.complete
        return out, complete

    @cached_property
    def _hexapod(self):
        """The 6-6 platform of a spatial mechanism of length legs (its start system is made once,
        on its first :meth:`fk_all`)."""
        from parakin.mechanisms.stewart66 import Stewart66

        return Stewart66(
            base=[tuple(b) for b in self.base_points.tolist()],
            platform=[tuple(p) for p in self.anchor_points.tolist()],
            allow_coincident=True,
        )

    def fk(self, joints: ArrayLike, near: ArrayLike | None = None) -> Array:
        """The working assembly (..., n): the assembly on every leg's declared branch, on home's
        side of the singularity locus (translational and planar platforms), nearest ``near``
        (default :meth:`home`; distance in units of the pose box, angles modulo a turn). Raises
        UnreachableError where an input has none."""
        q = as_batch(joints, self.n_joints, "joints")
        flat = q.reshape(-1, self.n_joints)
        sols, _ = self.real_solutions(flat)
        good = self._working(sols, flat)
        ref = (
            self.home()
            if near is None
            else as_batch(near, self.n_pose, "near").reshape(-1, self.n_pose)
        )
        lo, hi = self.pose_bounds()
        with np.errstate(invalid="ignore"):
            d = self.pose_difference(sols, np.asarray(ref)[..., None, :]) / (hi - lo)
            dist = np.where(good, np.sqrt(np.sum(d * d, -1)), np.inf)
        raise_first(
            ~np.any(good, -1),
            (len(flat),),
            lambda idx: (
                f"joints {tuple(np.round(flat[idx], 6).tolist())} have no assembly on the legs' "
                "branches and the working assembly mode (fk_all lists every assembly)"
            ),
        )
        best = np.argmin(dist, -1)
        pose = np.take_along_axis(sols, best[:, None, None], 1)[:, 0]
        return pose.reshape(*q.shape[:-1], self.n_pose)

    def _working(self, sols: Array, q: Array) -> NDArray[np.bool_]:
        """Which solutions (N, k, n) are on every leg's branch and the working assembly mode."""
        fin = np.all(np.isfinite(sols), -1)
        good = np.zeros(fin.shape, dtype=bool)
        if fin.any():
            qq = np.broadcast_to(q[:, None], (*sols.shape[:2], self.n_joints))[fin]
            x = sols[fin]
            with np.errstate(all="ignore"):
                ok = self.in_domain(x)
                err = np.full(len(x), np.inf)
                if ok.any():
                    err[ok] = self.joint_error(x[ok], qq[ok])
                good[fin] = ok & (err <= 1e-7 * max(1.0, self.size)) & self.on_assembly(x, qq)
        return good

    def assembly_label(self, pose: ArrayLike, joints: ArrayLike) -> str:
        """Which assembly mode (translational and planar: the sign of ``det(d residual / d pose)``
        against home's) and which legs, if any, sit on their other branch."""
        x = as_batch(pose, self.n_pose, "pose")
        q = as_batch(joints, self.n_joints, "joints")
        parts = []
        if self.platform != "spatial":
            same = bool(self.on_assembly(x, q))
            parts.append("home's assembly mode" if same else "the other assembly mode")
        ok = bool(self.in_domain(x))
        if ok:
            mine = self.ik(x)
            gap = mine - q
            rad = np.array([u == "rad" for u in self.joint_units])
            gap = np.where(rad, (gap + np.pi) % (2 * np.pi) - np.pi, gap)
            other = [
                self.joint_names[i]
                for i in range(self.n_joints)
                if abs(gap[i]) > 1e-6 * max(1.0, self.size)
            ]
        else:
            other = list(self.joint_names)
        if other:
            parts.append(f"other branch of {', '.join(other)}")
        elif any(leg.type != "length" for leg in self.legs):  # (a length leg has one branch)
            parts.append("legs on their branches")
        return ", ".join(parts)

    # ------------------------------------------------------------------ drawing
    def skeleton(self, pose: ArrayLike) -> Skeleton:
        """Base and platform outlines, each leg (actuated part and rod) and both frames."""
        x = as_batch(pose, self.n_pose, "pose")
        if x.ndim != 1:
            raise ValueError(f"skeleton() draws one pose, got a batch of shape {x.shape[:-1]}")
        q = self.ik(x)  # an unreachable pose is an error, not a drawing
        top = self.platform_world(x)
        centre, _ = self.spheres(q)
        points = {f"B_{i + 1}": self.base_points[i] for i in range(self.n_joints)}
        points |= {f"P_{i + 1}": top[i] for i in range(self.n_joints)}
        segments: list[tuple[str, Array]] = []
        for i, leg in enumerate(self.legs):
            b = self.base_points[i]
            if leg.type == "length":
                segments.append(("actuator", np.stack([b, top[i]])))
                continue
            points[f"C_{i + 1}"] = centre[i]
            if leg.type == "slider-rod":
                u = self._axes[i]
                lo = min(0.0, float(q[i])) - 0.1 * self.size
                hi = max(0.0, float(q[i])) + 0.1 * self.size
                segments.append(("rail", np.stack([b + lo * u, b + hi * u])))
            segments.append(("actuator", np.stack([b, centre[i]])))
            segments.append(("passive", np.stack([centre[i], top[i]])))
        t, r = self.platform_frame(x)
        return Skeleton(
            points=points,
            segments=segments,
            polygons=[("base", self.base_points.copy()), ("platform", top.copy())],
            frames={"O": (np.zeros(3), np.eye(3)), "P": (t, r)},
        )

    # ------------------------------------------------------------------ dynamics
    def mass_model(self) -> MassModel | None:
        """The declared ``masses`` (None without: no dynamics). A body given by its mass alone
        gets a default shape: the platform a thin disc through its anchors (radius their RMS
        distance from their centroid, centred there), a crank a solid rod of its radius along its
        arm, a rod a solid rod of the mean rod length (radius 1/40 of it), the centre of mass at
        mid-length, a slider a cube of 5 cm, a length leg's cylinder and piston solid rods of half
        the mean leg length at home (:func:`parakin.dynamics.model.hexapod_masses`)."""
        if self.masses is None:
            return None
        from parakin.dynamics.model import MassModel, RigidBody

        bodies: dict[str, RigidBody] = {}
        gravity = (0.0, 0.0, -9.81)
        for entry in self.masses:
            if entry[0] == "gravity":
                gravity = entry[1]
                continue
            kind, mass, inertia, com = entry
            body = self._default_body(kind, mass)
            if inertia is not None or com is not None:
                body = RigidBody(
                    mass,
                    inertia if inertia is not None else body.inertia,
                    com if com is not None else body.com,
                )
            bodies[kind] = body
        return MassModel(
            bodies, gravity, note=f"{self.name}: masses of {self.source or 'the description'}"
        )

    def _default_body(self, kind: str, mass: float) -> RigidBody:
        from parakin.dynamics.model import RigidBody, hexapod_masses

        if kind == "platform":
            p = self.anchor_points
            centroid = p.mean(axis=0)
            radius = float(np.sqrt(np.mean(np.sum((p - centroid) ** 2, axis=-1)))) or 0.01
            return RigidBody.disc(mass, radius, centroid)
        if kind == "crank":
            r = float(np.mean(self._cranks[self._types == "crank-rod"]))
            return RigidBody.rod(mass, r, r / 20, r / 2)
        if kind == "rod":
            length = float(np.mean(self._rods[self._types != "length"]))
            return RigidBody.rod(mass, length, length / 40, length / 2)
        if kind == "slider":
            return RigidBody(mass, (mass * _SLIDER_SIDE**2 / 6,) * 3)
        leg = float(np.mean(self.ik(self.home())[self._types == "length"]))
        model = hexapod_masses(self.anchor_points, leg, 1.0, mass, mass)
        return model.body(kind)

    def bodies(self, pose: Jet) -> Bodies:
        """The platform (a free body; translational: it keeps its orientation) and each leg's
        bodies: a length leg's cylinder and piston (S-P-S, :func:`parakin.dynamics.model.strut`),
        a slider sliding on its guide, a crank turning about its axis (frame: x its axis, z along
        its arm), and the rods of both, S-S links to the platform (:func:`rods`). The joints are
        the IK's, on each leg's branch, as jets."""
        import parakin.dynamics.jet as dj
        from parakin.dynamics.model import Bodies, free_platform

        origin, rotation = self._platform_jets(pose)
        tops = origin[..., None, :] + dj.matvec(rotation[..., None, :, :], self.anchor_points)
        groups = [free_platform(origin[..., None, :], rotation[..., None, :, :])]
        closures = []
        drives: _Drives = {}
        ends: _Ends = []
        types = self._types
        length = np.flatnonzero(types == "length")
        if length.size:
            struts, closure, more = self._strut_bodies(tops, length)
            groups += struts
            closures.append(closure)
            drives.update(more)
        # the legs whose rods end on a driven body: that body's group, its joints and the rods'
        # lower ends (the rods themselves are one group, below)
        driven = {"slider-rod": self._slider_bodies, "crank-rod": self._crank_bodies}
        for kind, bodies in driven.items():
            legs = np.flatnonzero(types == kind)
            if legs.size:
                group, more, lower = bodies(pose, tops, legs)
                groups.append(group)
                drives.update(more)
                ends += lower
        if ends:
            rod_group, closure = self._rod_bodies(tops, ends)
            groups.append(rod_group)
            closures.append(closure)
        joints: list[Any] = [None] * self.n_joints
        actuators = [""] * self.n_joints
        for i, (q, actuator) in drives.items():
            joints[i], actuators[i] = q, actuator
        return Bodies(tuple(groups), dj.stack(joints, axis=-1), tuple(actuators), tuple(closures))

    def _platform_jets(self, pose: Jet) -> tuple[Jet, Jet]:
        """The platform's origin (..., 3) and rotation (..., 3, 3) as jets: :meth:`platform_frame`
        of a pose that moves, which every body's motion derives from."""
        import parakin.dynamics.jet as dj

        if self.platform == "spatial":
            return pose[..., :3], dj.euler_zyx(pose[..., 3], pose[..., 4], pose[..., 5])
        if self.platform == "planar":
            origin = dj.stack([pose[..., 0], pose[..., 1], 0.0 * pose[..., 0]])
            return origin, dj.rotations([pose[..., 2]], "z")
        batch = pose.shape[:-1]
        return pose, dj.constant_like(np.broadcast_to(np.eye(3), (*batch, 3, 3)), pose)

    def _strut_bodies(
        self, tops: Jet, legs: NDArray[np.intp]
    ) -> tuple[list[BodyGroup], Closure, _Drives]:
        """The length legs' cylinders and pistons (S-P-S struts, closing loops at the platform)
        and their joints: each leg's length, driven by its piston's slide."""
        from parakin.dynamics.model import strut

        labels = [str(i + 1) for i in legs]
        (cyl, pis), closure, lengths = strut(
            self.base_points[legs], tops[..., legs, :], ("platform",) * len(legs), labels=labels
        )
        return [cyl, pis], closure, {i: (lengths[..., j], pis.names[j]) for j, i in enumerate(legs)}

    def _slider_leg(self, tops: Jet, i: int) -> tuple[Jet, Jet]:
        """Slider ``i``'s position along its axis (its joint, on the leg's branch: where the rod
        reaches the platform anchor) and the slider's point, where the rod hangs."""
        import parakin.dynamics.jet as dj

        u, rod, br = self._axes[i], self._rods[i], self.legs[i].branch
        w = tops[..., i, :] - self.base_points[i]
        b = dj.dot(w, u)
        q = b + br * dj.sqrt(rod * rod - (dj.dot(w, w) - b * b))
        return q, q[..., None] * u + self.base_points[i]

    def _slider_bodies(
        self, pose: Jet, tops: Jet, legs: NDArray[np.intp]
    ) -> tuple[BodyGroup, _Drives, _Ends]:
        """The sliders on their guides (slide joints, frames fixed), their joints and their
        points, the lower ends of their rods."""
        import parakin.dynamics.jet as dj
        from parakin.dynamics.model import BodyGroup, frame_with_z

        batch = pose.shape[:-1]
        drives: _Drives = {}
        ends, points = [], []
        for i in legs:
            q, point = self._slider_leg(tops, i)
            points.append(point)
            drives[i] = (q, f"slider{i + 1}")
            ends.append((i, point, f"slider{i + 1}"))
        frames = frame_with_z(self._axes[legs])
        group = BodyGroup(
            "slider",
            tuple(f"slider{i + 1}" for i in legs),
            ("world",) * len(legs),
            "slide",
            dj.stack(points, axis=-2),
            rotation=dj.constant_like(np.broadcast_to(frames, (*batch, *frames.shape)), pose),
            joint_axis=np.broadcast_to(self._axes[legs], (*batch, len(legs), 3)),
        )
        return group, drives, ends

    def _crank_leg(self, pose: Jet, tops: Jet, i: int) -> tuple[Jet, Jet, Jet]:
        """Crank ``i``'s angle (its joint, on the leg's branch), frame (x its axis, z along its
        arm) and tip, where its rod hangs: the leg's closed-form IK as jets."""
        import parakin.dynamics.jet as dj

        r, rod, br = self._cranks[i], self._rods[i], self.legs[i].branch
        z, s, axis = self._zeros[i], self._sides[i], self._axes[i]
        w = tops[..., i, :] - self.base_points[i]
        wu, wv = dj.dot(w, z), dj.dot(w, s)
        big_k = (dj.dot(w, w) + (r * r - rod * rod)) * (1.0 / (2.0 * r))
        root = dj.sqrt(wu * wu + wv * wv - big_k * big_k)
        inv = 1.0 / (wu * wu + wv * wv)
        cos_q = (wu * big_k - br * (wv * root)) * inv
        sin_q = (wv * big_k + br * (wu * root)) * inv
        arm = cos_q[..., None] * z + sin_q[..., None] * s
        tip = r * arm + self.base_points[i]
        # the angle's jet: its value by atan2, its rates from d(theta) = cos d(sin) - sin d(cos)
        c0, s0 = cos_q.value, sin_q.value
        angle = (c0 * sin_q - s0 * cos_q) + np.arctan2(s0, c0)
        axis_jet = dj.constant_like(np.broadcast_to(axis, (*pose.shape[:-1], 3)), pose)
        return angle, dj.stack([axis_jet, dj.cross(arm, axis), arm], axis=-1), tip

    def _crank_bodies(
        self, pose: Jet, tops: Jet, legs: NDArray[np.intp]
    ) -> tuple[BodyGroup, _Drives, _Ends]:
        """The cranks turning about their axes (hinge joints at their centres), their joints and
        their tips, the lower ends of their rods."""
        import parakin.dynamics.jet as dj
        from parakin.dynamics.model import BodyGroup

        batch = pose.shape[:-1]
        drives: _Drives = {}
        ends, frames = [], []
        for i in legs:
            angle, frame, tip = self._crank_leg(pose, tops, i)
            drives[i] = (angle, f"crank{i + 1}")
            frames.append(frame)
            ends.append((i, tip, f"crank{i + 1}"))
        base = dj.constant_like(
            np.broadcast_to(self.base_points[legs], (*batch, len(legs), 3)), pose
        )
        group = BodyGroup(
            "crank",
            tuple(f"crank{i + 1}" for i in legs),
            ("world",) * len(legs),
            "hinge",
            base,
            rotation=dj.stack(frames, axis=-3),
            joint_axis=np.broadcast_to(self._axes[legs], (*batch, len(legs), 3)),
        )
        return group, drives, ends

    @staticmethod
    def _rod_bodies(tops: Jet, ends: _Ends) -> tuple[BodyGroup, Closure]:
        """The rods of the slider and crank legs, in leg order: S-S links from their lower
        ``ends`` (leg, point, body) to the platform anchors, closing loops there."""
        import parakin.dynamics.jet as dj
        from parakin.dynamics.model import rods

        ends = sorted(ends, key=lambda end: end[0])
        legs = [end[0] for end in ends]
        return rods(
            "rod",
            dj.stack([end[1] for end in ends], axis=-2),
            tops[..., legs, :],
            [end[2] for end in ends],
            ("platform",) * len(legs),
            [str(i + 1) for i in legs],
        )
