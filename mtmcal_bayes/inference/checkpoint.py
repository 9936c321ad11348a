"""What an HDF5 checkpoint belongs to: the posterior's definition and the chain's settings, checked before resuming.

A checkpoint (emcee's ``HDFBackend``, one group per ensemble) holds steps of one posterior.  Resumed under another
— another campaign, model, data, fixed quantity or σ_model prior — its steps would continue a chain of a different
density and the run would end with a mixture of the two, silently.  So the file carries, as attributes of its root:

* ``mtmcal_posterior``: :meth:`~mtmcal_bayes.inference.log_posterior.LogPosterior.fingerprint`, a sha256 of the
  posterior's definition (its parameters, model, data, fixed quantities, σ_model prior, and its log density at fixed
  points, through which the campaign's observations, geometry and priors enter);
* ``mtmcal_chain``: the settings that shape the chain (seed, ensembles, walkers, the share of independence moves);
* ``mtmcal_described``: the same in words, for the message when they differ.

:func:`claim` writes them into a new file and checks them in an existing one; a mismatch is one line and nothing is
written to the file.  A file without them (written before they existed, or by something else) is refused too: what
it belongs to cannot be told.
"""

from __future__ import annotations

import json
from pathlib import Path

from ..errors import MtmcalError

POSTERIOR, CHAIN, DESCRIBED = "mtmcal_posterior", "mtmcal_chain", "mtmcal_described"


def chain_settings(settings, walkers: int) -> str:
    """The settings that shape the stored chain, as a JSON string (``seed`` as given: None when unseeded)."""
    return json.dumps({"seed": settings.seed, "ensembles": settings.n_ensembles, "walkers": walkers,
                       "independence_weight": settings.independence_weight}, sort_keys=True)


def claim(path: Path, post, settings, walkers: int) -> None:
    """Make ``path`` this run's checkpoint: label a new file, or check that an existing one belongs to this run
    (same posterior, same chain settings); an :class:`~mtmcal_bayes.errors.MtmcalError` naming what differs
    otherwise, before anything is written."""
    import h5py

    fingerprint, chain, described = post.fingerprint(), chain_settings(settings, walkers), post.describe()
    if not path.exists():
        with h5py.File(path, "w") as f:
            f.attrs[POSTERIOR], f.attrs[CHAIN], f.attrs[DESCRIBED] = fingerprint, chain, described
        return
    try:
        with h5py.File(path, "r") as f:
            stored = {k: f.attrs.get(k) for k in (POSTERIOR, CHAIN, DESCRIBED)}
    except OSError:
        raise MtmcalError(f"{path}: not an HDF5 checkpoint (remove it or use another file)") from None
    if stored[POSTERIOR] is None:
        raise MtmcalError(f"{path}: a checkpoint that does not say which posterior it holds (written by an earlier "
                          "version or by something else): remove it or use another file")
    if stored[POSTERIOR] != fingerprint:
        raise MtmcalError(f"{path}: checkpoint of another posterior ({stored[DESCRIBED]}; this run: {described}): "
                          "remove it or use another file")
    if stored[CHAIN] != chain:
        theirs, ours = json.loads(stored[CHAIN]), json.loads(chain)
        differ = ", ".join(f"{k} {theirs.get(k)} there, {ours[k]} here" for k in ours if theirs.get(k) != ours[k])
        if differ:
            raise MtmcalError(f"{path}: checkpoint of the same posterior sampled with other settings ({differ}): "
                              "resume with its settings, or remove it or use another file")
