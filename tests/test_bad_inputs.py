"""Bad input everywhere: every command that reads a kind of file, on every malformed file of that kind.

The corpus lives in ``tests/data/bad/``, one manifest per kind (tab-separated,
``#`` lines are comments):

* campaigns — ``*.toml`` and ``expected.tsv``: file, key (or ``-``), fragment;
* raw ball-bar traces — ``traces/``: each bad trace ``<name>.csv`` with the small,
  otherwise valid campaign ``<name>.toml`` that references it; ``traces/expected.tsv``:
  campaign, the file the error must name, key or line (or ``-``), fragment;
* NC programs — ``nc/*.nc`` and ``nc/expected.tsv``: file, key, fragment;
* DPRNT probe output — ``dprnt/*.txt`` and ``dprnt/expected.tsv``: file, key, fragment;
* tolerance sets (``--tolerances FILE``) — ``tolerances/*.toml`` and ``tolerances/expected.tsv``: file, key,
  fragment;
* σ_model prior files (``--sigma-model-prior FILE``) — ``sigma_prior/*.toml`` and ``sigma_prior/expected.tsv``:
  file, key, fragment.

Every command must exit with status 2, print nothing on stdout and exactly one
line on stderr that names the file, the key or line and what is wrong — no
traceback, no internal error — and must write nothing (``-o`` points into an
otherwise empty directory that must stay so).
"""

from __future__ import annotations

import argparse
import math
import shutil
import tomllib

import pytest

from mtmcal_bayes import InputError, load_campaign, parse_campaign
from mtmcal_bayes.cli import build_parser
from mtmcal_bayes.datasets import data_path
from mtmcal_bayes.io.gcode import parse_program

from .conftest import DATA

BAD = DATA / "bad"
TRACES = BAD / "traces"
PROGRAMS = BAD / "nc"
DPRNT = BAD / "dprnt"
TOLERANCES = BAD / "tolerances"
SIGMA_PRIORS = BAD / "sigma_prior"
VALID_PROGRAM = data_path("fig4_30a_bx_original.nc")  # compensate's PROGRAM while its campaign is the bad file
VALID_TRUTH = "[deviations]\nbeta_XB_arcsec = -24.11\n"  # simulate's --truth (read after the campaign)

# Argv templates of every command that reads a campaign: {campaign} is the bad file, {out} an output path
# that must not exist afterwards, {truth} a valid truth file, {program} a valid NC program.  Adding a command
# that reads a campaign is one entry here; test_every_campaign_command_is_listed fails until it is added.
# A template of a command the CLI does not have fails (test_every_listed_command_exists).  sample, report and
# validate must fail while loading, before any sampling: a slow test here means one of them does real work first.
COMMANDS_READING_CAMPAIGNS = (
    ("identify", "{campaign}"),
    ("simulate", "{campaign}", "--truth", "{truth}", "-o", "{out}"),
    ("sensitivity", "{campaign}"),
    ("sample", "{campaign}", "-o", "{out}", "--checkpoint", "{out}.h5", "--quiet"),
    ("report", "{campaign}", "-o", "{out}", "--quiet"),
    ("plan", "{campaign}", "-o", "{out}"),
    ("design", "{campaign}", "-o", "{out}"),
    ("next", "{campaign}", "-o", "{out}"),
    ("ncgen", "BX", "{campaign}", "-o", "{out}"),
    ("compensate", "{campaign}", "{program}", "-o", "{out}"),
    ("instruments", "{campaign}"),
    ("validate", "sbc", "{campaign}", "-o", "{out}", "--quiet"),
    ("axes", "{campaign}", "--csv", "{out}"),
)
COMMANDS_READING_PROGRAMS = (
    ("compensate", "{program}", "-o", "{out}"),
)
COMMANDS_READING_DPRNT = (
    ("probe-fit", "{file}"),
    ("probe-fit", "{file}", "--json"),
)
# Every command with --sigma-model-prior ({file} the bad prior; the thesis campaign is valid): it is read before
# any sampling or planning.  test_every_sigma_prior_command_is_listed fails until a new one is added.
COMMANDS_READING_SIGMA_PRIORS = (
    ("sample", "--sigma-model-prior", "{file}", "-o", "{out}", "--checkpoint", "{out}.h5", "--quiet"),
    ("report", "--sigma-model-prior", "{file}", "-o", "{out}", "--quiet"),
    ("plan", "--sigma-model-prior", "{file}", "-o", "{out}"),
    ("design", "--sigma-model-prior", "{file}", "-o", "{out}"),
    ("next", "--sigma-model-prior", "{file}", "-o", "{out}"),
)
# Every command with --tolerances ({file} the bad tolerance set; {campaigns} a folder of one valid campaign).
# test_every_tolerances_command_is_listed fails until a new one is added.
COMMANDS_READING_TOLERANCES = (
    ("sample", "--tolerances", "{file}", "-o", "{out}", "--quiet"),
    ("report", "--tolerances", "{file}", "-o", "{out}", "--quiet"),
    ("design", "--tolerances", "{file}", "-o", "{out}"),
    ("history", "{campaigns}", "--tolerances", "{file}", "-o", "{out}"),
    ("fleet", "{campaigns}", "--tolerances", "{file}", "-o", "{out}", "--quiet"),
)


