"""The README's Python section runs as written, and shows what it says it shows."""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def python_section() -> str:
    """The first ```python block after the "## From Python" heading."""
    text = README.read_text(encoding="utf-8")
    section = text[text.index("## From Python"):]
    match = re.search(r"```python\n(.*?)```", section, re.DOTALL)
    assert match, "README has no python block under '## From Python'"
    return match.group(1)


def test_readme_python_section_runs_as_written(tmp_path, monkeypatch):
    code = python_section()
    assert "mb.sample(" in code and ".summary" in code  # it shows sampling a posterior and reading its summary
    monkeypatch.chdir(tmp_path)  # whatever it writes stays out of the checkout
    out = io.StringIO()
    namespace: dict = {}
    with contextlib.redirect_stdout(out):
        exec(compile(code, str(README), "exec"), namespace)
    printed = out.getvalue().splitlines()
    assert printed[0] == "-24.11"  # Table 4.5's beta_XB, as the comment beside it says
    post = namespace["post"]
    assert list(post.summary.index[:8]) == list(namespace["mb"].IDENTIFIABLE)
    assert post.diagnostics.max_r_hat <= 1.01 and post.diagnostics.min_ess_bulk >= 400
    lo, hi = post.summary.loc["beta_XB", ["hdi_low", "hdi_high"]]
    assert f"{lo} {hi}" in out.getvalue()
    assert namespace["pred"].shape == (1000, len(namespace["model"].observations))
    assert sorted(p.name for p in tmp_path.iterdir()) == []
