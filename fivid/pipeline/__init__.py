"""The calibration pipeline: recipe + run config → cached stages → summary.json, report.html.

``fivid run pipelines/calibration.yaml --config configs/runs/sample.yaml`` drives it; see
docs/pipeline.md. Layer L4: it calls the library (ingest, identify, solver, score, report) and adds
planning, caching, locking, logging and dask sweeps.
"""

from fivid.pipeline.config import Plan, RunConfig, Threshold, load_plan
from fivid.pipeline.runner import run_pipeline

__all__ = ["Plan", "RunConfig", "Threshold", "load_plan", "run_pipeline"]
