"""Which statements of the package run for one kind of machine only (issue 42's measure of two stacks).

Every command of the README runs on the thesis campaign, and again on the three built-in demo campaigns, each set
under its own coverage measurement (in this process; the report's drawing processes are measured too). A statement
in a function body counts when either set runs it; the table gives, per unit of the package, how many ran for the
thesis machine only and how many for described machines only, and the totals, outside the plug-ins (``plugins/``,
whose code is the thesis machine's by definition) and inside them.

Each machine gets the same command lines: a history with a step change of one of its deviations, a design within a
budget besides the default one, a ball-bar program by pattern name and by run number and a touch-probe program, a
posterior through the machine's chain (``--model chain``) besides its default model's, a compensation with the
posterior of ``sample -o`` besides the default one, and a report on the first campaign of its simulated history (with
its truth).  What one kind has in its data the other gets in a copy of its campaigns: the demos a probe that
disagrees with its ball bar, as the thesis campaign's does (one group of probed positions moved 60 µm along Z;
``instruments``, and ``compensate``, refused and then accepted, run on it); the thesis machine a touch-probe run of
``[[probe.runs]]``, as the demos have (``sample --data probe`` and ``ncgen --probe`` run on it).  ``--uneven``
measures the first, uneven command lines instead (the thesis' history alone stepped, its design alone adding runs,
no copies), as issue 42 was first measured; ``--no-copies`` the same command lines without the copies.

    python bench/kind_coverage.py [--keep DIR] [--uneven | --no-copies]      (needs the coverage package: pip install coverage)
"""

from __future__ import annotations

import argparse
import ast
import contextlib
import io
import json
import subprocess
import sys
import tempfile
from pathlib import Path

# bench/coverage.py (the coverage of credible intervals) would shadow the coverage package
sys.path = [p for p in sys.path if Path(p or ".").resolve() != Path(__file__).resolve().parent]
import coverage  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "mtmcal_bayes"
TYPES = ("trunnion", "vertical-turn-mill", "head-head")
THESIS_PROGRAM = str(PACKAGE / "datasets" / "fig4_30a_bx_original.nc")
#: the deviation each demo's history steps by 40 (″ or µm) at its third campaign, as the thesis' steps beta_CZ
STEP = {"trunnion": "E_B0C", "vertical-turn-mill": "E_B0C", "head-head": "E_B0C"}
#: first word of a command line that must be refused (exit status 2: the instruments disagree)
REFUSED = "(refused)"
#: how far one group of a demo's probed positions is moved along Z, mm
MOVED_MM = 0.060


def simulated_report(history: Path, serial: str) -> list[str]:
    """``report`` on the first campaign of a simulated history (one with its truth)."""
    first = history / f"{serial}_2026-01-05.toml"
    return ["report", str(first), "-o", str(history / "report-first"), "--sampler", "exact", "--seed", "1"]


def first_pattern(machine: str) -> str:
    """The pattern of the demo campaign's first ball-bar run."""
    from mtmcal_bayes import load_campaign
    from mtmcal_bayes.io.machine_reader import demo_campaign

    return load_campaign(demo_campaign(machine)).ballbar.runs[0].pattern


def disagreeing_probe(machine: str, path: Path) -> Path:
    """The demo campaign of ``machine`` written to ``path`` with the positions of its first probe run at the last
    angle of its first indexed axis moved :data:`MOVED_MM` along Z: a probe that disagrees with the ball bar."""
    import ast

    from mtmcal_bayes import load_campaign
    from mtmcal_bayes.io.machine_reader import demo_campaign

    source = demo_campaign(machine)
    run = load_campaign(source).probe.runs[0]
    first = next(iter(run.angles.values()))
    group = [i for i, v in enumerate(first) if v == first[-1]]
    text = Path(source).read_text(encoding="utf-8")
    line = next(ln for ln in text.splitlines() if ln.startswith("centres_mm = "))
    centres = ast.literal_eval(line.split("=", 1)[1].strip())
    for repeat in centres:
        for i in group:
            repeat[i][2] += MOVED_MM
    path.write_text(text.replace(line, "centres_mm = " + repr(centres)), encoding="utf-8")
    return path


def added_probe_run(path: Path) -> Path:
    """The thesis campaign written to ``path`` with a ``[[probe.runs]]`` run added (what the demo campaigns' probes
    are): a sphere on the C table off its axis, read at four C and two more B positions with a stylus of
    ``[probe.styli]``, its readings the machine's nominal ones, twice."""
    import tomllib

    import numpy as np

    from mtmcal_bayes import load_campaign
    from mtmcal_bayes.datasets import builtin_campaign_text
    from mtmcal_bayes.io.tomlio import dumps
    from mtmcal_bayes.models.probe import ChainProbeKernel, ProbeLayout

    doc = tomllib.loads(builtin_campaign_text()[0])
    doc["probe"]["styli"] = {"mid": {"length_mm": 400.0}}
    run = {"id": "table", "stylus": "mid", "sphere_mm": [150.0, 50.0, 60.0],
           "angles_deg": {"C": [0.0, 90.0, 180.0, 270.0, 0.0, 0.0], "B": [0.0, 0.0, 0.0, 0.0, 30.0, 60.0]},
           "centres_mm": np.zeros((2, 6, 3)).tolist()}
    doc["probe"]["runs"] = [run]
    path.write_text(dumps(doc), encoding="utf-8")
    c = load_campaign(path)
    zero = ProbeLayout(c, kernel=ChainProbeKernel(c.machine.description)).zero[-6:]
    run["centres_mm"] = np.stack([zero, zero]).tolist()
    path.write_text(dumps(doc), encoding="utf-8")
    return path