def manifest(path, columns: int) -> list[list[str]]:
    rows = []
    for line in path.read_text(encoding="utf-8").splitlines():
        if line.strip() and not line.startswith("#"):
            fields = line.split("\t")
            assert len(fields) == columns, f"{path}: {line!r} has {len(fields)} fields, expected {columns}"
            rows.append(fields)
    return rows


CAMPAIGN_ROWS = manifest(BAD / "expected.tsv", 3)  # file, key, fragment
TRACE_ROWS = manifest(TRACES / "expected.tsv", 4)  # campaign, named file, key, fragment
PROGRAM_ROWS = manifest(PROGRAMS / "expected.tsv", 3)
DPRNT_ROWS = manifest(DPRNT / "expected.tsv", 3)
TOLERANCE_ROWS = manifest(TOLERANCES / "expected.tsv", 3)
SIGMA_PRIOR_ROWS = manifest(SIGMA_PRIORS / "expected.tsv", 3)


def _commands(parser: argparse.ArgumentParser, prefix: tuple = ()):
    """``(command path, parser)`` of every (sub)command, e.g. ``(("validate", "sbc"), parser)``."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield prefix + (name,), sub
                yield from _commands(sub, prefix + (name,))


COMMANDS = dict(_commands(build_parser()))


def _command_path(template) -> tuple:
    """The (sub)command a template runs, e.g. ``("validate", "sbc")``; ``()`` when the CLI has no such command
    (its first word unknown, or a command with subcommands given none of them)."""
    path: tuple = ()
    for a in template:
        if path + (a,) not in COMMANDS:
            break
        path += (a,)
    if not path or any(len(p) > len(path) and p[:len(path)] == path for p in COMMANDS):
        return ()
    return path


LISTS = {"COMMANDS_READING_CAMPAIGNS": COMMANDS_READING_CAMPAIGNS, "COMMANDS_READING_PROGRAMS": COMMANDS_READING_PROGRAMS,
         "COMMANDS_READING_DPRNT": COMMANDS_READING_DPRNT, "COMMANDS_READING_SIGMA_PRIORS": COMMANDS_READING_SIGMA_PRIORS,
         "COMMANDS_READING_TOLERANCES": COMMANDS_READING_TOLERANCES}


def test_every_listed_command_exists():
    """A command removed or renamed fails here (and in each of its parametrised cases), instead of turning the
    cases of its template into skips."""
    missing = [f"{name}: {' '.join(t[:2])}" for name, templates in LISTS.items() for t in templates
               if not _command_path(t)]
    assert not missing, missing


def _assert_available(template) -> None:
    assert _command_path(template), f"the CLI has no command {' '.join(template[:2])}"


def _id(template) -> str:
    """Test id of an argv template: its command words and flags without placeholders (``probe-fit--json``)."""
    return "-".join(a for a in template if "{" not in a and a not in ("-o", "--quiet", "--truth", "--checkpoint"))


def fill(template, **values) -> list[str]:
    return [a.format(**{k: str(v) for k, v in values.items()}) if "{" in a else a for a in template]


def assert_one_line_error(run_cli, argv, tmp_path, named, key: str, fragment: str) -> str:
    """Run ``argv``; exit 2, one stderr line naming ``named`` (and ``key``) with ``fragment``, nothing written."""
    before = sorted(tmp_path.iterdir())
    code, out, err = run_cli(*argv)
    assert "Traceback" not in out + err
    assert "internal error" not in err
    assert code == 2, err
    assert out == ""
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].strip(), err
    line = lines[0]
    assert line.startswith(f"mtmcal-bayes {argv[0]}: error: "), line
    assert named.name in line and str(named) in line, line
    if key != "-":
        assert f": {key}: " in line, line
    assert fragment in line, line
    assert sorted(tmp_path.iterdir()) == before, "a failing command wrote output"
    return line


@pytest.fixture
def inputs(tmp_path):
    """Valid companion inputs in ``tmp_path`` and the output path ``{out}``, which must not appear."""
    truth = tmp_path / "truth.toml"
    truth.write_text(VALID_TRUTH)
    return {"truth": truth, "program": VALID_PROGRAM, "out": tmp_path / "out"}


# --------------------------------------------------------------------------- the manifests cover the corpus
def test_every_corpus_file_is_in_a_manifest():
    assert sorted(p.name for p in BAD.glob("*.toml")) == sorted(r[0] for r in CAMPAIGN_ROWS)
    listed = {r[0] for r in TRACE_ROWS} | {r[1] for r in TRACE_ROWS}
    assert sorted(p.name for p in TRACES.iterdir() if p.name != "expected.tsv") == sorted(listed)
    assert sorted(p.name for p in PROGRAMS.iterdir() if p.name != "expected.tsv") == sorted(r[0] for r in PROGRAM_ROWS)
    assert sorted(p.name for p in DPRNT.iterdir() if p.name != "expected.tsv") == sorted(r[0] for r in DPRNT_ROWS)
    assert sorted(p.name for p in SIGMA_PRIORS.iterdir() if p.name != "expected.tsv") == \
        sorted(r[0] for r in SIGMA_PRIOR_ROWS)
    assert sorted(p.name for p in TOLERANCES.iterdir() if p.name != "expected.tsv") == \
        sorted(r[0] for r in TOLERANCE_ROWS)
    assert len(CAMPAIGN_ROWS) + len(TRACE_ROWS) + len(PROGRAM_ROWS) + len(DPRNT_ROWS) >= 20


def _commands_taking(takes) -> list[tuple]:
    """The (sub)command paths of which an argparse action satisfies ``takes``."""
    return [path for path, p in COMMANDS.items() if any(takes(a) for a in p._actions)]


def _assert_listed(paths, templates, reads: str, name: str) -> None:
    """Each command path has an argv template in ``templates`` (the list called ``name``)."""
    for path in paths:
        assert any(t[:len(path)] == path for t in templates), (
            f"'{' '.join(path)}' reads {reads}: add its argv template to {name}")


def test_every_campaign_command_is_listed():
    """Every (sub)command with a CAMPAIGN argument is in COMMANDS_READING_CAMPAIGNS."""
    takes_campaign = _commands_taking(lambda a: a.dest == "campaign")
    assert takes_campaign
    _assert_listed(takes_campaign, COMMANDS_READING_CAMPAIGNS, "a campaign", "COMMANDS_READING_CAMPAIGNS")


# --------------------------------------------------------------------------- campaigns
@pytest.mark.parametrize("template", COMMANDS_READING_CAMPAIGNS, ids=_id)
@pytest.mark.parametrize("name,key,fragment", CAMPAIGN_ROWS, ids=[r[0] for r in CAMPAIGN_ROWS])
def test_bad_campaign(run_cli, tmp_path, inputs, template, name, key, fragment):
    _assert_available(template)
    argv = fill(template, campaign=BAD / name, **inputs)
    assert_one_line_error(run_cli, argv, tmp_path, BAD / name, key, fragment)


# --------------------------------------------------------------------------- traces
@pytest.mark.parametrize("template", COMMANDS_READING_CAMPAIGNS, ids=_id)
@pytest.mark.parametrize("campaign,named,key,fragment", TRACE_ROWS, ids=[r[0] for r in TRACE_ROWS])
def test_bad_trace(run_cli, tmp_path, inputs, template, campaign, named, key, fragment):
    """The trace is read when the campaign loads, so every command that reads a campaign reports it."""
    _assert_available(template)
    argv = fill(template, campaign=TRACES / campaign, **inputs)
    assert_one_line_error(run_cli, argv, tmp_path, TRACES / named, key, fragment)


@pytest.mark.parametrize("campaign,named,key,fragment", TRACE_ROWS, ids=[r[0] for r in TRACE_ROWS])
def test_trace_is_read_when_the_campaign_loads(campaign, named, key, fragment):
    with pytest.raises(InputError) as info:
        load_campaign(TRACES / campaign)
    assert info.value.source == str(TRACES / named)
    assert info.value.key == (None if key == "-" else key)
    assert fragment in info.value.message


def good_trace(pattern: str) -> str:
    """A clean trace of ``pattern`` (both directions) as the corpus campaigns' geometry expects (CR: ψ = θ + 180°)."""
    angles = [15.0 * k for k in range(24)] if pattern[0] == "C" else [10.0 * k for k in range(10)]
    rows = ["angle_deg,dL_um,direction"]
    for d in ("CW", "CCW"):
        for a in angles:
            psi = math.radians(a) + (math.pi if pattern == "CR" else 0.0)
            ua, ub = (math.cos(psi), math.sin(psi)) if pattern[0] == "C" else (math.sin(psi), math.cos(psi))
            rows.append(f"{a:g},{3.0 - 47.9 * ua + 25.4 * ub:.4f},{d}")
    return "\n".join(rows) + "\n"


