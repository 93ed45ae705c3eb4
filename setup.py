"""Build hook: ship the project's top-level run-time files inside the package.

Snakemake reads ``config/config.yaml``, ``config/quick.yaml`` and ``config/schema.yaml`` at the
top of the checkout, and ``parakin report`` reads ``data/reference/*.csv``; an installed parakin
(``pip install .``, a wheel) needs them too. Rather than keeping a second copy in git, the build
copies them into ``parakin/_project/`` with the checkout's layout (``_project/config/…``,
``_project/data/reference/…``); :data:`parakin.config.ROOT` points there when parakin does not
run from a checkout. Everything else (metadata, dependencies) is in ``pyproject.toml``.
"""

from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

HERE = Path(__file__).resolve().parent
#: folder of the checkout -> files of it that the installed package needs (also in MANIFEST.in)
SHIPPED = {"config": "*.yaml", "data/reference": "*.csv"}


class BuildPy(build_py):
    """``build_py`` that also copies :data:`SHIPPED` into ``parakin/_project/``."""

    def run(self):
        super().run()
        if getattr(self, "editable_mode", False):  # an editable install reads the checkout itself
            return
        for folder, pattern in SHIPPED.items():
            files = sorted((HERE / folder).glob(pattern))
            if not files:
                raise FileNotFoundError(f"no {folder}/{pattern} to ship in the package")
            target = Path(self.build_lib) / "parakin" / "_project" / folder
            self.mkpath(str(target))
            for src in files:
                self.copy_file(str(src), str(target / src.name))


setup(cmdclass={"build_py": BuildPy})
