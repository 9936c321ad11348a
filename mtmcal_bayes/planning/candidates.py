"""Candidate additional measurements (SPEC §6) and the user's, read from a ``--candidates`` file.

A candidate is one ball-bar run that could be added to a campaign: a pattern
at a tool setup and a W-ball mount with a bar length, measured ``repeats``
times; or more repeats of a run the campaign already has.  A new setup or
mount brings its own nuisance offsets (a re-centred ball, a re-clamped ball).
The catalogue of candidates, one for every machine, and their feasibility are
:mod:`.catalogue`'s.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..campaign import Campaign, Mount, Setup
from ..io.textfiles import read_user_text
from ..io.toml_reader import TomlReader, parse_toml
from ..patterns import PATTERNS, mount_conflict

DEFAULT_REPEATS = 3
#: most repeats of a user candidate: beyond a few hundred, s²/n is far below u_inst² + sigma_model², which do not
#: average out, so more repeats add nothing; 1e20 would overflow the planner's arrays (docs/planning.md)
MAX_REPEATS = 10_000
#: largest |length| of a user candidate, mm (lever arms, mount, bar length): 10 m is beyond the travels of any
#: turn-mill machine; larger numbers are unit slips and make the design matrix singular (docs/planning.md)
MAX_LENGTH_MM = 10_000.0


@dataclass(frozen=True)
class Candidate:
    """One candidate measurement.

    ``setup``/``mount`` carry the geometry (mm); their ids name the nuisance
    parameters, so a candidate at an existing setup shares its offsets.
    ``repeat_of`` is the index of the campaign run it repeats (``None`` for a
    new run); ``extension`` the tool-length difference to the primary setup, mm; ``arc_deg``, ``hold_deg``
    the run's arc and held axes (:mod:`.catalogue`).
    """

    name: str
    kind: str
    pattern: str
    setup: Setup
    mount: Mount
    length: float
    repeats: int = DEFAULT_REPEATS
    repeat_of: int | None = None
    extension: float | None = None
    #: a described machine's run: the swivelled axis' arc ``(start, end, step)`` degrees (None: the axis' default
    #: grid) and the held rotary axes ``((letter, degrees), ...)``
    arc_deg: tuple[float, float, float] | None = None
    hold_deg: tuple[tuple[str, float], ...] = ()

    #: the instrument that measures it (a design's runs are grouped by instrument, each with its own scale)
    instrument = "ballbar"

    def renewed(self) -> set[tuple[str, str]]:
        """The ``(group, owner)`` of the nuisance terms a further run of it sets anew: its W-ball placement's."""
        return {("mount", self.mount.id)}

    def again(self, instance: int):
        """Itself: a further run's own placement is the designed run's mount (:mod:`.design_runs`)."""
        return self


_USER_KEYS = {"name", "pattern", "setup", "mount", "R_B_mm", "Z_T_mm", "X_T_mm", "Z_C_mm", "R_C_mm", "length_mm",
              "repeats"}


def _existing(r: TomlReader, t: dict, key: str, *, path: str, known: dict, geometry: tuple[str, ...]):
    """The campaign's setup/mount named by ``key``, None when the candidate gives a new one by its ``geometry``
    keys (both is an error: which one counts would be a guess)."""
    if key not in t:
        return None
    if given := [g for g in geometry if g in t]:
        r.fail(f"{path}.{given[0]}", f"give either {key} = \"<id>\" or {', '.join(geometry)} of a new {key}, not both")
    oid = r.string(t, key, path)
    if oid not in known:
        r.fail(f"{path}.{key}", f"no {key} {oid!r} in the campaign (have {', '.join(known)})")
    return known[oid]


def _length(r: TomlReader, t: dict, key: str, path: str, **checks) -> float:
    """Length ``key`` of a candidate, mm: finite, within ±MAX_LENGTH_MM (``checks`` as ``TomlReader.number``)."""
    v = r.number(t, key, path, **checks)
    if abs(v) > MAX_LENGTH_MM:
        r.fail(f"{path}.{key}", f"{v:g} mm is beyond ±{MAX_LENGTH_MM:g} mm, more than any machine tool's travel "
               "(µm written for mm?)")
    return v


