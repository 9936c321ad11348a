"""A campaign's measurement sections, ``[ballbar]``, ``[probe]`` and ``[rtest]``: one reader for every machine (SPEC §19, §20,
docs/machines.md).  ``[ballbar]`` is read by :mod:`.ballbar_section`, ``[rtest]`` by :mod:`.rtest_section`;
``[probe]`` here.  A plug-in whose campaign
format has probe sections of its own (the thesis': its C-axis and B-axis runs) names them (``probe_keys``) and reads
them into the same runs and styli (``read_probe_keys``); everything else of ``[probe]`` is the engine's on every
machine, beside them or instead of them.

``[probe]``: ``instrument``, ``repeatability_um``; ``[probe.styli.<id>] length_mm`` (spindle point to stylus-ball
centre; with ``ball_radius_mm``, to its tip); ``[[probe.runs]]`` with ``stylus`` (a stylus of ``[probe.styli]`` or of
the plug-in's sections, or its length ``R_B_mm``: a stylus of the run's own), ``sphere_mm`` (its nominal centre at the
home pose, workpiece side), ``angles_deg`` (axis letter -> list, all one length) and ``centres_mm`` (repeats ×
positions × 3: the commanded X, Y, Z at which the stylus centre reached the sphere's centre).
"""

from __future__ import annotations

from pathlib import Path

from .. import units
from ..campaign import Ballbar, Machine, Probe, ProbeRun, RTest
from ..machines.description import MachineDescription
from ..machines.plugins import provided
from .ballbar_section import read_ballbar
from .probe_readings import probe_readings
from .rtest_section import read_rtest
from .run_angles import read_run_angles
from .toml_reader import TomlReader

#: the engine's keys of ``[probe]``
PROBE_KEYS = ("instrument", "repeatability_um", "styli", "runs")


def measurement_sections(r: TomlReader, doc: dict, machine: Machine,
                         base_dir: Path | None) -> tuple[Ballbar, Probe, RTest | None]:
    """``[ballbar]`` (:func:`~.ballbar_section.read_ballbar`, with the machine's own keys), ``[probe]``
    (:func:`read_probe`) and ``[rtest]`` (:func:`~.rtest_section.read_rtest`) of a campaign on ``machine``; a campaign
    measures something (ball-bar, probe or R-test runs) or gives a ball bar's set-ups and mounts to design a campaign
    for."""
    probe_t = r.table(doc, "probe", "", required=False)
    rtest_t = r.table(doc, "rtest", "", required=False)
    ballbar = read_ballbar(r, r.table(doc, "ballbar", "", required=False), machine, base_dir)
    probe = read_probe(r, probe_t, machine, base_dir, ballbar=ballbar) if probe_t is not None else None
    rtest = read_rtest(r, rtest_t, machine.description) if rtest_t is not None else None
    if not ballbar.runs and not ballbar.planned and not (probe and probe.runs) and not rtest and \
            not (ballbar.setups and ballbar.mounts):
        r.fail("ballbar", "no measurements: give [[ballbar.runs]], [probe] with its runs or [rtest] with its runs "
               "(or, for a machine to design a campaign for, its [ballbar.setups] and [ballbar.mounts])")
    return ballbar, probe, rtest


