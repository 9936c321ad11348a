"""The report's HTML page: :class:`~mtmcal_bayes.html_page.Page` (shared with the machine-history pages)."""

from ..html_page import Page

__all__ = ["Page"]
