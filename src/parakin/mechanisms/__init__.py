"""Mechanisms: one module each, all implementing :class:`parakin.mechanisms.base.Mechanism`."""

from parakin.mechanisms.base import Mechanism
from parakin.mechanisms.p3p4s import P3P4S
from parakin.mechanisms.stewart12 import Stewart12
from parakin.mechanisms.stewart36 import Stewart36
from parakin.mechanisms.stewart66 import Stewart66
from parakin.mechanisms.ups2 import UPS2

#: CLI name -> mechanism class
REGISTRY: dict[str, type[Mechanism]] = {
    P3P4S.name: P3P4S,
    UPS2.name: UPS2,
    Stewart36.name: Stewart36,
    Stewart12.name: Stewart12,
    Stewart66.name: Stewart66,
}


def get(name: str) -> type[Mechanism]:
    """The mechanism class registered under CLI name ``name``."""
    try:
        return REGISTRY[name]
    except KeyError:
        raise KeyError(
            f"unknown mechanism {name!r}; known: {', '.join(sorted(REGISTRY))}"
        ) from None


__all__ = ["Mechanism", "P3P4S", "UPS2", "Stewart36", "Stewart12", "Stewart66", "REGISTRY", "get"]
