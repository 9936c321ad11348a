"""The speed and accuracy targets of the sampler, measured in one run and printed as ratios to the target.

    python bench/targets.py [--repeats 3] [--sbc]

Every command runs as a fresh process (whole process: imports included), as a
user runs it, on the built-in thesis campaign:

* ``sample`` (linear): wall time, sampling time, bulk/tail ESS of the eight and of
  sigma_model, R-hat, largest difference from the exact σ-marginal posterior,
  peak memory, size of ``posterior.nc``;
* ``sample --model htm-thesis``: wall time, diagnostics, and agreement with a long
  reference run (``--target-ess 20000``);
* ``report`` and ``report --compare-models``: wall time;
* issue 25's targets as ratios to the import floor t_ref (``python -c "import arviz, emcee, scipy.stats, numpy"``,
  timed in the same run, alternating with the commands): ``report`` (the built-in campaign, probe readings
  included: three posteriors) ≤ 3 t_ref, ``report`` of the same campaign without its probe readings ≤ 2.5 t_ref,
  ``sample`` ≤ 1.3 t_ref; the byte size of ``index.html`` ≤ 2 MB;
* with ``--sbc``: ``validate sbc --n 200 --model htm-thesis`` (a few minutes): wall
  time, uniformity p-value and 90 % coverage of the eight.

The ratio is value / target for upper bounds and target / value for lower
bounds, so a ratio ≤ 1 meets the target either way.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

EIGHT = ("alpha_CZ", "beta_CZ", "alpha_XB", "beta_XB", "gamma_XB", "alpha_BT", "dx_CZ_minus_dx_BT", "dy_CZ")


def run(argv: list[str], cwd: Path) -> tuple[float, int, str]:
    """Wall time (s), peak memory (MB) and stdout of a fresh process."""
    exe = Path(sys.executable).with_name(argv[0])
    argv = [str(exe) if exe.exists() else shutil.which(argv[0]), *argv[1:]]
    t0 = time.perf_counter()
    with tempfile.TemporaryFile("w+") as out:
        proc = subprocess.Popen(argv, cwd=cwd, stdout=out, stderr=subprocess.DEVNULL)
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - t0
        if status != 0:
            raise SystemExit(f"{' '.join(argv)} failed with status {status}")
        out.seek(0)
        return wall, usage.ru_maxrss // 1024, out.read()


def median_run(argv, cwd, repeats):
    runs = [run(argv, cwd) for _ in range(repeats)]
    return float(np.median([r[0] for r in runs])), max(r[1] for r in runs), runs[-1][2]


IMPORT_FLOOR = ["python", "-c", "import arviz, emcee, scipy.stats, numpy"]


def timed_against_floor(commands: dict, cwd: Path, repeats: int) -> tuple[float, dict[str, float]]:
    """Each command of ``commands`` (``{name: argv}``) run right after a run of the import floor, ``repeats`` rounds
    in the dict's order: t_ref (the floor's median wall time, s) and each command's median wall time (s)."""
    floors, times = [], {name: [] for name in commands}
    for _ in range(repeats):
        for name, argv in commands.items():
            floors.append(run(IMPORT_FLOOR, cwd)[0])
            times[name].append(run(argv, cwd)[0])
    return float(np.median(floors)), {name: float(np.median(ts)) for name, ts in times.items()}


def ratio_row(wall_s: float, t_ref: float, goal: float) -> dict:
    """One command's entry of a speed bench's JSON: its median wall time, its ratio to the import floor, the goal
    and whether the ratio meets it."""
    return {"wall_s": wall_s, "ratio_to_t_ref": wall_s / t_ref, "goal": goal, "met": wall_s / t_ref <= goal}


