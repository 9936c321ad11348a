"""Degenerate and extreme inputs through the command line (in-process, ``run_cli``).

Each case ends either in a clear error — exit status 2, one line on stderr naming
the file and the key, no traceback — or in a successful run whose outputs
(stdout, stderr, and every CSV, HTML, JSON and TOML file written) contain no
``nan`` / ``inf`` token.  Cases: R_C = 0 for the C patterns, equal tool lengths,
deviations of degrees, a single run, a single repeat per component, all-zero
data.  Sampler runs are one block of 50 steps (the least ``--max-steps`` allows: the first check).
"""

import json
import math
import re

import numpy as np
import pytest

from mtmcal_bayes import MODELS, load_campaign

from .conftest import DATA

QUICK = ("--max-steps", "50", "--seed", "3", "--quiet")
#: a nan/inf token standing alone: not "information", "infeasible", "nanometre"
TOKEN = re.compile(r"(?<![A-Za-z0-9_])[-+]?(?:nan|inf|infinity)(?![A-Za-z0-9_])", re.IGNORECASE)
#: embedded figures: base64 may spell "+nan/" by chance
DATA_URI = re.compile(r"data:[\w/+.-]+;base64,[A-Za-z0-9+/=]+")
MINIMAL = (DATA / "minimal_one_repeat.toml").read_text()


def bad_tokens(text: str) -> list[str]:
    text = DATA_URI.sub("", text)
    return [text[max(0, m.start() - 60): m.end() + 20] for m in TOKEN.finditer(text)]


def test_token_pattern():
    assert bad_tokens("mean nan µm") and bad_tokens("x,-inf,") and bad_tokens("NaN") and bad_tokens("Infinity")
    assert not bad_tokens("information, infeasible, nanometre, Inf_x, index, <img src='data:image/png;base64,a+nan/b'>")


