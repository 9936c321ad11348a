"""The safety net of a refactoring: every command's ``--json`` and the report's CSVs at fixed seeds, on the thesis
campaign and on each built-in type's demo, written to a folder; ``--compare BEFORE`` then says which differ.

    python bench/snapshot.py OUT [--only NAME ...] [--jobs 2]
    python bench/snapshot.py OUT --compare BEFORE

JSON is compared with wall times removed (keys naming seconds, elapsed or wall time); every other file byte for
byte.  A command that fails is recorded with its exit status and its stderr, so a change of failure shows too.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EXE = [sys.executable, "-m", "mtmcal_bayes.cli"]
TYPES = ("trunnion", "vertical-turn-mill", "head-head")
THESIS_PROGRAM = str(ROOT / "mtmcal_bayes" / "datasets" / "fig4_30a_bx_original.nc")
TIMING_KEYS = ("seconds", "second", "elapsed", "wall", "time_s", "duration")


def commands() -> dict[str, list]:
    """name -> argv after the executable; ``{out}`` is replaced by the command's own output folder."""
    c: dict[str, list[str]] = {}
    c["thesis-identify"] = ["identify", "--json"]
    for model in ("linear", "htm-thesis"):
        for data in ("ballbar", "probe", "both"):
            c[f"thesis-sample-{model}-{data}"] = ["sample", "--model", model, "--data", data, "--seed", "1", "--json"]
    c["thesis-sample-exact"] = ["sample", "--sampler", "exact", "--seed", "1", "--json"]
    c["thesis-closed-form"] = ["sample", "--closed-form", "--json"]
    c["thesis-plan"] = ["plan", "--json"]
    c["thesis-design"] = ["design", "--json", "--seed", "1"]
    c["thesis-instruments"] = ["instruments", "--json"]
    c["thesis-compensate"] = ["compensate", THESIS_PROGRAM, "-o", "{out}/comp.nc", "--json"]
    c["thesis-axes"] = ["axes", "--json"]
    c["thesis-report"] = ["report", "-o", "{out}/report", "--seed", "1", "--json"]
    c["thesis-sensitivity"] = ["sensitivity", "--json"]
    c["thesis-sensitivity-text"] = ["sensitivity"]
    c["thesis-sensitivity-markdown"] = ["sensitivity", "--markdown"]
    for t in TYPES:
        m = ["--machine", t]
        c[f"{t}-identify"] = ["identify", *m, "--json"]
        c[f"{t}-sample"] = ["sample", *m, "--seed", "1", "--json"]
        c[f"{t}-sample-exact"] = ["sample", *m, "--sampler", "exact", "--seed", "1", "--json"]
        for data in ("ballbar", "probe"):
            c[f"{t}-sample-exact-{data}"] = ["sample", *m, "--sampler", "exact", "--data", data, "--seed", "1",
                                             "--json"]
        c[f"{t}-plan"] = ["plan", *m, "--json"]
        c[f"{t}-design"] = ["design", *m, "--json", "--seed", "1"]
        c[f"{t}-instruments"] = ["instruments", *m, "--json"]
        c[f"{t}-compensate"] = ["compensate", *m, str(ROOT / "examples" / "machines" / f"{t}-five-axis.nc"),
                                "-o", "{out}/comp.nc", "--json"]
        c[f"{t}-axes"] = ["axes", *m, "--json"]
        c[f"{t}-report"] = ["report", *m, "-o", "{out}/report", "--seed", "1", "--json"]
        c[f"{t}-sensitivity"] = ["sensitivity", *m, "--json"]
        c[f"{t}-sensitivity-text"] = ["sensitivity", *m]
        c[f"{t}-sensitivity-markdown"] = ["sensitivity", *m, "--markdown"]
    # the README's history and fleet lines (each step after the first runs in the same folder)
    c["readme-history"] = [["simulate", "--history", "plant/M-1", "--serial", "M-1", "--type", "MTX", "--campaigns",
                            "4", "--step", "beta_CZ=40@3", "--seed", "1"],
                           ["history", "plant/M-1", "--json"]]
    c["readme-fleet"] = [["simulate", "--history", "plant/M-1", "--serial", "M-1", "--type", "MTX", "--campaigns", "4",
                          "--step", "beta_CZ=40@3", "--seed", "1"],
                         ["simulate", "--history", "plant/M-2", "--serial", "M-2", "--type", "MTX", "--campaigns", "4",
                          "--ramp", "alpha_XB=8@1", "--temperatures", "18.5,23,19.5,24", "--thermal", "alpha_XB=1.5",
                          "--seed", "2"],
                         ["fleet", "plant", "-o", "fleet", "--sampler", "exact", "--tolerances",
                          str(ROOT / "examples" / "plant_tolerances.toml"), "--json"]]
    c["trunnion-history"] = [["simulate", "--history", "h", "--machine", "trunnion", "--campaigns", "3", "--step",
                              "E_B0C=40@3", "--seed", "1"],
                             ["history", "h", "--json"]]
    c.update(simulate_commands())
    return c


