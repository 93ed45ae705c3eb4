"""Pipeline configuration: YAML files merged in order and validated against config/schema.yaml.

Loading is bounded before anything walks the tree, by the loader every YAML/JSON input of parakin
shares (:func:`parakin.io.load_data`): a config file is a regular file of at most
:data:`MAX_CONFIG_BYTES`, UTF-8, and its YAML expands (every alias repeated where it points) to at
most :data:`MAX_CONFIG_VALUES` values nested at most :data:`MAX_CONFIG_DEPTH` deep, counted on the
parser's events without expanding or building anything; a file that breaks a bound is one
ConfigError line, at once.
:func:`load_run_config` merges overlays onto ``config/config.yaml`` the way Snakemake merges
``--configfile`` onto the Snakefile's ``configfile:`` (what ``parakin reproduce|check|report
--config`` and the pipeline all do).
"""

from __future__ import annotations

import copy
import functools
import json
import math
import sys
import zlib
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import yaml

from parakin import io as _io
from parakin.errors import ConfigError

__all__ = [
    "load_config",
    "load_run_config",
    "check_bounds",
    "validate",
    "merge",
    "rng",
    "seed_for",
    "ROOT",
    "SCHEMA_PATH",
    "DEFAULT_CONFIG",
    "QUICK_CONFIG",
]

_CHECKOUT = Path(__file__).resolve().parents[2]
#: The project tree that holds ``config/`` and ``data/reference/``: the checkout (tests, Snakemake,
#: an editable install), or, for parakin installed from a wheel, the copy that the build ships
#: inside the package (``parakin/_project/``, same layout; see setup.py).
ROOT = (
    _CHECKOUT
    if (_CHECKOUT / "pyproject.toml").is_file() and (_CHECKOUT / "config" / "schema.yaml").is_file()
    else Path(__file__).resolve().parent / "_project"
)
SCHEMA_PATH = ROOT / "config" / "schema.yaml"
DEFAULT_CONFIG = ROOT / "config" / "config.yaml"
QUICK_CONFIG = ROOT / "config" / "quick.yaml"


#: largest config file (the full config is about 15 kB): the bound of every YAML/JSON input
MAX_CONFIG_BYTES = _io.MAX_DATA_BYTES
#: most values a config may expand to (the full config holds about 300): YAML aliases repeat a
#: node wherever they point, so 700 bytes of nested aliases expand to ~10^11 values
MAX_CONFIG_VALUES = _io.MAX_DATA_VALUES
#: deepest nesting of a config (the full config nests 5 deep)
MAX_CONFIG_DEPTH = _io.MAX_DATA_DEPTH


def check_bounds(config: Any, where: str = "config") -> None:
    """Raise ConfigError where ``config`` expands to more than :data:`MAX_CONFIG_VALUES` values,
    nests deeper than :data:`MAX_CONFIG_DEPTH` or refers to itself (:func:`parakin.io.check_data`:
    each shared node, an alias target, counted once and multiplied, so a bomb is measured
    without being expanded)."""
    _io.check_data(config, where, error=ConfigError)


def merge(base: dict, override: dict) -> dict:
    """Deep merge: ``override``'s leaves replace ``base``'s (as Snakemake merges --configfile)."""
    out = copy.deepcopy(base)
    for key, value in override.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = merge(out[key], value)
        else:
            out[key] = copy.deepcopy(value)
    return out


def _short(text: str, limit: int = 80) -> str:
    """``text`` on one line, cut to ``limit`` characters (a config error never dumps a whole section)."""
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _describe(error) -> str:
    key = ".".join(str(p) for p in error.absolute_path) or "(top level)"
    where = f"config key '{key}'"
    message = _short(error.message, 160)
    if error.validator == "additionalProperties":
        return f"{where}: {message} (see config/schema.yaml for the allowed keys)"
    if error.validator == "required":
        return f"{where}: {message}"
    limits = {
        k: error.schema[k]
        for k in (
            "minimum",
            "maximum",
            "exclusiveMinimum",
            "exclusiveMaximum",
            "minItems",
            "maxItems",
            "type",
            "enum",
        )
        if k in error.schema
    }
    allowed = _short(", ".join(f"{k} {v}" for k, v in limits.items()), 120)
    value = _short(json.dumps(error.instance, default=str))
    return f"{where} = {value}: {message}" + (f" (allowed: {allowed})" if allowed else "")


