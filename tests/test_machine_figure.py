"""The figures of a described machine (docs/machines.md): its chain at the home pose."""

from __future__ import annotations

from PIL import Image

from mtmcal_bayes.io.machine_reader import builtin_description
from mtmcal_bayes.reporting.machine_figure import draw_chain


def test_draw_chain_writes_a_png(tmp_path):
    path = draw_chain(builtin_description("trunnion"), tmp_path / "machine.png")
    assert path.stat().st_size > 10_000
    with Image.open(path) as img:
        assert img.format == "PNG" and min(img.size) > 500