@pytest.mark.parametrize("campaign,named", [r[:2] for r in TRACE_ROWS if r[1].endswith(".csv")],
                         ids=[r[0] for r in TRACE_ROWS if r[1].endswith(".csv")])
def test_trace_campaigns_are_valid_with_a_good_trace(tmp_path, campaign, named):
    """Control: with a clean trace in place of the bad one the campaign loads, so the trace is the only fault."""
    shutil.copy(TRACES / campaign, tmp_path / campaign)
    run = tomllib.loads((TRACES / campaign).read_text())["ballbar"]["runs"][0]
    assert run["trace_csv"] == named
    (tmp_path / named).write_text(good_trace(run["pattern"]))
    c = load_campaign(tmp_path / campaign)
    first, second = ("ex", "ey") if run["pattern"][0] == "C" else ("ex", "ez")
    assert c.ballbar.runs[0].repeats[first] * 1e3 == pytest.approx([-47.9], abs=1e-3)
    assert c.ballbar.runs[0].repeats[second] * 1e3 == pytest.approx([25.4], abs=1e-3)


# --------------------------------------------------------------------------- NC programs
@pytest.mark.parametrize("template", COMMANDS_READING_PROGRAMS, ids=_id)
@pytest.mark.parametrize("name,key,fragment", PROGRAM_ROWS, ids=[r[0] for r in PROGRAM_ROWS])
def test_bad_nc_program(run_cli, tmp_path, inputs, template, name, key, fragment):
    argv = fill(template, **{**inputs, "program": PROGRAMS / name})
    assert_one_line_error(run_cli, argv, tmp_path, PROGRAMS / name, key, fragment)


