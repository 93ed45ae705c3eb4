"""Mechanisms: one module each, all implementing :class:`parakin.mechanisms.base.Mechanism`.

A mechanism registers itself when its class is defined (a subclass of ``Mechanism`` that declares
a ``name``): :data:`REGISTRY` maps CLI names to classes, in the order the modules are imported.
Every module of this package is listed once, in :data:`MODULES` (mechanism modules, imported by
:func:`discover` when this package is) or in :data:`HELPERS` (the protocol, a mechanism's helpers,
and the described mechanisms of :mod:`parakin.mechanisms.described`, which a file names rather
than the registry): a module in neither is an error at import, never skipped in silence. Adding a
mechanism module is adding it here too.

A leg-driven mechanism needs no module at all: :func:`from_file` reads its description (YAML or
JSON; docs/mechanism_file.md).
"""

import pkgutil
from importlib import import_module

from parakin.mechanisms.base import REGISTRY, Mechanism
from parakin.mechanisms.described import Described, from_file
from parakin.mechanisms.p3p4s import P3P4S
from parakin.mechanisms.stewart12 import Stewart12
from parakin.mechanisms.stewart36 import Stewart36
from parakin.mechanisms.stewart66 import Stewart66
from parakin.mechanisms.ups2 import UPS2

__all__ = [
    "HELPERS",
    "MODULES",
    "REGISTRY",
    "Described",
    "Mechanism",
    "P3P4S",
    "UPS2",
    "Stewart12",
    "Stewart36",
    "Stewart66",
    "discover",
    "from_file",
    "get",
    "names",
    "unlisted_modules",
]

#: the mechanism modules, imported by :func:`discover` (their classes register themselves)
MODULES = ("p3p4s", "ups2", "stewart12", "stewart36", "stewart66", "rpr3")
#: every other module of the package: the protocol, the described mechanisms (named by a file,
#: not registered) and the mechanisms' helpers, imported by the modules that use them
HELPERS = (
    "base",
    "described",
    "p3p4s_dynamics",
    "p3p4s_indices",
    "p3p4s_mujoco",
    "stewart66_homotopy",
    "stewart66_legs",
    "stewart66_peers",
)


def unlisted_modules() -> list[str]:
    """The modules of this package in neither :data:`MODULES` nor :data:`HELPERS`."""
    listed = set(MODULES) | set(HELPERS)
    return sorted(info.name for info in pkgutil.iter_modules(__path__) if info.name not in listed)


def discover() -> dict[str, type[Mechanism]]:
    """Import every module of :data:`MODULES` and return :data:`REGISTRY` (their classes register
    themselves as they are defined; a module imported before is not run again). A module of this
    package listed nowhere is an ImportError naming it: nothing is skipped in silence."""
    unlisted = unlisted_modules()
    if unlisted:
        raise ImportError(
            f"parakin.mechanisms: module(s) {', '.join(unlisted)} are listed neither in MODULES "
            "(mechanism modules, imported and registered) nor in HELPERS (src/parakin/mechanisms/"
            "__init__.py): add each to the one it belongs to"
        )
    for name in MODULES:
        import_module(f"{__name__}.{name}")
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