def read_probe(r: TomlReader, t: dict, machine: Machine, base_dir=None, *, ballbar: Ballbar | None = None) -> Probe:
    """``[probe]``: instrument, repeatability, the machine's own sections (its plug-in's ``probe_keys``, read by its
    ``read_probe_keys`` into the probe's runs and styli; ``ballbar`` is the campaign's, which they may refer to),
    then ``[probe.styli]`` and ``[[probe.runs]]`` (DPRNT files named relative to ``base_dir``)."""
    P = "probe"
    own_keys = tuple(provided(machine, "probe_keys", ()))
    r.check_keys(t, set(PROBE_KEYS) | set(own_keys), P)
    rep = r.number(t, "repeatability_um", P, required=False, positive=True)
    probe = Probe(r.string(t, "instrument", P), units.to_internal(rep, "um") if rep is not None else None)
    provided(machine, "read_probe_keys", _no_keys)(r, t, probe, ballbar=ballbar, base_dir=base_dir)
    own_styli, own_runs = dict(probe.styli), [run.id for run in probe.runs]
    sections = provided(machine, "probe_sections", "the machine's own sections of [probe]")
    for sid, path, s in (r.subtables(t, "styli", P, allowed={"length_mm", "ball_radius_mm"}, what="stylus")
                         if "styli" in t else ()):
        if sid in own_styli:
            r.fail(path, f"{sid!r} names a stylus of {sections} too")
        radius = r.number(s, "ball_radius_mm", path, required=False, nonnegative=True, default=0.0)
        length = r.number(s, "length_mm", path, positive=True)
        if length - radius <= 0:
            r.fail(f"{path}.ball_radius_mm", "longer than the stylus")
        probe.styli[sid] = length  # to the tip, its ball's radius apart (Probe.centre_length), as written
        if radius:
            probe.ball_radii[sid] = radius
    raw = t.get("runs", [])  # none where the machine's own sections hold its runs, or the probe is declared only
    declared = probe.instrument or probe.repeatability is not None or probe.styli  # a probe to plan runs with
    if not isinstance(raw, list) or not (raw or probe.runs or declared) or not all(isinstance(x, dict) for x in raw):
        also = provided(machine, "probe_sections")
        r.fail(f"{P}.runs", "expected one or more [[probe.runs]] tables" + (f" (or {also})" if also else "")
               + ", or the probe's instrument, repeatability_um or [probe.styli] to plan its runs with")
    for i, x in enumerate(raw):
        probe.runs.append(_probe_run(r, x, f"{P}.runs[{i}]", machine.description, styli=probe.styli, number=i + 1,
                                     base_dir=base_dir))
    ids = [run.id for run in probe.runs]
    for i, rid in enumerate(ids[len(own_runs):]):
        if rid in ids[:len(own_runs) + i]:
            where = f"a run of {sections}" if rid in own_runs else "another run"
            r.fail(f"{P}.runs[{i}].id", f"{rid!r} names {where} too")
    return probe


def _no_keys(r: TomlReader, t: dict, probe: Probe, **_) -> None:
    """The engine's own sections of ``[probe]`` beyond ``[probe.styli]`` and ``[[probe.runs]]``: none."""


def _probe_run(r: TomlReader, t: dict, path: str, desc: MachineDescription, *, styli: dict,
               number: int, base_dir=None) -> ProbeRun:
    r.check_keys(t, {"id", "stylus", "R_B_mm", "sphere_mm", "angles_deg", "centres_mm", "dprnt"}, path)
    rid = r.string(t, "id", path, default=f"run{number}")
    if "R_B_mm" in t:  # the stylus given by its length alone: a stylus of the run's own, named after it
        if "stylus" in t:
            r.fail(f"{path}.R_B_mm", "give the stylus or its length R_B_mm, not both")
        if rid in styli:
            r.fail(f"{path}.id", f"{rid!r} names a stylus of [probe.styli] too; a run with R_B_mm names its own")
        styli[rid] = r.number(t, "R_B_mm", path, positive=True)
        stylus = rid
    else:
        stylus = r.string(t, "stylus", path, required=True)
    if stylus not in styli:
        r.fail(f"{path}.stylus", f"no stylus {stylus!r} in [probe.styli] (have: {', '.join(styli) or 'none'})")
    sphere = r.array(t, "sphere_mm", path, (3,))
    angles, n_pos = read_run_angles(r, t, path, desc, example="{A = [0, -30], C = [0, 90]}")
    if n_pos < 2:
        r.fail(f"{path}.angles_deg", "needs at least two indexed positions (only differences between positions inform "
               "the deviations)")
    centres, cov, files = probe_readings(r, t, path, n_pos, base_dir=base_dir)
    return ProbeRun(rid, stylus, sphere, {k: units.to_internal(v, "deg") for k, v in angles.items()}, centres,
                    dprnt=files, centre_cov=cov)


__all__ = ["measurement_sections", "read_probe", "PROBE_KEYS"]
