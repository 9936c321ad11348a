"""The package version: one place, read by pyproject.toml, the report and ``mtmcal-bayes --version``."""

__version__ = "0.1.0"
