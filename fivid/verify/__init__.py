"""``fivid verify``: the verification and validation manual as a command a lab runs on its own installation.

A catalogue of cases (:mod:`fivid.verify.cases`, one small module each, one registry), each comparing a quantity
fivid computes with a closed form, a published benchmark, a standard or a measurement, with its citation and a
tolerance derived from the method. :func:`run_cases` runs them (on dask, like a study), :func:`render_manual`
writes the HTML manual with the environment it ran on. The tests call the same cases (one home per oracle).
"""

from fivid.verify.case import Case, Curve, Outcome, Plot, Result
from fivid.verify.environment import environment
from fivid.verify.manual import render_manual
from fivid.verify.registry import register_case, registered_cases, select_cases, unregister_case
from fivid.verify.runner import evaluate_case, find_real_data, run_cases

__all__ = ["Case", "Curve", "Outcome", "Plot", "Result", "environment", "render_manual", "register_case",
           "registered_cases", "select_cases", "unregister_case", "evaluate_case", "find_real_data", "run_cases"]