def _one_per_key(errors: list) -> list:
    """The first error of each config key (jsonschema may report several for one bad value)."""
    seen, out = set(), []
    for e in errors:
        key = tuple(map(str, e.absolute_path))
        if key not in seen:
            seen.add(key)
            out.append(e)
    return out


def _nonfinite(node: Any, path: str = "") -> list[str]:
    """Keys whose value is a non-finite number (YAML .inf / .nan pass a JSON schema's range tests)."""
    if isinstance(node, dict):
        return [
            k
            for key, v in node.items()
            for k in _nonfinite(v, f"{path}.{key}" if path else str(key))
        ]
    if isinstance(node, list):
        return [k for i, v in enumerate(node) for k in _nonfinite(v, f"{path}.{i}")]
    if isinstance(node, float) and not math.isfinite(node):
        return [f"config key '{path}' = {node}: must be a finite number"]
    return []


def _get(config: dict, dotted: str) -> Any:
    node: Any = config
    for key in dotted.split("."):
        if not isinstance(node, dict) or key not in node:
            return None
        node = node[key]
    return node


#: [low, high] pairs that must be ordered (what the code would otherwise fail on at run time)
_ORDERED_PAIRS = [
    "zhao2017_3p4s.table1.fit.delta_range",
    "zhao2017_3p4s.table1.fit.phi_range_deg",
    "zhao2017_3p4s.table1.region.delta_range",
    "zhao2017_3p4s.table1.region.phi_range_deg",
    *(f"zhao2017_3p4s.optimization.bounds.{k}" for k in ("r_a", "r_b", "L", "d", "phi_deg")),
]
#: most points of one generated grid (a tiny step would ask for petabytes)
GRID_LIMIT = 100_000


def check_orderings(config: dict) -> list[str]:
    """Cross-key checks a JSON schema cannot state: ordered bounds, grid sizes (missing keys skipped)."""
    out = []
    for key in _ORDERED_PAIRS:
        pair = _get(config, key)
        if isinstance(pair, list) and len(pair) == 2 and not pair[0] < pair[1]:
            out.append(f"config key '{key}' = {pair}: lower bound must be < upper bound")
    for i, part in enumerate(_get(config, "ye_stewart12.d_grid_pct") or []):
        out += (
            _grid(f"ye_stewart12.d_grid_pct.{i}", *part)
            if isinstance(part, list) and len(part) == 3
            else []
        )
    s = _get(config, "ye_stewart12.structures_mm")
    if isinstance(s, dict) and {"min", "max", "step"} <= set(s):
        out += _grid("ye_stewart12.structures_mm", s["min"], s["max"], s["step"])
    for i, box in enumerate(_get(config, "zhao2017_3p4s.fk.accuracy_boxes") or []):
        lo, hi = box.get("low"), box.get("high")
        if isinstance(lo, list) and isinstance(hi, list) and not all(a < b for a, b in zip(lo, hi)):
            out.append(
                f"config key 'zhao2017_3p4s.fk.accuracy_boxes.{i}' low {lo} must be < high {hi} per axis"
            )
    return out


def _grid(key: str, start: float, stop: float, step: float) -> list[str]:
    if not start <= stop:
        return [f"config key '{key}': start {start} must be <= stop {stop}"]
    points = (stop - start) / step + 1 if step > 0 else math.inf
    if not points <= GRID_LIMIT:
        return [
            f"config key '{key}' = [{start}, {stop}, step {step}]: {points:.3g} points, more than the limit "
            f"{GRID_LIMIT}"
        ]
    return []


def validate(config: dict, schema_path: Path = SCHEMA_PATH, *, partial: bool = False) -> dict:
    """Validate ``config``; raise ConfigError naming the key, the value and the allowed range.

    ``partial``: ``config`` holds only some sections (what one pipeline rule receives,
    :func:`parakin.registry.prune_config`); the keys it has obey the same rules, the sections it
    lacks are not required."""
    check_bounds(config)
    schema = _schema(str(schema_path), Path(schema_path).stat().st_mtime_ns)
    if partial:
        schema = _relax_required(schema, config)
    validator = _jsonschema().Draft202012Validator(schema)
    errors = sorted(validator.iter_errors(config), key=lambda e: list(map(str, e.absolute_path)))
    problems = [_describe(e) for e in _one_per_key(errors)] + _nonfinite(config)
    if not problems:
        problems = check_orderings(config)
    if problems:
        raise ConfigError("; ".join(problems))
    return config


