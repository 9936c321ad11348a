"""The touch probe's nuisance terms: one owner rule for every campaign (SPEC §19, docs/machines.md).

Per stylus (owner: its id): the stylus-ball centre's offset across the spindle axis (``xS, yS, zS`` less the one
along the spindle: that one is the length error ``dRS``), unless its runs state their own (the thesis' ``xS, yS,
dRS, rS``).  Per run id (owner: the id; runs of one id share them): where its sphere sits on the workpiece side
(``xP, yP, zP``, at the home pose: placed by hand, a few hundred µm; the indexed positions turn it about the axes and
so tell it from their location errors) and, for readings in a frame zeroed somewhere unknown, where the sphere is in
that frame (``xD, yD, zD``); each run states which of these it has.
"""

from __future__ import annotations

from .description import FRAME, MachineDescription

#: a probed sphere's placement, by frame axis
SPHERE_TERMS = ("xP", "yP", "zP")


def stylus_terms(desc: MachineDescription) -> tuple[str, ...]:
    """The nuisance terms of one stylus: its centring across the spindle, then its length error."""
    along = FRAME[desc.spindle.frame_axis].lower()
    return tuple(f"{a}S" for a in "xyz" if a != along) + ("dRS",)


def probe_terms(desc: MachineDescription | None, probe) -> list[tuple[str, str]]:
    """``(owner, base)`` pairs of a campaign's probe: each stylus in the order its runs first use it, with the terms
    its first run states (else the machine's, :func:`stylus_terms`), then each run id's sphere and datum terms."""
    styli: dict[str, tuple[str, ...]] = {}
    spheres: dict[str, tuple[str, ...]] = {}
    for run in probe.runs:
        if run.stylus not in styli:
            styli[run.stylus] = run.stylus_terms if run.stylus_terms is not None else stylus_terms(desc)
        spheres.setdefault(run.id, tuple(run.sphere_terms) + tuple(run.datum_terms))
    return [(s, b) for s, terms in styli.items() for b in terms] + \
        [(rid, b) for rid, terms in spheres.items() for b in terms]


#: the R-test's zero of a run (``zero = "first"``) and a sphere's placement, by frame axis (SPEC §22)
RTEST_ZERO_TERMS = ("xZR", "yZR", "zZR")
RTEST_PLACEMENT_TERMS = ("xPR", "yPR", "zPR")


def nest_terms(desc: MachineDescription) -> tuple[str, ...]:
    """The nuisance terms of one R-test nest: its centre's offset across the spindle, then its length error."""
    along = FRAME[desc.spindle.frame_axis].lower()
    return tuple(f"{a}NR" for a in "xyz" if a != along) + ("dLR",)


def rtest_terms(desc: MachineDescription, rtest) -> list[tuple[str, str]]:
    """``(owner, base)`` pairs of a campaign's R-test (SPEC §22): each run's zero (``zero = "first"``), each
    placement's sphere error (in the order its runs first name it), each nest's terms unless it is calibrated (in
    the order its runs first use it)."""
    zeros = [(run.id, b) for run in rtest.runs if run.zero == "first" for b in RTEST_ZERO_TERMS]
    places = [(p, b) for p in dict.fromkeys(rtest.placement_of(run) for run in rtest.runs)
              for b in RTEST_PLACEMENT_TERMS]
    nests = [(n, b) for n in dict.fromkeys(run.nest for run in rtest.runs) if not rtest.nests[n].calibrated
             for b in nest_terms(desc)]
    return zeros + places + nests
