"""Pipeline configuration: YAML files merged in order and validated against config/schema.yaml."""

from __future__ import annotations

import copy
import json
import zlib
from pathlib import Path
from typing import Any, Iterable

import jsonschema
import yaml

from parakin.errors import ConfigError

__all__ = ["load_config", "validate", "merge", "rng", "seed_for", "ROOT", "SCHEMA_PATH", "DEFAULT_CONFIG", "QUICK_CONFIG"]

ROOT = Path(__file__).resolve().parents[2]
SCHEMA_PATH = ROOT / "config" / "schema.yaml"
DEFAULT_CONFIG = ROOT / "config" / "config.yaml"
QUICK_CONFIG = ROOT / "config" / "quick.yaml"


def merge(base: dict, override: dict) -> dict:
    """Deep merge: ``override``'s leaves replace ``base``'s (as Snakemake merges --configfile)."""
    out = copy.deepcopy(base)
    for key, value in override.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = merge(out[key], value)
        else:
            out[key] = copy.deepcopy(value)
    return out


def _describe(error: jsonschema.ValidationError) -> str:
    key = ".".join(str(p) for p in error.absolute_path) or "(top level)"
    where = f"config key '{key}'"
    if error.validator == "additionalProperties":
        return f"{where}: {error.message} (see config/schema.yaml for the allowed keys)"
    if error.validator == "required":
        return f"{where}: {error.message}"
    limits = {k: error.schema[k] for k in ("minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum",
                                           "minItems", "maxItems", "type", "enum") if k in error.schema}
    allowed = ", ".join(f"{k} {v}" for k, v in limits.items())
    return f"{where} = {json.dumps(error.instance)}: {error.message}" + (f" (allowed: {allowed})" if allowed else "")


def validate(config: dict, schema_path: Path = SCHEMA_PATH) -> dict:
    """Validate ``config``; raise ConfigError naming the key, the value and the allowed range."""
    schema = yaml.safe_load(Path(schema_path).read_text())
    validator = jsonschema.Draft202012Validator(schema)
    errors = sorted(validator.iter_errors(config), key=lambda e: list(map(str, e.absolute_path)))
    if errors:
        raise ConfigError("; ".join(_describe(e) for e in errors))
    for section in ("fit", "region"):
        for key in ("delta_range", "phi_range_deg"):
            lo, hi = config["zhao2017_3p4s"]["table1"][section][key]
            if not lo < hi:
                raise ConfigError(f"config key 'zhao2017_3p4s.table1.{section}.{key}' = [{lo}, {hi}]: "
                                  "lower bound must be < upper bound")
    return config


def load_config(paths: str | Path | Iterable[str | Path] = DEFAULT_CONFIG) -> dict[str, Any]:
    """Load YAML files (later ones override earlier ones, like Snakemake's --configfile), validate."""
    if isinstance(paths, (str, Path)):
        paths = [paths]
    config: dict[str, Any] = {}
    for path in paths:
        path = Path(path)
        if not path.is_file():
            raise ConfigError(f"config file {str(path)!r} does not exist")
        loaded = yaml.safe_load(path.read_text()) or {}
        if not isinstance(loaded, dict):
            raise ConfigError(f"config file {str(path)!r} must hold a mapping, got {type(loaded).__name__}")
        config = merge(config, loaded)
    return validate(config)


def seed_for(config: dict, stream: str) -> int:
    """A seed for the named random ``stream`` (e.g. ``"zhao2017_3p4s.samples"``), derived from
    the config's master seed, so that streams are independent and stable under reordering."""
    return int(config["seed"]) * 1_000_003 + zlib.crc32(stream.encode())


def rng(config: dict, stream: str):
    """``numpy.random.Generator`` of the named stream (see :func:`seed_for`)."""
    import numpy as np

    return np.random.default_rng(seed_for(config, stream))
