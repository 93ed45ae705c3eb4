"""Mechanisms: one module each, all implementing :class:`parakin.mechanisms.base.Mechanism`.

A mechanism registers itself when its class is defined (a subclass of ``Mechanism`` that declares
a ``name``): :data:`REGISTRY` maps CLI names to classes, in the order the modules are imported.
The mechanisms of the four papers and the 6-6 platform are imported here by name (the public
API); every other module of this package named without an underscore (``<name>.py``; a
mechanism's helpers are ``<name>_<what>.py``) is a mechanism module too, imported by
:func:`discover` when this package is: adding a mechanism is adding its module, nothing here
changes.
"""

import pkgutil
from importlib import import_module

from parakin.mechanisms.base import REGISTRY, Mechanism
from parakin.mechanisms.p3p4s import P3P4S
from parakin.mechanisms.stewart12 import Stewart12
from parakin.mechanisms.stewart36 import Stewart36
from parakin.mechanisms.stewart66 import Stewart66
from parakin.mechanisms.ups2 import UPS2

__all__ = [
    "REGISTRY",
    "Mechanism",
    "P3P4S",
    "UPS2",
    "Stewart12",
    "Stewart36",
    "Stewart66",
    "discover",
    "get",
    "names",
]


def discover() -> dict[str, type[Mechanism]]:
    """Import every mechanism module of this package and return :data:`REGISTRY` (their classes
    register themselves as they are defined; a module imported before is not run again)."""
    for info in pkgutil.iter_modules(__path__):
        if "_" not in info.name and info.name != "base":
            import_module(f"{__name__}.{info.name}")
    return REGISTRY


def names() -> list[str]:
    """The CLI names of every registered mechanism, in registration order."""
    return list(REGISTRY)


def get(name: str) -> type[Mechanism]:
    """The mechanism class registered under CLI name ``name``."""
    try:
        return REGISTRY[name]
    except KeyError:
        raise KeyError(
            f"unknown mechanism {name!r}; known: {', '.join(sorted(REGISTRY))}"
        ) from None


discover()
