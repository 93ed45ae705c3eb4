"""What every command shares: argument types, the mechanism and its parameters from the options,
the inputs in SI units, printing (text and strict JSON) and the options common to several commands."""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import re
import sys
from collections.abc import Sequence

import numpy as np

from parakin import kernels, mechanisms
from parakin.io import read_rows
from parakin.units import TO_SI, parse_quantity, to_si

EXIT_BAD_INPUT = 2
EXIT_NOT_CONVERGED = 1


#: largest --maxiter (a bound on the work one command may ask for)
MAXITER_LIMIT = 100_000
#: largest magnitude of a --param value in SI units (m, rad): far beyond any real mechanism
PARAM_LIMIT = 1e6
#: largest |angle| of a pose, a start or a joint (rad, about 159 turns). The spacing of doubles
#: at 1e3 is 1.1e-13 rad, below every accuracy the solvers promise; near 4.5e3 rad it reaches
#: 1e-12 rad and at 1e308 it is larger than a turn: such an angle names no orientation at all.
ANGLE_LIMIT = 1e3
#: what argparse must read as a (negative) number, not an option: -1, -1.5, -.5, -1e-3, -1.5E+02, -inf, -nan
_NEGATIVE_NUMBER = re.compile(
    r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-(inf|infinity|nan)$", re.IGNORECASE
)


class _Parser(argparse.ArgumentParser):
    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        # argparse's own pattern misses scientific notation: "-1e-3" would be taken for an option
        self._negative_number_matcher = _NEGATIVE_NUMBER

    def error(self, message: str):  # one line, status 2 (argparse prints usage too; keep it short)
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {message}\n")


