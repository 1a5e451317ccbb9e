"""The version of this source tree (``skidnav.__version__``), kept equal to ``pyproject.toml``'s
and to the newest release of CHANGELOG.md (tests/test_version.py). An installed package reports
its version from its metadata (:func:`skidnav.experiments.provenance.skidnav_version`)."""

__version__ = "0.1.0"
