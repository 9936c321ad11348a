"""Variants of the built-in thesis campaign with measurements removed, as TOML text."""

from mtmcal_bayes.datasets import builtin_text

_PROBE = "# ------------------------------------------------------ touch-trigger probe"
_REPORTED = "# ------------------------------------------- results as printed in the thesis"
_CR2 = "[[ballbar.runs]]\npattern = \"CR\"             # C axis, radial measurement at R'_B"


def thesis_text() -> str:
    return builtin_text("integrex_i200.toml")


def without_second_tool_length() -> str:
    """The thesis campaign without the CR run at R'_B (thesis step 5)."""
    text = thesis_text()
    return text[: text.index(_CR2)] + text[text.index(_PROBE):]


def without_probe() -> str:
    """The thesis campaign without any touch-probe data or published probe results."""
    text = thesis_text()
    return text[: text.index(_PROBE)] + text[text.index(_REPORTED): text.index("[reported.probe]")]


def thesis_reading() -> str:
    """The thesis campaign as the thesis reads it: every run in the thesis' convention, the stylus length known to
    10 µm (the built-in campaign before the touch probe's evidence changed both, docs/thesis-notes.md); no choice of
    reading recorded."""
    lines = [ln for ln in without_reading_choice().splitlines(keepends=True)
             if not ln.startswith('convention = "B0=') and not ln.startswith("dRS = {")]
    return "".join(lines)


def without_reading_choice(text: str | None = None) -> str:
    """The thesis campaign (or ``text``) read as it is, without the record of its choice of reading (no
    ``alternative_convention``, no ``alternative_reason``)."""
    return "".join(ln for ln in (text or thesis_text()).splitlines(keepends=True)
                   if not ln.startswith(("alternative_convention", "alternative_reason")))


def alternative_reading() -> str:
    """The thesis campaign read in its recorded alternative reading: each run's ``alternative_convention`` as its
    ``convention`` (built from the text, not from :meth:`Campaign.alternative_reading`)."""
    out = []
    for ln in thesis_text().splitlines(keepends=True):
        if ln.startswith("alternative_reason"):
            continue
        if ln.startswith("alternative_convention"):
            assert out[-1].startswith("convention = "), out[-1]  # it follows its run's convention
            out[-1] = ln.replace("alternative_convention", "convention", 1)
            continue
        out.append(ln)
    return "".join(out)


def sections_dropped(text: str, *prefixes: str) -> str:
    """A campaign's TOML text without the tables whose names start with one of ``prefixes``."""
    out, skip = [], False
    for line in text.splitlines():
        if line.startswith("["):
            skip = line.strip("[] ").startswith(prefixes)
        if not skip:
            out.append(line)
    return "\n".join(out) + "\n"


def probe_only(text: str) -> str:
    """A campaign's TOML text without its ball bar (``[ballbar]`` and the truth of its set-ups and mounts): a
    probe-only campaign."""
    return sections_dropped(text, "ballbar", "truth.setups", "truth.mounts")


def demo_with_first_run_key(machine: str, line: str) -> str:
    """The demo campaign of built-in type ``machine`` as TOML text, ``line`` (``key = value``) added to its first
    ``[[ballbar.runs]]`` table."""
    from mtmcal_bayes.io.machine_reader import demo_campaign

    text = open(demo_campaign(machine), encoding="utf-8").read()
    marker = "[[ballbar.runs]]\n"
    i = text.index(marker) + len(marker)
    return text[:i] + line + "\n" + text[i:]
