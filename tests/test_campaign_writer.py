"""One campaign writer for every machine (issue 42): what the one reader reads, the one writer writes back.

On the thesis campaign, designed campaigns (the thesis' and a demo's, as ``design -o`` wrote them), the three demos,
a probe-only campaign, campaigns with traces, with DPRNT files and with a reading chosen over another, and a campaign
of each format with everything else the reader takes (priors, tolerances, truth, design, date, temperature, travels,
planned runs with their own geometry): save → load gives the same campaign, and save → load → save the same bytes.

"The same": every key the reader fills equal; numbers to 1e-11 relative, as the writer keeps 12 significant digits
of each (:func:`mtmcal_bayes.io.tomlio._float`), which a mm ↔ µm conversion and back moves by at most one unit of
the twelfth.
"""

from __future__ import annotations

import dataclasses
import datetime
import tomllib
from pathlib import Path

import numpy as np
import pytest

from mtmcal_bayes import api, load_campaign, save_campaign
from mtmcal_bayes.datasets import builtin_campaign_text, data_path
from mtmcal_bayes.io.machine_reader import demo_campaign
from mtmcal_bayes.io.tomlio import dumps
from mtmcal_bayes.machines.deviations import generated
from mtmcal_bayes.machines.patterns import components
from mtmcal_bayes.models.ballbar import ChainBallbarModel
from mtmcal_bayes.observations import Observations
from mtmcal_bayes.units import ARCSEC

from .conftest import DATA
from .test_kinematic import write_trace

TYPES = ("trunnion", "vertical-turn-mill", "head-head")
RTOL = 1e-11


def _write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def _demo_doc(machine: str) -> dict:
    return tomllib.loads(Path(demo_campaign(machine)).read_text(encoding="utf-8"))


def _thesis_extras(tmp_path: Path) -> Path:
    """The thesis' format with everything besides its runs: priors of a deviation, a nuisance term and a scale,
    tolerances (symmetric, asymmetric, one-sided, the derived quantity), truth of every ball-bar group, a design goal,
    a date and a temperature, a CR geometry other than the default and a planned run with every key."""
    doc = tomllib.loads((DATA / "minimal_one_repeat.toml").read_text(encoding="utf-8"))
    doc["date"], doc["temperature_C"] = datetime.datetime(2026, 3, 15, 8, 30), 21.5
    doc["ballbar"]["cr_geometry"] = "RC+LB"
    doc["ballbar"]["runs"].append({"pattern": "CT", "setup": "RB2", "mount": "C", "planned": True, "repeats": 4,
                                   "length_mm": 150.0, "minutes": 0.0, "order": 1, "why": "a reason",
                                   "convention": "machine"})
    doc["priors"] = {"beta_XB": {"dist": "normal", "mean_arcsec": 3.0, "sd_arcsec": 30.0},
                     "xW": {"dist": "uniform", "low_um": -40.0, "high_um": 55.5},
                     "sigma_model": {"dist": "halfnormal", "sd_um": 2.0}}
    doc["tolerances"] = {"alpha_XB_arcsec": 30.0, "dy_CZ_um": {"low": -20.0, "high": 50.0},
                         "beta_CZ_arcsec": {"high": 20.0}, "dx_CZ_minus_dx_BT_um": 15.0}
    doc["truth"] = {"deviations": {"beta_XB_arcsec": -24.0, "dx_CZ_um": 53.1234567},
                    "setups": {"RB1": {"xT_um": 0.5, "dRB_um": -3.0}}, "mounts": {"C": {"yW_um": 40.0}}}
    doc["design"] = {"contraction": 0.4, "budget_min": 120.0,
                     "targets": {"alpha_XB_arcsec": 2.0, "dx_CZ_minus_dx_BT_um": 5.0}}
    return _write(tmp_path, "thesis_extras.toml", dumps(doc))


def _demo_extras(tmp_path: Path) -> Path:
    """A demo with what only the thesis' writer wrote before (tolerances) and what the engine's dropped (the linear
    axes' travels), beside priors, truth, design, date and temperature, and a planned run with its own arc, held
    axis and bar side."""
    doc = _demo_doc("trunnion")
    c = load_campaign(demo_campaign("trunnion"))
    doc["date"], doc["temperature_C"] = datetime.date(2026, 5, 1), 19.0
    doc["machine"]["travel_X_mm"] = 500.0
    first = next(r for r in doc["ballbar"]["runs"] if not r.get("planned"))
    other = next(a.letter for a in c.machine.description.rotary_axes if a.letter != first["pattern"][0])
    doc["ballbar"]["runs"].append({"pattern": first["pattern"], "setup": first["setup"], "mount": first["mount"],
                                   "arc_deg": [0.0, 20.0], "step_deg": 2.5, "hold_deg": {other: 10.0},
                                   "reversed": True, "planned": True, "repeats": 2, "minutes": 0.0})
    symbols = [d.symbol for d in generated(c.machine.description)]
    angle = next(n for n in symbols if n.startswith(("E_A", "E_B", "E_C")))
    length = next(n for n in symbols if n.startswith(("E_X", "E_Y", "E_Z")))
    doc["priors"] = {angle: {"dist": "normal", "sd_arcsec": 20.0}, "zT": {"dist": "normal", "sd_um": 10.0}}
    doc["tolerances"] = {f"{angle}_arcsec": 25.0, f"{length}_um": {"low": -10.0}}
    doc["truth"] = {"deviations": {f"{angle}_arcsec": 12.5, f"{length}_um": -7.25}}
    doc["design"] = {"targets": {f"{angle}_arcsec": 3.0}, "times": {"tool_change_min": 5.0}}
    return _write(tmp_path, "demo_extras.toml", dumps(doc))


