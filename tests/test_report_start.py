"""The report's first steps (``reporting/start.py``): the machine's figures begun before the report's computation is
imported, and a failure among them handled as any drawing's."""

from __future__ import annotations

import json
import subprocess
import sys

from mtmcal_bayes.reporting import machine_figure

#: modules of the report's computation: none of them may be imported by its first steps
COMPUTATION = ("mtmcal_bayes.reporting.build", "mtmcal_bayes.inference", "mtmcal_bayes.posterior",
               "mtmcal_bayes.planning", "arviz", "emcee", "scipy.stats", "xarray")


def _fresh(code: str) -> dict:
    """Run ``code`` in a new interpreter (nothing imported yet) and return the JSON it prints last."""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_first_steps_import_no_computation():
    """Importing the first steps (and the package ``reporting``) imports none of the computation's modules; the
    package still gives ``build_report`` when asked for it."""
    seen = _fresh(
        "import json, sys\n"
        "import mtmcal_bayes.reporting.start\n"
        f"light = sorted(m for m in {COMPUTATION!r} if m in sys.modules)\n"
        "from mtmcal_bayes.reporting import build_report\n"
        "from mtmcal_bayes.reporting.build import build_report as built\n"
        "print(json.dumps({'light': light, 'same': build_report is built}))")
    assert seen == {"light": [], "same": True}


def test_machine_figures_begun_before_the_computation_is_imported(tmp_path):
    """Through the command's own function: the first batch drawn holds the machine's two figures and begins while
    none of the computation's modules is imported; the report is written whole."""
    out = tmp_path / "rep"
    seen = _fresh(
        "import json, sys\n"
        "from mtmcal_bayes.reporting import drawing\n"
        "batches = []\n"
        "real = drawing.Drawing.start\n"
        "def start(self, jobs, workers=None):\n"
        f"    batches.append(([n for n, _ in jobs], sorted(m for m in {COMPUTATION!r} if m in sys.modules)))\n"
        "    return real(self, jobs, workers)\n"
        "drawing.Drawing.start = start\n"
        "import mtmcal_bayes as mb\n"
        f"rep = mb.report(output={str(out)!r}, sampler='exact', seed=1)\n"
        "print(json.dumps({'first': batches[0], 'files': rep.files}))")
    names, imported = seen["first"]
    assert names == ["machine.png", "deviations.png"] and imported == []
    assert {"machine.png", "deviations.png", "corner.png", "index.html"} <= set(seen["files"])
    assert all((out / f).is_file() for f in seen["files"])


def test_failure_in_the_first_figures_leaves_nothing(run_cli, tmp_path, monkeypatch):
    """A machine figure that fails stops the report as any drawing does: one line naming the figure, exit 1, no
    temporary directory left and the existing output directory as it was."""
    def broken(*args, **kwargs):
        raise RuntimeError("simulated failure while drawing the machine")

    monkeypatch.setattr(machine_figure, "chain_figure", broken)
    existing = tmp_path / "rep"
    existing.mkdir()
    (existing / "keep.txt").write_text("mine")
    code, out, err = run_cli("report", "-o", existing, "--sampler", "exact", "--quiet")
    assert code == 1 and "machine.png" in err and "simulated failure while drawing the machine" in err
    assert len(err.strip().splitlines()) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rep"]
    assert sorted(p.name for p in existing.iterdir()) == ["keep.txt"]