def test_programs_the_stricter_reader_still_accepts(run_cli, tmp_path):
    """Block delete, a <name> line, G43 H, a G04 dwell and a G28 return pass; only the motion blocks change."""
    text = ("%\n<BX_TEST>\nO1000 (test)\nG90 G21\n"
            "G43 H1 G00 X-390.0000 Y0.0000 Z-112.2605 B0.0000 C0.0000\n"
            "G04 X2.0\n"
            "/G01 X-388.2722 Y0.0000 Z-112.2647 B0.2778 C0.0000 F2000\n"
            "G28 X0 Y0 Z0\n"
            "G01 X-386.5444 Y0.0000 Z-112.2773 B0.5556 C0.0000\n"
            "M30\n%\n")
    program = parse_program(text, "ok.nc")
    assert [b.number for b in program.motion] == [5, 7, 9]
    (tmp_path / "ok.nc").write_text(text)
    code, _, err = run_cli("compensate", tmp_path / "ok.nc", "-o", tmp_path / "out.nc")
    assert code == 0, err
    before, after = text.splitlines(), (tmp_path / "out.nc").read_text().splitlines()
    assert len(before) == len(after)
    changed = [i + 1 for i, (a, b) in enumerate(zip(before, after)) if a != b]
    assert set(changed) <= {5, 7, 9} and changed  # the dwell (line 6) and G28 (line 8) pass through


