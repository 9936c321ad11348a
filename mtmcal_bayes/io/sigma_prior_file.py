"""σ_model prior files: a prior of the model-discrepancy scales learnt elsewhere (a fleet), for one campaign.

::

    format = "mtmcal-sigma-model-prior/1"
    source = "fleet plant/: type \\"INTEGREX i-200\\", 3 machines, 14 campaigns"   # free text, required

    [sigma_model]            # the ball bar's discrepancy scale (required)
    distribution = "lognormal"
    median_um = 2.74         # > 0
    log_sd = 0.34            # sd of ln σ, > 0

    [sigma_model_probe]      # optional: the touch probe's scale, same keys
    distribution = "lognormal"
    median_um = 1.2
    log_sd = 0.5

Every problem is one :class:`~mtmcal_bayes.errors.InputError` naming the file and the key (docs/inference.md,
"A σ_model learnt elsewhere").
"""

from __future__ import annotations

import os
from pathlib import Path

from ..parameters import SCALE_LABEL
from ..sigma_prior import DISTRIBUTION, SigmaModelPrior, log_sd_problem, median_problem
from .textfiles import read_user_text, write_text_atomic
from .tomlio import dumps
from .toml_reader import TomlReader, parse_toml

FORMAT = "mtmcal-sigma-model-prior/1"
#: the keys of each scale's table
SCALE_KEYS = ("distribution", "median_um", "log_sd")


def parse_sigma_model_prior(text: str, source: str) -> SigmaModelPrior:
    """The prior in TOML ``text``; ``source`` names the file in errors."""
    r = TomlReader(source)
    doc = parse_toml(text, source, f"a σ_model prior with format = \"{FORMAT}\"")
    fmt = r.string(doc, "format", "", required=True)  # first: another kind of file (a campaign) is named as such
    if fmt != FORMAT:
        r.fail("format", f"{fmt!r} is not a σ_model prior (expected {FORMAT!r})")
    r.check_keys(doc, {"format", "source", *SCALE_LABEL}, "")
    where = r.string(doc, "source", "", required=True)
    if not where.strip():
        r.fail("source", "empty: say where the prior was learnt")
    scales = {}
    for name in SCALE_LABEL:
        table = r.table(doc, name, "", required=name == "sigma_model")
        if table is None:
            continue
        r.check_keys(table, SCALE_KEYS, name)
        dist = r.string(table, "distribution", name, required=True)
        if dist != DISTRIBUTION:
            r.fail(f"{name}.distribution", f"unknown distribution {dist!r} (expected {DISTRIBUTION!r})")
        median = r.number(table, "median_um", name, positive=True)
        if problem := median_problem(median):
            r.fail(f"{name}.median_um", problem)
        log_sd = r.number(table, "log_sd", name, positive=True)
        if problem := log_sd_problem(log_sd):
            r.fail(f"{name}.log_sd", problem)
        scales[name] = (median, log_sd)
    return SigmaModelPrior(scales, where)


def read_sigma_model_prior(path: str | os.PathLike) -> SigmaModelPrior:
    """The σ_model prior of the file at ``path`` (``--sigma-model-prior FILE``)."""
    return parse_sigma_model_prior(read_user_text(Path(path), "σ_model prior file"), str(path))


def sigma_model_prior_text(prior: SigmaModelPrior) -> str:
    """The TOML text of ``prior``."""
    doc = {"format": FORMAT, "source": prior.source}
    for name in SCALE_LABEL:
        if name in prior.scales:
            median, log_sd = prior.scales[name]
            doc[name] = {"distribution": DISTRIBUTION, "median_um": median, "log_sd": log_sd}
    return dumps(doc)


def write_sigma_model_prior(path: str | os.PathLike, prior: SigmaModelPrior) -> None:
    """Write ``prior`` to ``path`` atomically (nothing half-written); :func:`read_sigma_model_prior` reads it back."""
    write_text_atomic(path, sigma_model_prior_text(prior))
