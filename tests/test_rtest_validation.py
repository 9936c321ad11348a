"""Validation of the R-test (issue 43, docs/rtest.md): the tables of what a one-sphere static R-test campaign
determines on each built-in type are the ones the Jacobian gives (bench/rtest_determines.py)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "rtest.md"


def _bench(name: str):
    """A bench script as a module (bench/ is not a package)."""
    spec = importlib.util.spec_from_file_location(name, ROOT / "bench" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


DETERMINES = _bench("rtest_determines")


def _doc_section(machine: str) -> str:
    """The text of ``machine``'s part of docs/rtest.md's "What a one-sphere static R-test campaign determines"."""
    text = DOC.read_text(encoding="utf-8")
    section = text[text.index("## What a one-sphere static R-test campaign determines"):]
    section = section[:section.index("\n## ", 1)]
    part = section[section.index(f"### `{machine}`"):]
    return part[:part.index("\n### ", 1)] if "\n### " in part[1:] else part


@pytest.mark.parametrize("machine", DETERMINES.TYPES)
def test_the_documented_table_is_the_computed_one(machine):
    """Each type's table in the docs is the one computed from the campaign's Jacobian now (over the machine's
    default selection of deviations, for the four settings of frame and zero), and its runs line the campaign's."""
    part = _doc_section(machine)
    assert DETERMINES.table(machine) in part
    assert f"runs (°): {DETERMINES.runs(machine)}" in part


def test_the_table_covers_every_deviation_and_setting():
    """The table is not empty of verdicts: each type's campaign determines some deviations and leaves some out, and
    each row names a verdict for every setting."""
    for machine in DETERMINES.TYPES:
        by = DETERMINES.verdicts(machine)
        for ident in by.values():
            assert ident.determined and ident.undetermined
            named = set(ident.determined) | set(ident.undetermined) | {n for c in ident.combinations for n in c.weights}
            assert named == set(ident.deviations)
