"""A script of the repository (bench/, examples/: not packages) loaded as a module, for the tests that hold the docs
or the package data to what the script computes or writes."""

from __future__ import annotations

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def load_script(path: Path):
    """The script at ``path`` as a module (run once, as an import would)."""
    spec = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def bench_script(name: str):
    """``bench/<name>.py`` as a module."""
    return load_script(ROOT / "bench" / f"{name}.py")