def simulate_commands() -> dict[str, list]:
    """``simulate`` on every campaign format: text, ``--json``, ``linear``, ``-o`` with and without noise, written
    histories; planned runs (designed campaigns), a probe gap (a C-axis run naming no stylus) and probe-only
    campaigns (the controller cycles)."""
    data = ROOT / "tests" / "data"
    thesis_truth = str(data / "formats_truth.toml")
    cases = {"thesis": ([], thesis_truth),
             "thesis-designed": ([str(data / "formats" / "designed_thesis_d54cc98.toml")], thesis_truth),
             "thesis-new-designed": ([str(data / "formats" / "designed_new_machine_d54cc98.toml")], thesis_truth),
             "thesis-probe-gap": ([str(data / "formats" / "thesis_first_published.toml")], thesis_truth)}
    truths = ROOT / "bench" / "simulate_truths"  # each demo's [truth]
    for t in TYPES:
        cases[t] = (["--machine", t], str(truths / f"{t}.toml"))
    for t in ("trunnion", "head-head"):
        cases[f"{t}-cycle"] = ([str(data / "controller_cycles" / f"{t}-cycle.toml")], str(truths / f"{t}.toml"))
    c: dict[str, list] = {}
    for name, (where, truth) in cases.items():
        base = ["simulate", *where, "--truth", truth]
        c[f"{name}-simulate-text"] = base
        c[f"{name}-simulate"] = [*base, "--json"]
        c[f"{name}-simulate-linear"] = [*base, "--model", "linear", "--json"]
        c[f"{name}-simulate-o"] = [*base, "-o", "{out}/synthetic.toml"]
        c[f"{name}-simulate-noise"] = [*base, "--noise", "--seed", "3", "-o", "{out}/synthetic.toml"]
        c[f"{name}-simulate-linear-noise"] = [*base, "--model", "linear", "--noise", "--seed", "3", "-o",
                                              "{out}/synthetic.toml"]
        c[f"{name}-simulate-history"] = ["simulate", *where, "--truth", truth, "--history", "h", "--campaigns", "2",
                                         "--seed", "1"]
    return c


def run_one(name: str, argv: list[str], out: Path) -> None:
    d = out / name
    if d.exists():
        shutil.rmtree(d)
    d.mkdir(parents=True)
    steps = argv if isinstance(argv[0], list) else [argv]
    for step in steps:
        args = [a.replace("{out}", str(d)) for a in step]
        p = subprocess.run(EXE + args, capture_output=True, text=True, cwd=d)
        if p.returncode:
            break
    (d / "stdout.txt").write_text(p.stdout)
    (d / "status.txt").write_text(f"{p.returncode}\n{p.stderr if p.returncode else ''}")
    # keep the tables and programs; drop the figures, the HTML and the NetCDF (they carry dates or pixels)
    for f in list(d.rglob("*")):
        if f.is_file() and f.suffix in {".png", ".html", ".nc"} and f.name != "comp.nc":
            f.unlink()


def strip_times(obj):
    if isinstance(obj, dict):
        return {k: strip_times(v) for k, v in obj.items() if not any(t in k.lower() for t in TIMING_KEYS)}
    if isinstance(obj, list):
        return [strip_times(v) for v in obj]
    return obj


def normalised(f: Path, root: Path) -> str:
    """The file's text with its snapshot folder and temporary folders written as placeholders."""
    text = f.read_text(errors="replace").replace(str(root), "{out}")
    return re.sub(r"/tmp/[A-Za-z0-9_.-]+", "/tmp/{tmp}", text)


def same(a: Path, b: Path, root_a: Path, root_b: Path) -> bool:
    ta, tb = normalised(a, root_a), normalised(b, root_b)
    if a.suffix in {".txt", ".json"}:
        try:
            return strip_times(json.loads(ta)) == strip_times(json.loads(tb))
        except json.JSONDecodeError:
            pass
    return ta == tb


def compare(out: Path, before: Path) -> int:
    """Print each file of ``before``'s commands that ``out`` lacks or has otherwise, and each file a command now
    writes that it did not (only the commands both snapshots ran); returns 1 when any is found."""
    bad = 0
    for d in sorted(p for p in before.iterdir() if p.is_dir()):
        for f in sorted(p for p in d.rglob("*") if p.is_file() and ".cache" not in p.parts):
            g = out / f.relative_to(before)
            if not g.exists():
                print(f"missing  {f.relative_to(before)}")
                bad += 1
            elif not same(f, g, before, out):
                print(f"differs  {f.relative_to(before)}")
                bad += 1
        if (out / d.name).is_dir():
            for g in sorted(p for p in (out / d.name).rglob("*") if p.is_file() and ".cache" not in p.parts):
                if not (before / g.relative_to(out)).exists():
                    print(f"new      {g.relative_to(out)}")
                    bad += 1
    print(f"{bad} difference(s)")
    return 1 if bad else 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--only", nargs="*", default=None, help="substrings of the names to run")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--compare", type=Path, default=None, metavar="BEFORE")
    a = ap.parse_args()
    a.out.mkdir(parents=True, exist_ok=True)
    todo = {k: v for k, v in commands().items() if not a.only or any(s in k for s in a.only)}
    with concurrent.futures.ThreadPoolExecutor(a.jobs) as pool:
        for f in [pool.submit(run_one, k, v, a.out) for k, v in todo.items()]:
            f.result()
    return compare(a.out, a.compare) if a.compare else 0


if __name__ == "__main__":
    sys.exit(main())
