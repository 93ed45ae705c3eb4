"""parakin: kinematics, dynamics and design optimisation of parallel mechanisms, reproducing four
published papers (see README.md)."""

__version__ = "0.1.0"  # the package version (pyproject.toml reads it from here)

__all__ = ["__version__"]