def commands(machine: list[str], out: Path, program: str, pattern: list[str], history: list[list[str]],
             even: bool = True) -> list[list[str]]:
    """The README's commands on one machine (``machine``: ``[]`` for the thesis campaign or ``["--machine", T]``),
    writing below ``out`` (made here); ``pattern`` the ``ncgen`` arguments of each ball-bar program; ``even``: with a
    design within a budget alone besides the default one."""
    out.mkdir(parents=True, exist_ok=True)
    even_only = [
        ["design", *machine, "--seed", "1", "--contraction", "0", "--budget-min", "60", "--json", "-o",
         str(out / "design-budget")],
        ["sample", *machine, "--model", "chain", "--seed", "1", "--max-steps", "2000", "--json"],
        ["sample", *machine, "--sampler", "exact", "--seed", "1", "-o", str(out / "post.nc")],
        ["compensate", *machine, program, "--posterior", str(out / "post.nc"), "-o", str(out / "comp-post.nc"),
         "--json"],
        ["ncgen", *machine, "--probe", "1"],
    ] if even else []
    return [
        ["identify", *machine, "--json"],
        ["sensitivity", *machine, "--json"],
        ["sample", *machine, "--seed", "1", "--json"],
        ["sample", *machine, "--sampler", "exact", "--seed", "1", "--json"],
        ["sample", *machine, "--closed-form", "--json"],
        ["report", *machine, "-o", str(out / "report"), "--seed", "1"],
        ["plan", *machine, "--json"],
        ["design", *machine, "--seed", "1", "--json", "-o", str(out / "design")],
        *even_only,
        ["instruments", *machine, "--json"],
        ["compensate", *machine, program, "-o", str(out / "comp.nc"), "--json"],
        ["axes", *machine, "--json"],
        *(["ncgen", *machine, p] for p in pattern),
        ["validate", "sbc", *machine, "--n", "8", "--sampler", "exact", "--workers", "1", "--json"],
        *history,
    ]


def run_all(argvs: list[list[str]]) -> None:
    """Run each command, its output swallowed; a command that fails (or, marked :data:`REFUSED`, is not refused) is
    named on stderr with its last line."""
    from mtmcal_bayes.cli import main

    for argv in argvs:
        expected = (0, None)
        if argv[0] == REFUSED:
            argv, expected = argv[1:], (2,)
        err = io.StringIO()
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
            try:
                code = main(argv)
            except SystemExit as exit_:
                code = exit_.code
        if code not in expected:
            last = (err.getvalue().strip().splitlines() or ["(no message)"])[-1]
            print(f"kind_coverage: {' '.join(argv)} exited {code}: {last}", file=sys.stderr)