def _thesis_traces(tmp_path: Path) -> Path:
    """The thesis' format with a run read from two trace files (one repeat each)."""
    text = (DATA / "minimal_one_repeat.toml").read_text(encoding="utf-8")
    text = text.replace('ex_um = [-47.9]\ney_um = [25.4]', 'trace_csv = ["cr1.csv", "cr2.csv"]')
    write_trace(tmp_path / "cr1.csv", "CR", np.pi, -0.0479, 0.0254)
    write_trace(tmp_path / "cr2.csv", "CR", np.pi, -0.0481, 0.0260)
    return _write(tmp_path, "thesis_traces.toml", text)


def _thesis_dprnt(tmp_path: Path) -> Path:
    """The thesis campaign with its C-axis run read from DPRNT files in a folder of their own (the published one at
    every angle: what is written back is the files' names, relative to the saved campaign)."""
    doc = tomllib.loads(builtin_campaign_text()[0])
    c = doc["probe"]["c_axis"]
    (tmp_path / "dprnt").mkdir()
    names = []
    for i in range(len(c["angles_deg"])):
        names.append(f"dprnt/c{i}.txt")
        (tmp_path / names[-1]).write_bytes(data_path("fig5_13_dprnt_output.txt").read_bytes())
    del c["centres_mm"]
    c["dprnt"] = names
    return _write(tmp_path, "thesis_dprnt.toml", dumps(doc))