def floor_rows(tmp: Path, repeats: int, row) -> None:
    """Issue 25: report, a ball-bar-only report and sample as ratios to the import floor, each command timed
    right after a floor run (pairs; medians of each)."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    from variants import without_probe  # the built-in campaign without its touch-probe readings

    (tmp / "ballbar_only.toml").write_text(without_probe(), encoding="utf-8")
    commands = {"report": ["mtmcal-bayes", "report", "-o", "r1", "--quiet"],
                "report, ball bar only": ["mtmcal-bayes", "report", str(tmp / "ballbar_only.toml"), "-o", "r2",
                                          "--quiet"],
                "sample": ["mtmcal-bayes", "sample", "--seed", "1", "--quiet"]}
    t_ref, times = timed_against_floor(commands, tmp, max(repeats, 3))
    row("import floor t_ref (arviz, emcee, scipy.stats, numpy)", t_ref, None, "s")
    for name, target in (("report", 3.0), ("report, ball bar only", 2.5), ("sample", 1.3)):
        row(f"{name}: whole process / t_ref", times[name] / t_ref, target, "")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=3, help="timed runs per command (median reported)")
    ap.add_argument("--sbc", action="store_true", help="also run validate sbc --n 200 --model htm-thesis")
    ap.add_argument("--floor-only", action="store_true", help="only issue 25's ratios to the import floor")
    args = ap.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="targets-"))
    rows = []

    def row(what, value, target, unit, upper=True):
        """A measure against its target; ``target`` None: stated, no target."""
        if target is None:
            rows.append((what, value, "stated", unit, None))
            return
        ratio = value / target if upper else target / value
        rows.append((what, value, f"{'≤' if upper else '≥'} {target:g}", unit, ratio))

    if args.floor_only:
        run(["mtmcal-bayes", "report", "-o", "rep", "--quiet"], tmp)
        row("report: index.html", (tmp / "rep" / "index.html").stat().st_size / 1e6, 2.0, "MB")
        floor_rows(tmp, args.repeats, row)
        _print(rows, args.repeats)
        return
    wall, mem, out = median_run(["mtmcal-bayes", "sample", "--seed", "1", "--quiet", "--json", "-o", "post.nc"],
                                tmp, args.repeats)
    doc = json.loads(out)
    d, s = doc["diagnostics"], doc["summary"]
    row("sample (linear): whole process", wall, 3.0, "s")
    row("sample (linear): sampling", d["wall_time_s"], 1.0, "s")
    row("sample (linear): min bulk ESS, eight", min(s[n]["ess_bulk"] for n in EIGHT), 1000, "", upper=False)
    row("sample (linear): min tail ESS, eight", min(s[n]["ess_tail"] for n in EIGHT), 1000, "", upper=False)
    row("sample (linear): bulk/tail ESS, sigma_model", min(s["sigma_model"]["ess_bulk"], s["sigma_model"]["ess_tail"]),
        400, "", upper=False)
    row("sample (linear): max R-hat", d["max_r_hat"], 1.01, "")
    row("sample (linear): max |mean − exact|", d["reference"]["max_mean_diff_sd"], 0.05, "sd")
    row("sample (linear): max |sd − exact|", d["reference"]["max_sd_diff_pct"], 3.0, "%")
    row("sample (linear): peak memory", mem, 400, "MB")
    row("sample (linear): posterior.nc", (tmp / "post.nc").stat().st_size / 1e6, 5.0, "MB")

    wall, mem, out = median_run(["mtmcal-bayes", "sample", "--model", "htm-thesis", "--seed", "1", "--quiet", "--json"],
                                tmp, args.repeats)
    doc = json.loads(out)
    d, s = doc["diagnostics"], doc["summary"]
    _, _, ref_out = run(["mtmcal-bayes", "sample", "--model", "htm-thesis", "--seed", "2", "--target-ess", "20000",
                         "--quiet", "--json"], tmp)
    ref = json.loads(ref_out)["summary"]
    row("sample (htm-thesis): whole process", wall, 10.0, "s")
    row("sample (htm-thesis): min bulk/tail ESS, eight",
        min(min(s[n]["ess_bulk"], s[n]["ess_tail"]) for n in EIGHT), 1000, "", upper=False)
    row("sample (htm-thesis): max R-hat", d["max_r_hat"], 1.01, "")
    # two Monte-Carlo runs: the difference expected from their ESS alone (means: 1/√ESS each; sds: 1/√(2·ESS) each)
    ess = {n: (min(s[n]["ess_bulk"], s[n]["ess_tail"]), min(ref[n]["ess_bulk"], ref[n]["ess_tail"])) for n in EIGHT}
    row("sample (htm-thesis): max |mean − long run|", max(abs(s[n]["mean"] - ref[n]["mean"]) / ref[n]["sd"] for n in EIGHT),
        None, "sd")
    row("  expected from Monte-Carlo error alone (1σ)", max(np.sqrt(1 / a + 1 / b) for a, b in ess.values()), None, "sd")
    row("sample (htm-thesis): max |sd − long run|", max(100 * abs(s[n]["sd"] / ref[n]["sd"] - 1) for n in EIGHT), None, "%")
    row("  expected from Monte-Carlo error alone (1σ, Gaussian)",
        max(100 * np.sqrt(1 / (2 * a) + 1 / (2 * b)) for a, b in ess.values()), None, "%")
    row("sample (htm-thesis): peak memory", mem, 400, "MB")

    wall, _, _ = median_run(["mtmcal-bayes", "report", "-o", "rep", "--quiet"], tmp, args.repeats)
    row("report (linear): whole process", wall, 10.0, "s")
    row("report: index.html", (tmp / "rep" / "index.html").stat().st_size / 1e6, 2.0, "MB")
    floor_rows(tmp, args.repeats, row)
    wall, _, _ = median_run(["mtmcal-bayes", "report", "-o", "cmp", "--compare-models", "--quiet"], tmp, 1)
    row("report --compare-models: whole process", wall, 45.0, "s")

    if args.sbc:
        wall, _, out = run(["mtmcal-bayes", "validate", "sbc", "--n", "200", "--model", "htm-thesis", "--json",
                            "--quiet"], tmp)
        q = json.loads(out)["quantities"]
        row("validate sbc --n 200 htm-thesis: whole process", wall / 60, 10.0, "min")
        row("validate sbc: min p_uniform, eight", min(q[n]["p_uniform"] for n in EIGHT), 0.01, "", upper=False)
        cov = [q[n]["coverage_90"] for n in EIGHT]
        row("validate sbc: 90 % coverage, lowest of eight", 100 * min(cov), 86.0, "%", upper=False)
        row("validate sbc: 90 % coverage, highest of eight", 100 * max(cov), 94.0, "%")

    _print(rows, args.repeats)
    shutil.rmtree(tmp, ignore_errors=True)


def _print(rows, repeats: int) -> None:
    print(f"Targets of issues 14 and 25, built-in thesis campaign, {os.cpu_count()} cores, median of {repeats} runs "
          "(whole process: imports included)")
    print(f"{'measure':52s} {'value':>10s} {'target':>10s} {'unit':4s} {'ratio':>6s}")
    for what, value, target, unit, ratio in rows:
        verdict = "" if ratio is None else f"{ratio:6.2f} {'ok' if ratio <= 1 else 'MISSED'}"
        print(f"{what:52s} {value:10.3g} {target:>10s} {unit:4s} {verdict}")


if __name__ == "__main__":
    main()