def assert_error(result, *fragments):
    """Exit 2, one line on stderr (naming file and key: ``fragments``), nothing on stdout, no traceback."""
    code, out, err = result
    assert code == 2, (code, out, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err and "internal error" not in err, err
    for f in fragments:
        assert f in lines[0], (f, lines[0])
    assert not out.strip(), out
    return lines[0]


def assert_clean(result, directory=None):
    """Exit 0, no traceback, and no nan/inf token in stdout, stderr or any text file written."""
    code, out, err = result
    assert code == 0, err
    assert "Traceback" not in err and "internal error" not in err, err
    texts = {"stdout": out, "stderr": err}
    if directory is not None:
        for p in sorted(directory.rglob("*")):
            if p.suffix in (".csv", ".html", ".json", ".toml", ".txt", ".md"):
                texts[p.name] = p.read_text(encoding="utf-8")
    for name, text in texts.items():
        assert not bad_tokens(text), (name, bad_tokens(text)[:3])
    return out, err


def finite_json(out: str):
    """Parse JSON output; every number in it finite (the CLI turns NaN into null, so nulls are checked apart)."""
    doc = json.loads(out)

    def walk(x):
        if isinstance(x, float):
            assert math.isfinite(x)
        elif isinstance(x, dict):
            for v in x.values():
                walk(v)
        elif isinstance(x, list):
            for v in x:
                walk(v)

    walk(doc)
    return doc


def assert_summary_filled(doc):
    for name, row in doc["summary"].items():
        for k in ("mean", "sd", "median", "hdi_low", "hdi_high", "r_hat", "ess_bulk", "ess_tail"):
            assert row[k] is not None, (name, k)


def write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


# --------------------------------------------------------------------------- R_C = 0 for the C patterns
RC0 = MINIMAL.replace("[ballbar.mounts.C]\nZ_C_mm = 65.5348\nR_C_mm = 50.0",
                      "[ballbar.mounts.C]\nZ_C_mm = 65.5348\nR_C_mm = 0.0")


def test_r_c_zero(run_cli, tmp_path):
    """CA at R_C = 0 carries no information on the C-axis tilt (ex_CA = R_C·beta_CZ): identify says so, the
    sensitivity table (which needs an R_C > 0 mount) refuses by name, the posterior flags alpha_CZ and beta_CZ
    as determined only in combination with the C line's offsets, and the planner proposes a CA at R_C > 0 first."""
    assert RC0 != MINIMAL
    f = write(tmp_path, "rc0.toml", RC0)
    out, _ = assert_clean(run_cli("identify", f))
    assert "not computed: CA run at mount C has R_C = 0, which carries no information" in out
    doc = finite_json(assert_clean(run_cli("identify", f, "--json"))[0])
    assert doc["ballbar"]["alpha_CZ"]["value"] is None and "R_C = 0" in doc["ballbar"]["alpha_CZ"]["missing"]

    line = assert_error(run_cli("sensitivity", f), "rc0.toml", "ballbar.mounts", "R_C_mm > 0")
    assert line.endswith("have B R_C_mm = 0, C R_C_mm = 0")

    assert_clean(run_cli("simulate", f, "--truth", write(tmp_path, "t.toml", "[deviations]\nbeta_CZ_arcsec = 20\n")))
    out, _ = assert_clean(run_cli("sample", f, *QUICK))
    assert "Identifiability (the campaign's Jacobian, nuisance terms included):" in out
    # each tilt is seen only beside the C line's offset at the mount's height (the Jacobian's combinations)
    assert "  - alpha_CZ: determined only in combination: alpha_CZ + " in out and "·dy_CZ" in out
    assert "  - beta_CZ: determined only in combination: beta_CZ − " in out and "·dx_CZ" in out

    doc = finite_json(assert_clean(run_cli("plan", f, "--json"))[0])
    best = doc["candidates"][0]
    assert best["pattern"] == "CA" and best["R_C_mm"] > 0 and "alpha_CZ" in best["newly_identified"], best


# --------------------------------------------------------------------------- equal tool lengths
@pytest.mark.parametrize("what, old, new, key", [
    ("R_B", "R_B_mm = 406.4608", "R_B_mm = 356.3945", "ballbar.setups.RB2.R_B_mm"),
    ("Z_T", "Z_T_mm = 62.2491", "Z_T_mm = 112.2877", "ballbar.setups.RB2.Z_T_mm"),
])
def test_equal_tool_lengths(run_cli, tmp_path, what, old, new, key):
    """Two setups with the same R_B (or the same Z_T: Eq 4.17 divides by Z'_T − Z_T) are rejected by every
    command, in one line naming the file and the key; report writes nothing."""
    f = write(tmp_path, "equal.toml", MINIMAL.replace(old, new))
    truth = write(tmp_path, "t.toml", "[deviations]\n")
    for argv in (("identify",), ("identify", "--json"), ("simulate", "--truth", truth), ("sensitivity",),
                 ("sample", *QUICK), ("sample", "--closed-form"), ("plan",),
                 ("report", "-o", tmp_path / "rep", *QUICK)):
        line = assert_error(run_cli(argv[0], f, *argv[1:]), "equal.toml", key)
        assert "equal to ballbar.setups.RB1." in line
    assert not (tmp_path / "rep").exists()


# --------------------------------------------------------------------------- deviations of degrees
DEGREES = """[deviations]
alpha_XB_arcsec = 3600      # 1°
beta_XB_arcsec = -7200      # −2°
gamma_XB_arcsec = 10800     # 3°
alpha_BT_arcsec = 5400
alpha_CZ_arcsec = -3600
beta_CZ_arcsec = 7200
gamma_XY_arcsec = 3600
beta_YZ_arcsec = -3600
dx_CZ_um = 53
dy_CZ_um = -45
[setups.RB1]
xT_um = 1.0
dRB_um = -20
[mounts.C]
xW_um = 60
yW_um = -40
"""


def test_deviations_of_degrees(run_cli, tmp_path):
    """A truth with 1–3° angular deviations: every model gives finite eccentricities; the kinematic models
    depart from the linear one by millimetres (where the first order breaks down), and a posterior under the
    linear model says so in a warning line, while htm-thesis samples to finite summaries."""
    truth = write(tmp_path, "degrees.toml", DEGREES)
    camp = write(tmp_path, "c.toml", MINIMAL)
    pred = {}
    for model in MODELS:
        doc = finite_json(assert_clean(run_cli("simulate", camp, "--truth", truth, "--model", model, "--json"))[0])
        pred[model] = np.array([r["value_um"] for r in doc["eccentricities"]], dtype=float)
        assert np.isfinite(pred[model]).all() and np.abs(pred[model]).max() > 1000.0  # mm-sized eccentricities
    assert np.abs(pred["htm-thesis"] - pred["linear"]).max() > 1000.0  # > 1 mm: the linear model breaks down
    assert np.abs(pred["htm-literal"] - pred["htm-thesis"]).max() > 10.0

    synth = tmp_path / "synth.toml"
    assert_clean(run_cli("simulate", camp, "--truth", truth, "-o", synth, "--noise", "--seed", "4"))
    assert load_campaign(synth).truth.deviations["gamma_XB"] == pytest.approx(10800 * np.pi / 648000)
    out, _ = assert_clean(run_cli("identify", synth))
    assert "alpha_XB" in out

    _, err = assert_clean(run_cli("sample", synth, *QUICK))
    warning = next(line for line in err.splitlines() if "linear model is first order" in line)
    assert warning.startswith("WARNING: the linear model is first order and the deviations found are too large")
    assert warning.endswith("use the htm-thesis model")

    doc = finite_json(assert_clean(run_cli("sample", synth, "--model", "htm-thesis", "--json", *QUICK))[0])
    assert_summary_filled(doc)
    assert not any("linear model is first order" in w for w in doc["diagnostics"]["warnings"])


# --------------------------------------------------------------------------- a single run
SINGLE_CR = """format = "mtmcal-campaign/1"
[ballbar]
length_mm = 100.0
accuracy_um = 0.5
[ballbar.setups.RB1]
R_B_mm = 356.3945
Z_T_mm = 112.2877
X_T_mm = 490.0
[ballbar.mounts.C]
Z_C_mm = 65.5348
R_C_mm = 50.0
[[ballbar.runs]]
pattern = "CR"
setup = "RB1"
mount = "C"
ex_um = [-47.9]
ey_um = [25.4]
"""


def test_single_run(run_cli, tmp_path):
    """One CR run, one setup, one mount, one repeat: identify lists what it cannot compute, the sensitivity
    table refuses by name, the posterior lists the quantities the data do not identify, the planner proposes
    B patterns on a new W-ball placement on the C axis (the campaign has none), and the report is complete."""
    f = write(tmp_path, "single.toml", SINGLE_CR)
    out, _ = assert_clean(run_cli("identify", f))
    assert "not computed: needs ey of a CA run" in out and "needs ey of CR at a second tool length" in out
    assert_error(run_cli("sensitivity", f), "single.toml", "ballbar.mounts")
    assert_clean(run_cli("simulate", f, "--truth", write(tmp_path, "t.toml", "[deviations]\ndx_CZ_um = 5\n")))

    doc = finite_json(assert_clean(run_cli("sample", f, "--json", *QUICK))[0])
    assert_summary_filled(doc)
    assert {n.split(":")[0] for n in doc["diagnostics"]["not_identified"]} >= {"alpha_CZ", "beta_CZ", "alpha_BT"}

    doc = finite_json(assert_clean(run_cli("plan", f, "--json"))[0])
    b_rows = [r for r in doc["candidates"] if r["pattern"].startswith("B")]
    assert b_rows and all(r["mount"] == "C@R_C0" and r["R_C_mm"] == 0.0 for r in b_rows), b_rows[:2]

    rep = tmp_path / "rep"
    out, _ = assert_clean(run_cli("report", f, "-o", rep, *QUICK), rep)
    assert (rep / "index.html").exists() and (rep / "summary.csv").exists()
    assert "Identifiability (the campaign's Jacobian, nuisance terms included):" in out


def test_single_bx_run_plan(run_cli, tmp_path):
    """One BX run on one mount (on the C axis): the C-pattern candidates go to that mount or to other R_C."""
    text = SINGLE_CR.replace("[ballbar.mounts.C]\nZ_C_mm = 65.5348\nR_C_mm = 50.0",
                             "[ballbar.mounts.B]\nZ_C_mm = 65.5348\nR_C_mm = 0.0")
    text = text.replace('pattern = "CR"', 'pattern = "BX"').replace('mount = "C"', 'mount = "B"')
    text = text.replace("ey_um", "ez_um")
    f = write(tmp_path, "bx.toml", text)
    assert_clean(run_cli("identify", f))
    finite_json(assert_clean(run_cli("plan", f, "--json"))[0])
    assert_clean(run_cli("sample", f, *QUICK))


# --------------------------------------------------------------------------- one repeat, all zero
def test_single_repeat_per_component(run_cli, tmp_path):
    """Every component measured once (no repeat scatter of its own: the likelihood takes 0.25 µm):
    the report is complete and free of NaN."""
    f = write(tmp_path, "one.toml", MINIMAL)
    rep = tmp_path / "rep"
    assert_clean(run_cli("report", f, "-o", rep, *QUICK), rep)
    doc = finite_json(assert_clean(run_cli("sample", f, "--json", *QUICK))[0])
    assert_summary_filled(doc)


def test_all_zero_data(run_cli, tmp_path):
    """All eccentricities 0.0 in three identical repeats (zero scatter): identify prints zeros (not −0.00),
    the posterior is centred on zero and finite, the planner and the closed form run."""
    text = re.sub(r"(e[xyz]_um) = \[[^\]]*\]", r"\1 = [0.0, 0.0, 0.0]", MINIMAL)
    f = write(tmp_path, "zeros.toml", text)
    out, _ = assert_clean(run_cli("identify", f))
    assert "-0.00" not in out
    doc = finite_json(assert_clean(run_cli("identify", f, "--json"))[0])
    assert all(v["value"] == 0.0 for v in doc["ballbar"].values())
    doc = finite_json(assert_clean(run_cli("sample", f, "--json", *QUICK))[0])
    assert_summary_filled(doc)
    assert abs(doc["summary"]["beta_XB"]["mean"]) < doc["summary"]["beta_XB"]["sd"]
    finite_json(assert_clean(run_cli("plan", f, "--json"))[0])
    assert_clean(run_cli("sample", f, "--closed-form"))
    assert_clean(run_cli("sensitivity", f, "--json"))


# --------------------------------------------------------------------------- sampler budget
@pytest.mark.parametrize("steps", ["49", "0", "-5"])
def test_step_budget_below_the_shortest_run(run_cli, steps):
    """A run is at least 50 steps (its first check): a smaller budget would be overrun silently; it is an error."""
    assert_error(run_cli("sample", "--max-steps", steps, "--quiet"), "--max-steps", "below the shortest run of 50 steps")


def test_simulate_truth_too_large_for_any_ballbar(run_cli, tmp_path):
    """A truth whose eccentricities are not finite or not below the bar length: one line naming the truth file."""
    truth = tmp_path / "huge.toml"
    truth.write_text("[deviations]\nbeta_XB_arcsec = 1e300\n", encoding="utf-8")
    code, out, err = run_cli("simulate", "--truth", truth, "-o", tmp_path / "synth.toml")
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1
    assert "huge.toml" in err and "too large to be measured" in err
    assert not (tmp_path / "synth.toml").exists()


def test_simulate_linear_warns_for_degree_sized_truth(run_cli, tmp_path):
    truth = tmp_path / "deg.toml"
    truth.write_text("[deviations]\nbeta_XB_arcsec = 7200\n", encoding="utf-8")
    code, _out, err = run_cli("simulate", "--truth", truth, "--model", "linear", "--json")
    assert code == 0 and "linear model is first order" in err
    code, _out, err = run_cli("simulate", "--truth", truth, "--model", "htm-thesis", "--json")
    assert code == 0 and "WARNING" not in err
