"""Validation of the inference: simulation-based calibration (``mtmcal-bayes validate sbc``)."""

from .sbc import SBCResult, SBCSettings, run_sbc

__all__ = ["SBCResult", "SBCSettings", "run_sbc"]
