"""Exceptions raised by parakin: every one names the offending value and the limit it broke."""

from __future__ import annotations


class ParakinError(Exception):
    """Base class of all parakin errors."""


class UnreachableError(ParakinError, ValueError):
    """A pose or a joint vector lies outside what the mechanism can assemble."""


class SingularityError(ParakinError, ValueError):
    """A Jacobian is singular (or numerically so) at the requested configuration."""


class ConfigError(ParakinError, ValueError):
    """A configuration file is malformed: names the key and the allowed range."""


class ShapeError(ParakinError, ValueError):
    """An array has the wrong trailing dimension for the mechanism."""


class InputError(ParakinError, ValueError):
    """An input (a file, a ``--param`` value) breaks a bound or is malformed: names the input and
    the limit (:func:`parakin.io.load_data`)."""