def body_lines(path: Path) -> set[int]:
    """The lines of statements inside function bodies (docstrings excluded)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    out: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(getattr(body[0], "value", None), ast.Constant):
                body = body[1:]
            for stmt in body:
                for sub in ast.walk(stmt):
                    if isinstance(sub, ast.stmt):
                        out.add(sub.lineno)
    return out


def measure(name: str, argvs: list[list[str]], workdir: Path) -> dict[str, set[int]]:
    """The lines run by ``argvs``, measured in a fresh interpreter of its own: worker processes the package keeps
    (the report's drawing pool) would otherwise carry one kind's measurement into the other's."""
    workdir = workdir / name
    workdir.mkdir(parents=True, exist_ok=True)
    (workdir / "argvs.json").write_text(json.dumps(argvs), encoding="utf-8")
    subprocess.run([sys.executable, __file__, "--measure", str(workdir)], check=True)
    lines: dict[str, set[int]] = {}
    for path in workdir.glob(".coverage*"):  # one data file per process
        data = coverage.CoverageData(basename=str(path))
        data.read()
        for f in data.measured_files():
            lines.setdefault(f, set()).update(data.lines(f) or ())
    return lines


def measure_here(workdir: Path) -> None:
    """Run the commands of ``workdir/argvs.json`` under coverage, each process' data in a file of its own there."""
    argvs = json.loads((workdir / "argvs.json").read_text(encoding="utf-8"))
    rc = workdir / "coveragerc"
    rc.write_text(f"[run]\nsource = {PACKAGE}\nconcurrency = thread, multiprocessing\nparallel = true\n"
                  f"data_file = {workdir / '.coverage'}\n", encoding="utf-8")
    cov = coverage.Coverage(config_file=str(rc))
    cov.start()
    run_all(argvs)
    cov.stop()
    cov.save()


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--keep", type=Path, default=None, help="keep the outputs in DIR")
    ap.add_argument("--uneven", action="store_true", help="the first, uneven command lines (module docstring)")
    ap.add_argument("--no-copies", action="store_true", help="the same command lines, without the copies of the "
                    "campaigns that give one kind what the other has in its data")
    ap.add_argument("--measure", type=Path, default=None, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.measure is not None:
        measure_here(a.measure)
        return 0
    work = Path(a.keep or tempfile.mkdtemp(prefix="kind-coverage-"))
    work.mkdir(parents=True, exist_ok=True)
    thesis_hist = [["simulate", "--history", str(work / "th"), "--serial", "M-1", "--campaigns", "3", "--step",
                    "beta_CZ=40@3", "--start", "2026-01-05", "--seed", "1"], ["history", str(work / "th"), "--json"],
                   ["fleet", str(work / "th"), "-o", str(work / "thf"), "--sampler", "exact", "--workers", "1",
                    "--json"]]
    even = not a.uneven
    copies = even and not a.no_copies
    if even:
        thesis_hist += [simulated_report(work / "th", "M-1")]
    thesis = commands([], work / "out" / "thesis", THESIS_PROGRAM, ["BX", "--run=1"] if even else ["BX"],
                      thesis_hist, even)
    described = []
    for t in TYPES:
        step = ["--step", f"{STEP[t]}=40@3"] if even else []
        hist = [["simulate", "--history", str(work / t), "--machine", t, "--campaigns", "3", *step, "--start",
                 "2026-01-05", "--seed", "1"],
                ["history", str(work / t), "--json"],
                ["fleet", str(work / t), "-o", str(work / f"{t}-fleet"), "--sampler", "exact", "--workers", "1",
                 "--json"]]
        if even:
            hist += [simulated_report(work / t, "SIM-001")]
        program = str(ROOT / "examples" / "machines" / f"{t}-five-axis.nc")
        described += commands(["--machine", t], work / "out" / t, program,
                              [first_pattern(t), "--run=1"] if even else ["--run=1"], hist, even)
        if copies:  # what the thesis campaign has in its data
            moved = disagreeing_probe(t, work / f"{t}-moved.toml")
            described += [["instruments", str(moved), "--json"],
                          [REFUSED, "compensate", str(moved), program, "-o", str(work / f"{t}-refused.nc"),
                           "--json"],
                          ["compensate", str(moved), program, "--accept-disagreement", "-o",
                           str(work / f"{t}-moved.nc"), "--json"]]
    if copies:  # what the demo campaigns have in their data: a run of [[probe.runs]]
        added = added_probe_run(work / "thesis-probe-run.toml")
        thesis += [["sample", str(added), "--data", "probe", "--sampler", "exact", "--seed", "1", "--json"],
                   ["ncgen", "--probe", "table", str(added)]]
    a_lines = measure("thesis", thesis, work)
    b_lines = measure("described", described, work)
    rows = []
    for path in sorted(PACKAGE.rglob("*.py")):
        f = str(path)
        body = body_lines(path)
        ra, rb = a_lines.get(f, set()) & body, b_lines.get(f, set()) & body
        rows.append((path.relative_to(PACKAGE), len(body), len(ra | rb), len(ra - rb), len(rb - ra)))
    for label, keep in (("outside plugins/", lambda p: p.parts[0] != "plugins"),
                        ("plugins/", lambda p: p.parts[0] == "plugins")):
        sel = [r for r in rows if keep(r[0])]
        body, ran, only_a, only_b = (sum(r[i] for r in sel) for i in (1, 2, 3, 4))
        print(f"{label}: {body} statements in function bodies, {ran} run by either kind; thesis only {only_a} "
              f"({100 * only_a / max(ran, 1):.1f} % of those run, {100 * only_a / max(body, 1):.1f} % of all), "
              f"described only {only_b} ({100 * only_b / max(ran, 1):.1f} % of those run, "
              f"{100 * only_b / max(body, 1):.1f} % of all)")
    print("\nunits with the most one-kind statements (thesis only / described only):")
    by_unit: dict[str, list[int]] = {}
    for p, body, ran, oa, ob in rows:
        u = p.parts[0] if len(p.parts) > 1 else p.stem
        acc = by_unit.setdefault(u, [0, 0, 0])
        acc[0] += ran
        acc[1] += oa
        acc[2] += ob
    for u, (ran, oa, ob) in sorted(by_unit.items(), key=lambda kv: -(kv[1][1] + kv[1][2]))[:15]:
        print(f"  {u:16s} run {ran:5d}   thesis only {oa:5d}   described only {ob:5d}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
