"""Fleets: every machine's calibrations in a folder tree, computed in parallel on Dask, in one overview.

* :func:`run_fleet` — discover the campaigns below a folder (:mod:`.discover`), take what the cache holds
  (:mod:`.cache`), run the rest as independent units on a Dask cluster (:mod:`.units`, :mod:`.run`): each
  campaign's posterior, each machine's history (``mtmcal_bayes.histories``);
* :class:`FleetResult` — machines × quantities with conformity, drift and recalibrate-by dates, the errors;
  ``to_json()``, ``to_text()``, ``write(output)`` (:mod:`.overview`: ``index.html``, ``fleet_summary.csv``).

The package is called ``fleets`` so that ``mtmcal_bayes.fleet`` stays the API function (importing a subpackage
sets the attribute of its parent package of the same name).
"""

from .result import PARTIAL, FleetResult
from .run import run_fleet
from .units import FleetSettings

__all__ = ["run_fleet", "FleetResult", "FleetSettings", "PARTIAL"]