def test_generated_programs_parse(run_cli):
    for pattern in ("BX", "CR"):
        code, out, err = run_cli("ncgen", pattern)
        assert code == 0, err
        assert parse_program(out, pattern).motion


# --------------------------------------------------------------------------- DPRNT
@pytest.mark.parametrize("template", COMMANDS_READING_DPRNT, ids=_id)
@pytest.mark.parametrize("name,key,fragment", DPRNT_ROWS, ids=[r[0] for r in DPRNT_ROWS])
def test_bad_dprnt(run_cli, tmp_path, inputs, template, name, key, fragment):
    argv = fill(template, file=DPRNT / name, **inputs)
    assert_one_line_error(run_cli, argv, tmp_path, DPRNT / name, key, fragment)


# --------------------------------------------------------------------------- σ_model prior files
def test_every_sigma_prior_command_is_listed():
    """Every (sub)command with a --sigma-model-prior flag is in COMMANDS_READING_SIGMA_PRIORS."""
    takes = _commands_taking(lambda a: "--sigma-model-prior" in a.option_strings)
    assert {("sample",), ("report",)} <= set(takes)
    _assert_listed(takes, COMMANDS_READING_SIGMA_PRIORS, "a σ_model prior", "COMMANDS_READING_SIGMA_PRIORS")


@pytest.mark.parametrize("template", COMMANDS_READING_SIGMA_PRIORS, ids=lambda t: t[0])
@pytest.mark.parametrize("name,key,fragment", SIGMA_PRIOR_ROWS, ids=[r[0] for r in SIGMA_PRIOR_ROWS])
def test_bad_sigma_model_prior(run_cli, tmp_path, inputs, template, name, key, fragment):
    """A bad --sigma-model-prior file is one line naming the file and the key, exit 2, before any sampling, nothing
    written."""
    argv = fill(template, file=SIGMA_PRIORS / name, **inputs)
    assert_one_line_error(run_cli, argv, tmp_path, SIGMA_PRIORS / name, key, fragment)


# --------------------------------------------------------------------------- stricter checks keep good input
def test_sigma_model_priors_that_stay_valid():
    base = (DATA / "minimal_one_repeat.toml").read_text()
    for spec in ('{dist = "uniform", low_um = 0, high_um = 5}', '{dist = "halfnormal", sd_um = 2}',
                 '{dist = "normal", mean_um = 1, sd_um = 2}'):
        c = parse_campaign(base + f"\n[priors]\nsigma_model = {spec}\n", "p.toml")
        assert c.priors["sigma_model"]["dist"] in spec


# --------------------------------------------------------------------------- tolerance sets
def test_every_tolerances_command_is_listed():
    """Every (sub)command with a --tolerances flag is in COMMANDS_READING_TOLERANCES."""
    takes = _commands_taking(lambda a: "--tolerances" in a.option_strings)
    assert {"fleet"} <= {p[0] for p in takes}
    _assert_listed(takes, COMMANDS_READING_TOLERANCES, "a tolerance set", "COMMANDS_READING_TOLERANCES")


@pytest.mark.parametrize("template", COMMANDS_READING_TOLERANCES, ids=lambda t: t[0])
@pytest.mark.parametrize("name,key,fragment", TOLERANCE_ROWS, ids=[r[0] for r in TOLERANCE_ROWS])
def test_bad_tolerances(run_cli, tmp_path, inputs, template, name, key, fragment):
    """A bad --tolerances file is one line naming the file and the key, exit 2, before any work, nothing written
    (the fleet's cache included: it would be in {out}/.cache)."""
    _assert_available(template)
    campaigns = tmp_path / "campaigns"
    campaigns.mkdir()
    shutil.copy(DATA / "minimal_one_repeat.toml", campaigns / "one.toml")
    argv = fill(template, file=TOLERANCES / name, campaigns=campaigns, **inputs)
    assert_one_line_error(run_cli, argv, tmp_path, TOLERANCES / name, key, fragment)
