"""The ``angles_deg`` of a probe or R-test run: one list of angles per rotary axis of the machine, one angle per
position, every list the same length."""

from __future__ import annotations

import numpy as np

from ..machines.description import MachineDescription
from .toml_reader import TomlReader


def read_run_angles(r: TomlReader, t: dict, path: str, desc: MachineDescription, *, example: str
                    ) -> tuple[dict[str, np.ndarray], int]:
    """``t["angles_deg"]`` of the run at ``path``: ``({letter: (k,) degrees}, k)``; ``example`` shows the form in the
    error where the table is missing.  An unknown or non-rotary letter, or lists of different lengths: one line
    naming the key."""
    a = t.get("angles_deg")
    if not isinstance(a, dict) or not a:
        r.fail(f"{path}.angles_deg", f"expected a table of rotary axis -> list of angles, e.g. {example}")
    angles = {}
    for letter in a:
        ax = desc.axes.get(letter)
        if ax is None or not ax.rotary:
            r.fail(f"{path}.angles_deg.{letter}", f"not a rotary axis of this machine "
                   f"({', '.join(x.letter for x in desc.rotary_axes)})")
        angles[letter] = r.array(a, letter, f"{path}.angles_deg", (None,))
    sizes = {len(v) for v in angles.values()}
    if len(sizes) > 1:
        r.fail(f"{path}.angles_deg", "every axis needs one angle per position: the lists differ in length")
    return angles, sizes.pop()
