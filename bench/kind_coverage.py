"""Which statements of the package run for one kind of machine only (issue 42's measure of two stacks).

Every command of the README runs on the thesis campaign, and again on the three built-in demo campaigns, each set
under its own coverage measurement (in this process; the report's drawing processes are measured too). A statement
in a function body counts when either set runs it; the table gives, per unit of the package, how many ran for the
thesis machine only and how many for described machines only, and the totals, outside the plug-ins (``plugins/``,
whose code is the thesis machine's by definition) and inside them.

    python bench/kind_coverage.py [--keep DIR]       (needs the coverage package: pip install coverage)
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


def commands(machine: list[str], out: Path, program: str, pattern: str, history: list[list[str]]) -> list[list[str]]:
    """The README's commands on one machine (``machine``: ``[]`` for the thesis campaign or ``["--machine", T]``),
    writing below ``out`` (made here)."""
    out.mkdir(parents=True, exist_ok=True)
    return [
        ["identify", *machine, "--json"],
        ["sensitivity", *machine, "--json"],
        ["sample", *machine, "--seed", "1", "--json"],
        ["sample", *machine, "--sampler", "exact", "--seed", "1", "--json"],
        ["sample", *machine, "--closed-form", "--json"],
        ["report", *machine, "-o", str(out / "report"), "--seed", "1"],
        ["plan", *machine, "--json"],
        ["design", *machine, "--seed", "1", "--json", "-o", str(out / "design")],
        ["instruments", *machine, "--json"],
        ["compensate", *machine, program, "-o", str(out / "comp.nc"), "--json"],
        ["axes", *machine, "--json"],
        ["ncgen", *machine, pattern],
        ["validate", "sbc", *machine, "--n", "8", "--sampler", "exact", "--workers", "1", "--json"],
        *history,
    ]


def run_all(argvs: list[list[str]]) -> None:
    """Run each command, its output swallowed; a command that fails is named on stderr with its last line."""
    from mtmcal_bayes.cli import main

    for argv in argvs:
        err = io.StringIO()
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
            try:
                code = main(argv)
            except SystemExit as exit_:
                code = exit_.code
        if code not in (0, None):
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
    ap.add_argument("--measure", type=Path, default=None, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.measure is not None:
        measure_here(a.measure)
        return 0
    work = Path(a.keep or tempfile.mkdtemp(prefix="kind-coverage-"))
    work.mkdir(parents=True, exist_ok=True)
    thesis_hist = [["simulate", "--history", str(work / "th"), "--serial", "M-1", "--campaigns", "3", "--step",
                    "beta_CZ=40@3", "--seed", "1"], ["history", str(work / "th"), "--json"],
                   ["fleet", str(work / "th"), "-o", str(work / "thf"), "--sampler", "exact", "--workers", "1",
                    "--json"]]
    thesis = commands([], work / "out" / "thesis", THESIS_PROGRAM, "BX", thesis_hist)
    described = []
    for t in TYPES:
        hist = [["simulate", "--history", str(work / t), "--machine", t, "--campaigns", "3", "--seed", "1"],
                ["history", str(work / t), "--json"],
                ["fleet", str(work / t), "-o", str(work / f"{t}-fleet"), "--sampler", "exact", "--workers", "1",
                 "--json"]]
        described += commands(["--machine", t], work / "out" / t, str(ROOT / "examples" / "machines" / f"{t}-five-axis.nc"),
                              "--run=1", hist)
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