def _demo_traces(tmp_path: Path) -> Path:
    """A demo whose every measured run is read from a trace file the chain simulates (deviations up to 100″ /
    100 µm, an offset r0 of 12.5 µm; CW, then CCW reversed)."""
    c = load_campaign(demo_campaign("trunnion"))
    fm = ChainBallbarModel(c)
    rng = np.random.default_rng(5)
    scale = np.array([100 * ARCSEC if p.kind == "angle" else 0.1 for p in fm.space.parameters])
    theta = rng.uniform(-1.0, 1.0, len(scale)) * scale
    doc = _demo_doc("trunnion")
    measured = [r for r in doc["ballbar"]["runs"] if not r.get("planned")]
    for i, ((_, dL), run, table) in enumerate(zip(fm.traces(theta[None]), c.ballbar.runs, measured)):
        rows = ["angle_deg,dL_um,direction"]
        for direction, order in (("CW", slice(None)), ("CCW", slice(None, None, -1))):
            rows += [f"{float(a)!r},{float(v) * 1e3 + 12.5!r},{direction}"
                     for a, v in zip(c.ballbar.arc_of(run)[order], dL[0][order])]
        (tmp_path / f"run{i}.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
        for key in [k for k in table if k.endswith("_um")]:
            del table[key]
        table["trace_csv"] = [f"run{i}.csv"]
    return _write(tmp_path, "demo_traces.toml", dumps(doc))


def _demo_chosen_reading(tmp_path: Path) -> Path:
    """A demo whose first run names an alternative reading (both directions turned) and the reason of the choice."""
    c = load_campaign(demo_campaign("head-head"))
    doc = _demo_doc("head-head")
    run = c.ballbar.runs[0]
    a, b = components(c.machine.description, run.pattern)
    k = run.pattern[0]
    doc["ballbar"]["runs"][0]["alternative_convention"] = f"{k}0=-{a[1].upper()},{k}90=-{b[1].upper()}"
    doc["ballbar"]["alternative_reason"] = "the bar's side was not written down"
    return _write(tmp_path, "demo_chosen.toml", dumps(doc))


@pytest.fixture(scope="module")
def designed_demo(tmp_path_factory) -> Path:
    """The head-head demo designed on by ``design -o`` with the ball bar for a target below its sd today: its
    measured runs, the planned runs after them (with their arcs and held axes), its probe runs and its
    ``[design]``."""
    out = tmp_path_factory.mktemp("designed") / "design"
    api.design(str(demo_campaign("head-head")), targets={"E_A0C": 0.5}, output=out, seed=1, instruments="ballbar")
    planned = load_campaign(out / "campaign.toml").ballbar.planned
    assert planned and any(p.hold_deg for p in planned)  # what the case is for
    return out / "campaign.toml"


CASES = {
    "thesis": lambda tmp: _write(tmp, "thesis.toml", builtin_campaign_text()[0]),
    "thesis designed": lambda tmp: DATA / "formats" / "designed_thesis_d54cc98.toml",
    "thesis machine designed from nothing": lambda tmp: DATA / "formats" / "designed_new_machine_d54cc98.toml",
    "thesis probe readings of the first format": lambda tmp: DATA / "formats" / "thesis_first_published.toml",
    "thesis extras": _thesis_extras,
    "thesis traces": _thesis_traces,
    "thesis DPRNT": _thesis_dprnt,
    **{t: (lambda tmp, t=t: Path(demo_campaign(t))) for t in TYPES},
    "demo probe only": lambda tmp: DATA / "controller_cycles" / "trunnion-cycle.toml",
    "demo extras": _demo_extras,
    "demo traces": _demo_traces,
    "demo reading chosen": _demo_chosen_reading,
}


@pytest.mark.parametrize("case", [*CASES, "demo designed"])
def test_save_load_is_the_campaign_and_save_load_save_the_bytes(case, tmp_path, request):
    """Saved into another folder (trace and DPRNT files then named relative to it, not by their absolute path) and
    read back: the same campaign; saved again from what was read: the same bytes."""
    source = request.getfixturevalue("designed_demo") if case == "demo designed" else CASES[case](tmp_path)
    original = load_campaign(source)
    out = tmp_path / "saved"
    out.mkdir()
    save_campaign(original, out / "a.toml")
    assert str(tmp_path) not in (out / "a.toml").read_text(encoding="utf-8")  # files named relative to it
    back = load_campaign(out / "a.toml")
    _same_campaign(original, back)
    save_campaign(back, out / "b.toml")
    assert (out / "b.toml").read_bytes() == (out / "a.toml").read_bytes()


#: what is not the campaign itself: where it was read from, where a tolerance was given
NOT_COMPARED = {"source", "base_dir", "key"}
#: file names, written relative to the saved file: compared as the files they name
FILE_FIELDS = {"trace_csv", "dprnt"}


def _same_campaign(a, b) -> None:
    """``a`` and ``b`` alike in every field the reader fills, recursively (numbers to :data:`RTOL`; the functions a
    format completes its ball bar with are its own, not compared); the observations of the ball bar alike too."""
    _same(a, b, "campaign", (a.base_dir, b.base_dir))
    if a.ballbar.runs:
        oa, ob = Observations.from_campaign(a), Observations.from_campaign(b)
        assert oa.keys == ob.keys and np.array_equal(oa.n, ob.n)
        _same(oa.mean, ob.mean, "observations", (None, None))


def _same(a, b, where: str, dirs: tuple) -> None:
    if a is None or b is None:
        assert a is None and b is None, where
    elif callable(a) and not dataclasses.is_dataclass(a):
        assert callable(b), where
    elif dataclasses.is_dataclass(a):
        assert type(a) is type(b), where
        for f in dataclasses.fields(a):
            if f.name in NOT_COMPARED:
                continue
            x, y = getattr(a, f.name), getattr(b, f.name)
            if f.name in FILE_FIELDS and x is not None:
                x, y = _files(dirs[0], x), _files(dirs[1], y)
            _same(x, y, f"{where}.{f.name}", dirs)
    elif isinstance(a, dict):
        assert list(a) == list(b), where
        for k in a:
            _same(a[k], b[k], f"{where}[{k!r}]", dirs)
    elif isinstance(a, (list, tuple)) and not all(isinstance(x, (int, float)) for x in a):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            _same(x, y, f"{where}[{i}]", dirs)
    elif isinstance(a, (np.ndarray, list, tuple, float)) or (isinstance(a, int) and not isinstance(a, bool)):
        x, y = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        assert x.shape == y.shape and np.allclose(x, y, rtol=RTOL, atol=0.0, equal_nan=True), where
    else:
        assert a == b, where


def _files(base_dir, names) -> list[str]:
    return [str(Path(base_dir or ".", n).resolve()) for n in names]


def test_a_thesis_probe_without_readings_is_saved_and_read_back(tmp_path):
    """The thesis campaign with its probe runs taken away (a new machine's probe, its styli kept to design with):
    saved without the thesis' probe sections (their readings are required keys), its styli as ``[probe.styli]`` with
    their ball radii; read back the same campaign but for the plug-in's record of the sections it no longer has;
    saved again the same bytes."""
    original = load_campaign(_write(tmp_path, "thesis.toml", builtin_campaign_text()[0]))
    original.probe.runs = []
    save_campaign(original, tmp_path / "a.toml")
    text = (tmp_path / "a.toml").read_text(encoding="utf-8")
    assert "[probe.c_axis]" not in text and "[probe.b_axis]" not in text
    back = load_campaign(tmp_path / "a.toml")
    assert back.probe.runs == [] and back.probe.styli == original.probe.styli
    assert back.probe.ball_radii == original.probe.ball_radii
    original.probe.own = back.probe.own
    _same_campaign(original, back)
    save_campaign(back, tmp_path / "b.toml")
    assert (tmp_path / "b.toml").read_bytes() == (tmp_path / "a.toml").read_bytes()
