"""The work of a fleet, in units that run anywhere: one campaign's posterior, one machine's history.

A unit is a plain function of picklable arguments (the :class:`~mtmcal_bayes.campaign.Campaign` objects travel
with it, so a worker on another computer needs no access to the files) returning a JSON-able dict: what is
cached and what the fleet's JSON shows.  Each unit is seeded from the fingerprints of its campaigns and the
user's seed, and named by a key over the same and the settings (:func:`unit_key`): the result of a unit never
depends on which worker ran it, when, or next to what.

A unit never raises: a failure comes back as ``{"error": "<one line>"}``, reported beside the others' results.
"""

from __future__ import annotations

import base64
import hashlib
import json
import tempfile
import time
from dataclasses import dataclass, field, fields
from pathlib import Path

from ..errors import MtmcalError, ParameterError
from ..io.json_text import rounded
from ..version import __version__
from .tolerances import display_limits, machine_tolerances, tolerance_dict, tolerance_tuple
from .sigma_model import history_log_likelihood

#: the cache entry's format; a change of what a unit returns must change it (or the package version)
UNIT_FORMAT = "mtmcal-fleet-unit/2"


@dataclass(frozen=True)
class FleetSettings:
    """How every campaign of the fleet is sampled and every history fitted (all enter the cache key).

    ``tolerances``: a plant-wide set used instead of each campaign's own ``[tolerances]`` (its conformity, its
    machine's forecast and change thresholds); given as ``{name: Tolerance}``, kept as ``((name, low, high), ...)``
    (:func:`~.tolerances.tolerance_tuple`), names as written (each machine resolves them, :meth:`tolerances_for`);
    None: each campaign's own.  ``tolerances_file``: the file they were read from, named by an error (not a result's
    setting: it enters neither the JSON nor the cache key).
    """

    model: str = "linear"
    seed: int = 1
    sampler: str = "emcee"
    target_ess: float = 1000.0
    max_steps: int = 20_000
    tolerances: tuple | None = None
    tolerances_file: str = field(default="", compare=False)

    def __post_init__(self):  # bad settings fail here, before any work, not in every unit
        if isinstance(self.tolerances, dict) and not self.tolerances_file:
            object.__setattr__(self, "tolerances_file", next((t.source for t in self.tolerances.values()
                                                              if getattr(t, "source", "")), ""))
        if self.tolerances is not None:
            object.__setattr__(self, "tolerances", tolerance_tuple(self.tolerances))
        from ..inference.sampling import SamplerSettings
        from ..models import check_model

        check_model(self.model)
        if not isinstance(self.seed, int) or isinstance(self.seed, bool):
            raise ParameterError("seed", f"{self.seed!r} is not an integer")
        SamplerSettings(sampler=self.sampler, target_ess=self.target_ess, max_steps=self.max_steps)
        if self.sampler == "exact" and self.model != "linear":
            raise ParameterError("sampler", f"exact: the exact posterior is known for the linear model only, "
                                 f"not for {self.model} (use the emcee sampler)")

    def tolerance_set(self) -> dict | None:
        """The plant-wide tolerances as ``{name: Tolerance}``, names as written, or None."""
        return None if self.tolerances is None else tolerance_dict(self.tolerances, self.tolerances_file)

    def tolerances_for(self, machine) -> tuple[dict | None, list[str]]:
        """The plant-wide tolerances by ``machine``'s quantity names and the names it does not have
        (:func:`~.tolerances.machine_tolerances`); ``(None, [])`` without plant-wide tolerances."""
        return machine_tolerances(self.tolerances, machine, self.tolerances_file)

    def to_json(self) -> dict:
        """The settings; ``tolerances`` as ``{name: {"low", "high"}}`` in ″ / µm (null: each campaign's own)."""
        out = {f.name: getattr(self, f.name) for f in fields(self) if f.name not in ("tolerances", "tolerances_file")}
        return {**out, "tolerances": None if self.tolerances is None else display_limits(self.tolerance_set())}


def unit_key(kind: str, digests: list[str], settings: FleetSettings) -> str:
    """The name of a unit's work: sha256 over its kind, its campaigns' fingerprints, the settings it depends on
    (a history: the seed only), the plant-wide tolerances when given (a campaign's verdicts, a history's forecast
    and thresholds: a result with other tolerances is never reused) and the package version (a new version
    computes afresh)."""
    used = settings.to_json() if kind == "campaign" else {"seed": settings.seed, "model": settings.model}
    used.pop("tolerances", None)  # without plant-wide tolerances, the key they had before these existed
    if settings.tolerances is not None:  # a campaign's conformity, a history's forecast and thresholds
        used["tolerances"] = [list(t) for t in sorted(settings.tolerances)]  # one key whatever the order given
    text = json.dumps({"format": UNIT_FORMAT, "kind": kind, "digests": digests, "settings": used,
                       "version": __version__}, sort_keys=True)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def unit_seed(digests: list[str], seed: int) -> int:
    """A 32-bit seed from the campaigns' fingerprints and the user's seed: the same content, the same draws."""
    h = hashlib.sha256(f"{seed}:{':'.join(digests)}".encode())
    return int.from_bytes(h.digest()[:4], "big")


