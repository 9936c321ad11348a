"""Draw docs/figures/machine_<type>.png and docs/figures/deviations_<type>.png for each built-in machine type: its
chain at the home pose and what its location errors mean (docs/machines.md).  Run from the repository root:

    python docs/figures/make_machine_figures.py
"""

from __future__ import annotations

from pathlib import Path

from mtmcal_bayes.io.machine_reader import BUILTIN_TYPES, builtin_description
from mtmcal_bayes.reporting.machine_figure import draw_chain, draw_deviations

OUT = Path(__file__).parent


def main() -> None:
    for name in BUILTIN_TYPES:
        desc = builtin_description(name)
        for path in (draw_chain(desc, OUT / f"machine_{name}.png"),
                     draw_deviations(desc, OUT / f"deviations_{name}.png")):
            print(path)


if __name__ == "__main__":
    main()
