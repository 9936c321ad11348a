"""Files in and out: campaign TOML, truth files, ball-bar traces, NC programs, DPRNT probe output, posteriors,
σ_model priors learnt elsewhere.

Every reader turns a problem into one :class:`~mtmcal_bayes.errors.InputError`
line naming the file and the key or line; every writer goes through a
temporary file, so nothing is left half-written.  Values are converted to the
internal units (mm, rad) here and nowhere later.
"""

from .campaign_reader import load_campaign, load_truth, parse_campaign
from .campaign_writer import campaign_to_dict, save_campaign
from .dprnt import DprntPoints, parse_dprnt, read_dprnt
from .gcode import Program, parse_program, read_program, rewrite
from .sigma_prior_file import read_sigma_model_prior, write_sigma_model_prior

__all__ = ["load_campaign", "load_truth", "parse_campaign", "campaign_to_dict", "save_campaign",
           "DprntPoints", "parse_dprnt", "read_dprnt", "Program", "parse_program", "read_program", "rewrite",
           "read_sigma_model_prior", "write_sigma_model_prior"]
