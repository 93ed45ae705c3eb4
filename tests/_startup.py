"""Loaded before every other plugin (``-p _startup`` first in pyproject's ``addopts``; ``pythonpath``
puts ``tests/`` on the path first): jsonschema imported without the costly optional format
library rfc3987-syntax (:func:`parakin.config._jsonschema`). nbmake imports jsonschema (through
nbformat) when it loads, in the controller and in every xdist worker, and rfc3987-syntax builds a
grammar at import: about 1 CPU-s in each of those processes before the first test, on the path of
every run. No test checks a format; a test that imports rfc3987_syntax itself still can."""

from parakin.config import _jsonschema

_jsonschema()
