"""The touch-probe nuisance terms of a described machine's campaign (SPEC §19, docs/machines.md).

Per stylus: the stylus-ball centre's offset across the spindle axis (``xS, yS, zS`` less the one along the
spindle: that one is the length error ``dRS``).  Per run: where its sphere sits on the workpiece side
(``xP, yP, zP``, at the home pose): placed by hand, a few hundred µm; the indexed positions turn it about the
axes and so tell it from their location errors.
"""

from __future__ import annotations

from .description import FRAME, MachineDescription

#: a probed sphere's placement, by frame axis
SPHERE_TERMS = ("xP", "yP", "zP")


def stylus_terms(desc: MachineDescription) -> tuple[str, ...]:
    """The nuisance terms of one stylus: its centring across the spindle, then its length error."""
    along = FRAME[desc.spindle.frame_axis].lower()
    return tuple(f"{a}S" for a in "xyz" if a != along) + ("dRS",)


def probe_terms(desc: MachineDescription, probe) -> list[tuple[str, str]]:
    """``(owner, base)`` pairs of a described campaign's probe: each stylus used, then each run's sphere."""
    used = list(dict.fromkeys(run.stylus for run in probe.runs))
    return [(s, b) for s in used for b in stylus_terms(desc)] + \
        [(run.id, b) for run in probe.runs for b in SPHERE_TERMS]
