"""ArviZ, imported in one place.

Some ArviZ releases announce their coming 1.0 API with a ``FutureWarning`` on
import; it says nothing about this package's use, so it is silenced here and
every module takes ``az`` from this one.
"""

import warnings

with warnings.catch_warnings():
    warnings.simplefilter("ignore", FutureWarning)
    import arviz as az

__all__ = ["az"]
