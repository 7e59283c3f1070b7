"""Parametric studies (DESIGN §11): a sweep over conditions whose points are small analyses, run on dask.

``load_study(path)`` reads a study config (docs/studies.md), ``run_study(study, outdir)`` runs it incrementally
(a finished point is not recomputed; a killed study resumes), ``open_study(path)`` opens its ``study.nc`` with
the swept conditions indexed. The CLI is ``fivid study STUDY.yaml -o DIR``. What a study computes is its *kind*
(:mod:`fivid.study.kind`: one protocol, one registry; the shipped kinds in :mod:`fivid.study.kinds`).
"""

from fivid.study.config import AXES, Study, load_study
from fivid.study.kind import StudyKind, register_study_kind, registered_kinds, study_kind
from fivid.study.lumped import HoffmannSystem
from fivid.study.runner import open_study, run_study

__all__ = ["AXES", "Study", "load_study", "run_study", "open_study", "HoffmannSystem", "StudyKind",
           "register_study_kind", "registered_kinds", "study_kind"]