def read_candidates(path, campaign: Campaign) -> list[Candidate]:
    """Candidates defined by the user in a TOML file of ``[[candidate]]`` tables.

    Each gives ``pattern`` and either ``setup = "<id>"`` of the campaign or the
    lever arms ``R_B_mm``, ``Z_T_mm``, ``X_T_mm`` of a new setup; either
    ``mount = "<id>"`` or ``Z_C_mm``, ``R_C_mm`` of a new mount; optional
    ``length_mm`` (bar length, default the campaign's), ``repeats`` (default 3)
    and ``name``.
    """
    r, items = candidate_tables(path)
    bb = campaign.ballbar
    out = []
    for i, t in enumerate(items):
        path_i = f"candidate[{i}]"
        r.check_keys(t, _USER_KEYS, path_i)
        pattern = r.string(t, "pattern", path_i, required=True)
        if pattern not in PATTERNS:
            r.fail(f"{path_i}.pattern", f"unknown pattern {pattern!r} (expected one of {' '.join(PATTERNS)})")
        setup = _existing(r, t, "setup", path=path_i, known=bb.setups,
                          geometry=("R_B_mm", "Z_T_mm", "X_T_mm")) or Setup(
            f"user{i}", _length(r, t, "R_B_mm", path_i, positive=True), _length(r, t, "Z_T_mm", path_i),
            _length(r, t, "X_T_mm", path_i))
        mount = _existing(r, t, "mount", path=path_i, known=bb.mounts, geometry=("Z_C_mm", "R_C_mm")) or Mount(
            f"user{i}", _length(r, t, "Z_C_mm", path_i, nonnegative=True),
            _length(r, t, "R_C_mm", path_i, nonnegative=True))
        if conflict := mount_conflict(pattern, t.get("mount"), mount.R_C):
            r.fail(f"{path_i}.mount" if "mount" in t else f"{path_i}.R_C_mm", conflict)
        length, repeats, name = candidate_run(r, t, path_i, campaign, pattern=pattern, setup=setup, mount=mount)
        out.append(Candidate(name, "user", pattern, setup, mount, length, repeats,
                             extension=setup.R_B - campaign.primary_setup().R_B))
    return out


def candidate_tables(path) -> tuple[TomlReader, list[dict]]:
    """The reader and the ``[[candidate]]`` tables of a candidates file (one line naming the file and key when it
    has none, or one is not a table)."""
    doc = parse_toml(read_user_text(path, "candidates file"), str(path))
    r = TomlReader(str(path))
    r.check_keys(doc, {"candidate"}, "")
    items = doc.get("candidate")
    if not isinstance(items, list) or not items:
        r.fail("candidate", "expected one or more [[candidate]] tables")
    for i, t in enumerate(items):
        if not isinstance(t, dict):
            r.fail(f"candidate[{i}]", "expected a table")
    return r, items


def candidate_run(r: TomlReader, t: dict, path: str, campaign: Campaign, *, pattern: str, setup: Setup,
                  mount: Mount) -> tuple[float, int, str]:
    """``(bar length mm, repeats, name)`` of a candidate table, each checked (defaults: the campaign's bar, 3
    repeats, a name from pattern, set-up and mount)."""
    length = _length(r, t, "length_mm", path, required=False, positive=True, default=campaign.ballbar.length)
    repeats = r.number(t, "repeats", path, required=False, positive=True, default=DEFAULT_REPEATS)
    if repeats != int(repeats):
        r.fail(f"{path}.repeats", f"must be a whole number, got {repeats:g}")
    if repeats > MAX_REPEATS:
        r.fail(f"{path}.repeats", f"{repeats:g} is more than {MAX_REPEATS}: beyond a few hundred repeats the "
               "instrument accuracy and the model discrepancy, which do not average out, set the uncertainty")
    name = r.string(t, "name", path, default=f"{pattern} @ {setup.id}/{mount.id} (user)")
    return length, int(repeats), name


class WithoutBar:
    """What a candidate that is not a ball-bar run (a probe run, an R-test run) answers where the ranking asks a
    ball-bar run's questions: no bar length (nan), and a pattern named by its kind and its axis (``"probe C"``)."""

    @property
    def length(self) -> float:
        return float("nan")

    @property
    def pattern(self) -> str:
        return f"{self.kind} {self.axis}"

    @property
    def instrument(self) -> str:
        return self.kind

    def again(self, instance: int):
        """The candidate as its ``instance``-th run (2, 3, ...): its own terms (:meth:`renewed`) under owners of their
        own, ``<id>#<instance>``."""
        import dataclasses

        return self if instance == 1 else dataclasses.replace(self, id=f"{self.id}#{instance}")