def finite_float(text: str) -> float:
    """A finite number (decimal or scientific notation, any sign), or a clear argparse error."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    return value


def nonempty(text: str) -> str:
    """A non-empty string (``--output ''`` is a mistake, not a request for the default)."""
    if not text.strip():
        raise argparse.ArgumentTypeError(f"{text!r} is empty")
    return text


def nonnegative_float(text: str) -> float:
    value = finite_float(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"{text!r} must be >= 0")
    return value


def iteration_count(text: str) -> int:
    """An integer in [0, MAXITER_LIMIT]; "1e3" is accepted (an integral number)."""
    value = finite_float(text)
    if not value.is_integer() or not 0 <= value <= MAXITER_LIMIT:
        raise argparse.ArgumentTypeError(f"{text!r} must be an integer in [0, {MAXITER_LIMIT}]")
    return int(value)


def _default(field: dataclasses.Field):
    if field.default is not dataclasses.MISSING:
        return field.default
    if field.default_factory is not dataclasses.MISSING:
        return field.default_factory()
    return None


def _numeric_shape(value) -> tuple[int, ...] | None:
    """The shape of ``value`` if it is a real number or an array of them (not a bool), else None."""
    if isinstance(value, (bool, np.bool_, str)) or value is None:
        return None
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return None
    return a.shape


def parameters_of(cls) -> dict[str, object]:
    """The parameters ``--param`` and ``--geometry`` may set, name -> default: every field of the
    mechanism's dataclass whose default is a real number or an array of them, by the names of the
    Python API (switches such as a convention name or a flag are not parameters)."""
    out = {}
    for f in dataclasses.fields(cls):
        default = _default(f)
        if _numeric_shape(default) is not None:
            out[f.name] = default
    return out


def _parameter(where: str, value, default):
    """``value`` (a number, a quantity such as ``35deg``, or a nested list of them) checked against
    the parameter's default: the same shape, finite, at most :data:`PARAM_LIMIT` in magnitude (SI)
    and whole where the default is an integer; arrays as nested tuples (mechanisms are hashable).
    A YAML ``true``/``false`` is refused, not read as 1/0."""
    shape = _numeric_shape(default)
    want = "one number" if not shape else f"an array of shape {shape}"
    try:
        a = np.asarray(_numbers(value, len(shape), where, want), dtype=float)
    except ValueError as exc:
        if str(exc).startswith(where):
            raise
        raise ValueError(f"{where}: expected {want}, got a ragged list") from None
    if a.shape != shape:
        raise ValueError(f"{where}: expected {want}, got shape {a.shape}")
    if not np.all(np.isfinite(a) & (np.abs(a) <= PARAM_LIMIT)):
        raise ValueError(
            f"{where}: values must be finite numbers <= {PARAM_LIMIT:g} in magnitude (SI units)"
        )
    if isinstance(default, (int, np.integer)):
        if not float(a).is_integer():
            raise ValueError(f"{where}: {float(a)!r} must be a whole number")
        return int(a)
    return float(a) if not shape else _nested_tuple(a)


def _numbers(value, ndim: int, where: str, want: str):
    """``value`` as nested lists of floats exactly ``ndim`` deep (a list nested deeper is refused
    at once, never handed to numpy, which takes at most 32 axes): numbers, or quantities as text
    (``35deg``); a boolean, ``None``, a mapping or a date is refused, naming the value."""
    if isinstance(value, (list, tuple)):
        if ndim == 0:
            raise ValueError(f"{where}: expected {want}, got a list nested deeper")
        return [_numbers(v, ndim - 1, where, want) for v in value]
    if ndim > 0:
        raise ValueError(f"{where}: expected {want}, got shape () ({_short_repr(value)})")
    if isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{where}: {value!r} is a boolean (YAML true/false), not a number")
    if isinstance(value, str):
        try:
            return parse_quantity(value)
        except ValueError as exc:
            raise ValueError(f"{where}: {_short_repr(value)} is not a number ({exc})") from None
    if isinstance(value, (int, float, np.integer, np.floating)):
        try:
            return float(value)
        except OverflowError:
            raise ValueError(f"{where}: {_short_repr(value)} is too large a number") from None
    raise ValueError(f"{where}: {_short_repr(value)} is not a number or an array of numbers")


def _short_repr(value, limit: int = 60) -> str:
    text = " ".join(repr(value).split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _nested_tuple(a: np.ndarray):
    return tuple(_nested_tuple(v) for v in a) if a.ndim else float(a)


def _param_text(text: str, default):
    """The value of ``--param NAME=TEXT``: a number or quantity, or for an array parameter a
    YAML/JSON list (``[[0, 0, 0], [1, 0, 0], ...]``), read within the bounds of every YAML/JSON
    input (size, depth, aliases, expansion: :func:`parakin.io.parse_data`)."""
    if not _numeric_shape(default):
        return text
    from parakin.io import parse_data

    return parse_data(text, f"--param value {_short_repr(text, 40)}")


def _geometry(path: str) -> dict:
    """The parameters in ``--geometry FILE`` (YAML or JSON, the names of the Python API), read
    within the bounds of every YAML/JSON input (:func:`parakin.io.load_data`: a regular file,
    size, depth, aliases, expansion)."""
    from parakin.io import load_data

    data = load_data(path, f"--geometry {path}")
    if not isinstance(data, dict):
        raise ValueError(f"--geometry {path}: expected a mapping of parameter names to values")
    return data


def _mechanism(
    name: str | None,
    params: Sequence[str],
    geometry: str | None = None,
    file: str | None = None,
):
    """The mechanism ``name`` with the parameters of ``--geometry FILE``, then of each ``--param
    NAME=VALUE`` (the declared parameters, :func:`parameters_of`); or the mechanism described in
    ``--mechanism FILE`` (:func:`parakin.mechanisms.from_file`), which takes neither: its file
    holds every number."""
    if file is not None:
        if name is not None:
            raise ValueError(f"give a mechanism name ({name}) or --mechanism {file}, not both")
        if params or geometry is not None:
            raise ValueError(
                f"--param and --geometry set a registered mechanism's parameters; --mechanism "
                f"{file} holds its own (edit the file)"
            )
        return mechanisms.from_file(file)
    if name is None:
        raise ValueError(
            "give a mechanism: a name (one of "
            f"{', '.join(sorted(mechanisms.REGISTRY))}) or --mechanism FILE (a YAML/JSON "
            "description, docs/mechanism_file.md)"
        )
    cls = mechanisms.get(name)
    known = parameters_of(cls)
    given = {}
    if geometry is not None:
        given = {k: (f"--geometry {geometry}: {k}", v) for k, v in _geometry(geometry).items()}
    for item in params:
        key, sep, value = item.partition("=")
        if not sep:
            raise ValueError(f"--param {item!r} must look like NAME=VALUE (e.g. phi=35deg)")
        key = key.strip()
        given[key] = (f"--param {item}", _param_text(value, known.get(key)))
    unknown = sorted(set(given) - set(known))
    if unknown:
        raise ValueError(f"unknown parameter(s) {unknown} of {name}; known: {sorted(known)}")
    values = {k: _parameter(where, v, known[k]) for k, (where, v) in given.items()}
    try:
        return cls(**values)
    except TypeError as exc:
        raise ValueError(f"{name}: {exc}") from None


def mechanism_of(args):
    """The mechanism the options of :func:`_mechanism_options` name (``MECH`` with ``--param`` /
    ``--geometry``, or ``--mechanism FILE``): what every command that takes a mechanism calls."""
    return _mechanism(args.mechanism, args.param, args.geometry, args.mechanism_file)


def _finite(values: np.ndarray, what: str, inputs: np.ndarray) -> np.ndarray:
    """``values`` if every entry is finite; else a ValueError naming the input (too large?)."""
    bad = ~np.all(np.isfinite(np.atleast_2d(values)), axis=-1)
    if np.any(bad):
        row = np.atleast_2d(inputs)[int(np.argmax(bad))]
        raise ValueError(
            f"{what} of {np.array2string(row, precision=6)} is not finite "
            f"(|values| up to {np.max(np.abs(row)):.3g}: too large for this mechanism?)"
        )
    return values


def _angles(values: np.ndarray, names, units, option: str) -> np.ndarray:
    """``values`` if every angle among them (unit ``rad`` or ``deg``) is within
    :data:`ANGLE_LIMIT`; else a ValueError naming the value and the limit in its unit."""
    for k, unit in enumerate(units):
        if unit in ("rad", "deg"):
            limit = ANGLE_LIMIT / TO_SI[unit]
            worst = float(np.max(np.abs(np.atleast_2d(values)[..., k])))
            if not worst <= limit:
                raise ValueError(
                    f"{option}: {names[k]} = {worst:.6g} {unit} is beyond the limit |angle| <= "
                    f"{limit:.6g} {unit} ({ANGLE_LIMIT:g} rad; a pose angle is a few turns at most)"
                )
    return values


def _dumps(obj) -> str:
    """Strict JSON: a number that is not finite (NaN, inf) is written ``null`` (JSON has no
    NaN); the command's own fields say why (e.g. ``dynamics``' ``singular`` flag)."""
    try:
        return json.dumps(obj, allow_nan=False)
    except ValueError:  # a NaN or an infinity somewhere: the slow path
        return json.dumps(_json_safe(obj), allow_nan=False)


def _json_safe(obj):
    """``obj`` with every non-finite float replaced by None (numpy scalars and arrays too)."""
    if isinstance(obj, dict):
        return {k: _json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_json_safe(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _json_safe(obj.tolist())
    if isinstance(obj, (float, np.floating)):
        return float(obj) if math.isfinite(obj) else None
    return obj


def _print_json(mech, fields: dict) -> None:
    """One JSON object on stdout: the mechanism, its parameters, then ``fields``."""
    print(_dumps({"mechanism": mech.name, "parameters": mech.parameters(), **fields}))


def _batch(values: Sequence[float], n: int, what: str, names: Sequence[str]) -> np.ndarray:
    if len(values) == 0 or len(values) % n:
        raise ValueError(
            f"{what} needs a multiple of {n} values ({', '.join(names)}), got {len(values)}"
        )
    a = np.asarray(values, dtype=float).reshape(-1, n)
    return a[0] if len(a) == 1 else a


def _units(mech, kind: str, paper: bool) -> tuple[str, ...]:
    return getattr(mech, f"paper_{kind}_units" if paper else f"{kind}_units")


def _unit(u: str) -> str:
    """A unit as printed after a value: nothing for a dimensionless one (``"1"``)."""
    return "" if u == "1" else f" {u}"


def _fmt_vector(names, values, units) -> str:
    """``name = value unit`` per entry (no unit where dimensionless); values in a form the options
    read back (``-2.1e-17`` too)."""
    return "  ".join(f"{n} = {v:.10g}{_unit(u)}" for n, v, u in zip(names, values, units))


def _units_note(mech, command: str, paper: bool) -> None:
    """``--units paper`` where the paper prints SI: say so (once, on stderr) instead of silently
    printing the same numbers."""
    if (
        paper
        and mech.paper_pose_units == mech.pose_units
        and mech.paper_joint_units == mech.joint_units
    ):
        units = (
            ", ".join(sorted(set(mech.pose_units + mech.joint_units) - {"1"})) or "dimensionless"
        )
        print(
            f"parakin {command}: note: the paper prints {mech.name} poses and joints in SI units ({units}), "
            "so --units paper is the same as --units si",
            file=sys.stderr,
        )


def _inputs(args, mech, what: str, paper: bool) -> tuple[np.ndarray, np.ndarray]:
    """The values of ``--pose``/``--joints`` (one vector or a batch) or of ``--input FILE``, as
    given (in ``--units``) and in SI, every one finite and every angle within :data:`ANGLE_LIMIT`."""
    kind = "pose" if what == "pose" else "joint"
    names, units = getattr(mech, f"{kind}_names"), _units(mech, kind, paper)
    values = getattr(args, what)
    if args.input is not None:
        if values is not None:
            raise ValueError(f"give --{what} or --input, not both")
        given = read_rows(args.input, names, units)
    elif values is None:
        raise ValueError(f"give --{what} VALUES or --input FILE (CSV or .npy, one row each)")
    else:
        given = _batch(values, len(names), f"--{what}", names)
    option = f"--{what}" if args.input is None else f"--input {args.input}"
    _angles(given, names, units, option)
    _compiled_if_worth_it(len(given))
    return given, _finite(to_si(given, units), f"{option} in SI units", given)


#: a command with fewer inputs runs the kernels on numpy: loading compiled code costs 0.5-1 s per
#: process (minutes on an empty cache), more than numpy takes for a few hundred inputs
#: (``PARAKIN_KERNELS=1`` compiles anyway, ``=0`` never)
COMPILED_MIN_INPUTS = 256


def _compiled_if_worth_it(n_inputs: int) -> None:
    """For the rest of this command: the numpy path below :data:`COMPILED_MIN_INPUTS` inputs."""
    if n_inputs < COMPILED_MIN_INPUTS and os.environ.get("PARAKIN_KERNELS") != "1":
        kernels.use_interpreted()


def _text_option(p, flag: str, **kwargs) -> None:
    """An option that takes a non-empty text (a file, a folder, a name); None when not given."""
    p.add_argument(flag, type=nonempty, default=None, **kwargs)


def _mechanism_options(p) -> None:
    """The mechanism and its geometry: ``MECH [--param NAME=VALUE]... [--geometry FILE]``, or
    ``--mechanism FILE`` (a described mechanism); :func:`mechanism_of` reads them."""
    p.add_argument(
        "mechanism",
        nargs="?",
        default=None,
        choices=sorted(mechanisms.REGISTRY),
        help="mechanism name (or --mechanism FILE)",
    )
    _text_option(
        p,
        "--mechanism",
        dest="mechanism_file",
        metavar="FILE",
        help="a mechanism described in a YAML or JSON file instead of a name: its platform and "
        "legs (length, slider-rod, crank-rod), e.g. examples/delta.yaml (docs/mechanism_file.md)",
    )
    p.add_argument(
        "--param",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="set a mechanism parameter, by its name in the Python API: a number (SI, or with "
        "a unit: phi=35deg, d=120mm) or an array as a YAML/JSON list (base=[[0,0,0],...])",
    )
    _text_option(
        p,
        "--geometry",
        metavar="FILE",
        help="the mechanism's parameters from a YAML or JSON file (names of the Python API, "
        "arrays as lists); --param values override them",
    )


def _mechanism_args(p) -> None:
    _mechanism_options(p)
    p.add_argument(
        "--units", choices=["si", "paper"], default="si", help="units of input and output"
    )
    p.add_argument("--json", action="store_true", help="print a JSON object")


def _file_args(p, what: str) -> None:
    _text_option(
        p,
        "--input",
        metavar="FILE",
        help=f"read many {what}s from FILE (.csv, optional header 'name [unit]', or .npy), one per row",
    )
    _text_option(
        p,
        "--output",
        metavar="FILE",
        help="write the results to FILE (.csv with a header, or .npy) instead of printing them",
    )


def _config_overlays(p) -> None:
    """``--config YAML`` (repeatable): overlays on config/config.yaml."""
    p.add_argument(
        "--config",
        action="append",
        type=nonempty,
        default=None,
        metavar="YAML",
        help="config overlay(s) merged onto config/config.yaml in order, as snakemake "
        "--configfile (e.g. config/quick.yaml)",
    )


def _config_args(p) -> None:
    _config_overlays(p)
    _text_option(
        p,
        "--config-json",
        help="the whole config as JSON (what Snakemake passes)",
    )
    p.add_argument(
        "--validated",
        action="store_true",
        help="the --config-json sections were validated by the pipeline (workflow/rules/common.smk "
        "validates the whole config once); skip validating them again",
    )