def _plain(obj):
    """``obj`` as strict JSON data: floats exact (17 digits), NaN as None, numpy and dates as plain values."""
    return rounded(json.loads(json.dumps(obj, default=_default)), 17)


def _default(v):
    if hasattr(v, "item"):  # numpy scalars
        return v.item()
    if hasattr(v, "tolist"):
        return v.tolist()
    return str(v)  # dates, paths


def _one_line(exc: BaseException, step: str) -> str:
    """The line a failed unit reports: the package's own error as it is, anything else as an internal error of
    ``step`` (what the worker was doing)."""
    if isinstance(exc, MtmcalError):
        return str(exc)
    return f"internal error in {step}: {type(exc).__name__}: {exc}".splitlines()[0]


def model_for(campaign, model: str) -> str:
    """The model a fleet's ``model`` means for ``campaign``: as given where its machine offers it, else the machine's
    own kinematic model (a described machine's chain where the thesis machine's ``htm-thesis`` is asked for;
    docs/fleet.md, "Mixed fleets")."""
    from ..models import default_kinematic_model, models_of

    return model if model in models_of(campaign.machine) else default_kinematic_model(campaign.machine)


def campaign_unit(campaign, settings: FleetSettings, seed: int) -> dict:
    """The posterior of one campaign, as ``sample --json`` summarises each quantity (with the conformity
    verdicts of the campaign's own ``[tolerances]``), with its warnings and the sampler's verdicts."""
    t0 = time.perf_counter()
    try:
        from ..inference.sampling import SamplerSettings
        from ..models import default_data
        from ..posterior import sample_posterior
        from ..posterior.output import quantity_json
        from ..reporting.decisions import add_suggestions

        s = SamplerSettings(seed=seed, max_steps=settings.max_steps, target_ess=settings.target_ess,
                            sampler=settings.sampler)
        post = sample_posterior(campaign, model=model_for(campaign, settings.model), settings=s,
                                data=default_data(campaign),
                                tolerances=settings.tolerances_for(campaign.machine)[0])
        add_suggestions(post, campaign)
        d = post.diagnostics
        out = {"seed": seed,
               "summary": {n: quantity_json(n, row, post.conformity) for n, row in post.summary.iterrows()},
               "diagnostics": {"converged": d.converged, "min_ess_bulk": d.min_ess_bulk, "min_ess_tail": d.min_ess_tail,
                               "max_r_hat": d.max_r_hat, "kept_draws": d.kept_draws, "sampler": d.sampler},
               "warnings": list(post.warnings)}
        return {"result": _plain(out), "files": {}, "elapsed_s": time.perf_counter() - t0}
    except Exception as exc:  # a unit reports, it does not raise (module docstring)
        return {"error": _one_line(exc, f"the posterior of {campaign.source}"), "elapsed_s": time.perf_counter() - t0}


#: keys of the history's JSON that are not results of its campaigns' content: where it was read and written
_HISTORY_PLACES = ("files", "output")


def _machine_history(campaigns: list, seed: int, model: str, tolerances: dict | None = None):
    """The history model of one machine (``mtmcal_bayes.histories``), imported when first needed; the
    tolerances of the forecast are ``tolerances`` (plant-wide), else the latest campaign's own."""
    from ..histories import fit_history

    return fit_history(campaigns, model=model_for(campaigns[-1], model), seed=seed, tolerances=tolerances)


def history_unit(campaigns: list, seed: int, with_page: bool, model: str = "linear", *,
                 tolerances: dict | None = None) -> dict:
    """The history of one machine from its dated campaigns: the history's JSON (without the places it names)
    and, ``with_page``, its page's files (``{path: base64}``, written by the history itself into a temporary
    folder of the worker).  ``tolerances``: the plant-wide set, else the latest campaign's own."""
    t0 = time.perf_counter()
    try:
        result = _machine_history(campaigns, seed, model, tolerances)
        doc = {k: v for k, v in result.to_json().items() if k not in _HISTORY_PLACES}
        files = {}
        if with_page:
            with tempfile.TemporaryDirectory(prefix="mtmcal-history-") as tmp:
                result.write(tmp)
                files = {p.relative_to(tmp).as_posix(): base64.b64encode(p.read_bytes()).decode("ascii")
                         for p in sorted(Path(tmp).rglob("*")) if p.is_file()}
        # only a machine with a type has its σ_model pooled, and only from a history whose data have the ball bar's
        typed = bool(campaigns[-1].machine.type) and result.fit.model.scales[0] == "sigma_model"
        loglik = history_log_likelihood(result.fit.model) if typed else None
        return {"result": _plain({"seed": seed, **doc, "sigma_model_loglik": loglik}), "files": files,
                "elapsed_s": time.perf_counter() - t0}
    except Exception as exc:  # a unit reports, it does not raise (module docstring)
        return {"error": _one_line(exc, "the history"), "elapsed_s": time.perf_counter() - t0}