#: optional libraries of jsonschema's format checkers that cost seconds to import: rfc3987-syntax
#: builds a lark grammar of RFC 3987 (1.4-1.8 CPU-s, more than the rest of a Snakemake start's
#: parsing). It comes with jupyter (jsonschema[format-nongpl]); parakin checks no formats
_COSTLY_FORMAT_LIBRARIES = ("rfc3987_syntax",)


def _jsonschema() -> Any:
    """jsonschema, imported (where this process has not yet) without the costly optional format
    libraries: the validators here get no format checker, so none of them is ever used. The block
    lasts for the import only; a later ``import rfc3987_syntax`` works as usual."""
    if "jsonschema" not in sys.modules:
        blocked = [name for name in _COSTLY_FORMAT_LIBRARIES if name not in sys.modules]
        sys.modules.update(dict.fromkeys(blocked))  # None: "import name" raises ImportError
        try:
            import jsonschema  # noqa: F401
        finally:
            for name in blocked:
                if sys.modules.get(name, 0) is None:
                    del sys.modules[name]
    return sys.modules["jsonschema"]


@functools.lru_cache(maxsize=4)
def _schema(path: str, mtime_ns: int) -> dict:
    """The parsed schema (read again when the file changes); callers never modify it."""
    return _yaml(Path(path).read_text())


def _yaml(text: str) -> Any:
    """``yaml.safe_load`` with libyaml's parser where installed (5-10x faster, same result)."""
    return yaml.load(text, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))


def load_config(paths: str | Path | Iterable[str | Path] = DEFAULT_CONFIG) -> dict[str, Any]:
    """Load YAML files (later ones override earlier ones, like Snakemake's --configfile), validate.

    Every file is read within the bounds of :func:`check_bounds`; see :func:`load_run_config` for
    overlays on the full config."""
    if isinstance(paths, (str, Path)):
        paths = [paths]
    config: dict[str, Any] = {}
    for path in paths:
        config = merge(config, _load_yaml(Path(path)))
    return validate(config)


def load_run_config(overlays: Iterable[str | Path] = ()) -> dict[str, Any]:
    """``config/config.yaml`` with each of ``overlays`` merged on top (e.g. ``config/quick.yaml``),
    validated: the config a pipeline run ``snakemake --configfile OVERLAY ...`` sees."""
    return load_config([DEFAULT_CONFIG, *overlays])


def _load_yaml(path: Path) -> dict[str, Any]:
    """One config file's mapping, read within the bounds (a regular file, size, UTF-8, depth,
    aliases, expansion: :func:`parakin.io.load_data`)."""
    name = f"config file {str(path)!r}"
    loaded = _io.load_data(path, name, error=ConfigError)
    if loaded is None:
        return {}
    if not isinstance(loaded, dict):
        raise ConfigError(f"{name} must hold a mapping, got {type(loaded).__name__}")
    return loaded


def seed_for(config: dict, stream: str) -> int:
    """A seed for the named random ``stream`` (e.g. ``"zhao2017_3p4s.samples"``), derived from
    the config's master seed, so that streams are independent and stable under reordering."""
    return int(config["seed"]) * 1_000_003 + zlib.crc32(stream.encode())


def rng(config: dict, stream: str):
    """``numpy.random.Generator`` of the named stream (see :func:`seed_for`)."""
    import numpy as np

    return np.random.default_rng(seed_for(config, stream))


def _relax_required(schema: Any, config: Any) -> Any:
    """A copy of ``schema`` whose ``required`` lists keep only the keys ``config`` has (recursively)."""
    if isinstance(schema, list):
        return [_relax_required(s, config) for s in schema]
    if not isinstance(schema, dict):
        return schema
    out = {}
    for key, value in schema.items():
        if key == "required" and isinstance(value, list) and isinstance(config, dict):
            out[key] = [k for k in value if k in config]
        elif key == "properties" and isinstance(value, dict):
            sub = config if isinstance(config, dict) else {}
            out[key] = {k: _relax_required(v, sub.get(k)) for k, v in value.items()}
        else:
            out[key] = value
    return out


def validate_sections(config: dict, schema_path: Path = SCHEMA_PATH) -> dict:
    """:func:`validate` of a config pruned to some sections."""
    return validate(config, schema_path, partial=True)
