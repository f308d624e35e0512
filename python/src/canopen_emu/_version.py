"""The package's version: the project's (include/co/co_version.h, CHANGELOG.md).

Hard-coded on purpose, so that nothing is read at run time; pyproject.toml takes it from here and
python/tests/test_version.py holds it equal to CO_VERSION_STRING."""

__version__ = "0.1.0"
