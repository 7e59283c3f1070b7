"""Run verification cases: each case one task on dask (like a study's points), or in this process.

A case that raises is a failed case (its exception is the reason); a case whose measured data are absent is
skipped with the reason. The results come back in catalogue order.
"""

from __future__ import annotations

import importlib.util
import logging
import math
import os
import time
from pathlib import Path

from fivid.execution.cluster import call, check_scheduler_address, map_tasks
from fivid.verify.case import Case, Result

__all__ = ["run_cases", "evaluate_case", "find_real_data", "default_real_data_folders"]

log = logging.getLogger("fivid")

_PACKAGE_DATA = Path(__file__).resolve().parent / "data"


def default_real_data_folders() -> list[Path]:
    """Where measured data are looked for by default: the data shipped in the package (``fivid/verify/data``,
    licensed files small enough to ship), then ``../shared/real_data`` beside a development checkout."""
    checkout = Path(__file__).resolve().parents[2]
    return [_PACKAGE_DATA, checkout.parent / "shared" / "real_data"]


def find_real_data(relative: str, folder: str | os.PathLike | None = None) -> Path | None:
    """The file or folder ``relative`` under ``folder`` (when given) or the default folders; None if absent."""
    folders = [Path(folder)] if folder is not None else default_real_data_folders()
    for f in folders:
        path = f / relative
        if path.exists():
            return path
    return None


def evaluate_case(case: Case, quick: bool, data: Path | None) -> Result:
    """Compute one case (on a worker or here) and judge it against its tolerance."""
    t0 = time.perf_counter()
    if case.real_data is not None and data is None:
        return Result(case, "skipped", None, math.nan, 0.0, quick=quick,
                      reason=f"needs the measured data {case.real_data!r}, not found (fivid verify --real-data DIR: "
                             "the folder that holds it, e.g. ../shared/real_data of a checkout)")
    try:
        outcome = case.compute(quick, data)
    except Exception as exc:  # noqa: BLE001 - a case that cannot run is a failed verification, reported as such
        return Result(case, "failed", None, math.nan, time.perf_counter() - t0, quick=quick,
                      reason=f"the computation raised {type(exc).__name__}: {exc}")
    error = case.measure_error(float(outcome.value), float(outcome.reference))
    passed = math.isfinite(error) and error <= float(outcome.tolerance)
    return Result(case, "passed" if passed else "failed", outcome, error, time.perf_counter() - t0, quick=quick,
                  reason="" if passed else ("outside its tolerance" if math.isfinite(error) else
                                            "the error is not a finite number"))


def run_cases(cases: list[Case], *, quick: bool = False, workers: int = 2, scheduler: str | None = None,
              real_data: str | os.PathLike | None = None, progress=None) -> list[Result]:
    """Run ``cases``; returns their results in the order given.

    Parameters
    ----------
    cases : list of Case
        From :func:`fivid.verify.select_cases`.
    quick : bool
        Every case at its reduced resolution (the ``--quick`` manual).
    workers : int
        Worker processes of the dask LocalCluster; 0 runs the cases in this process (as does a missing
        dask.distributed, with a warning: a plain install can verify itself).
    scheduler : str, optional
        ``tcp://host:port`` of a running dask scheduler (then ``workers`` is ignored).
    real_data : path-like, optional
        Folder of the measured data (default: :func:`default_real_data_folders`).
    progress : bool, optional
        Progress bar (default: when the terminal is interactive).
    """
    from tqdm.auto import tqdm

    if scheduler is not None:
        check_scheduler_address(scheduler)
    items = {c.name: (evaluate_case, c, quick, None if c.real_data is None else find_real_data(c.real_data, real_data))
             for c in cases}
    results: dict[str, Result] = {}
    if workers and scheduler is None and importlib.util.find_spec("distributed") is None:
        log.warning("verify: dask.distributed is not installed (pip install 'fivid[sweep]'): the cases run one after "
                    "the other in this process")
        workers = 0
    stream = map_tasks(call, items, workers=workers, scheduler=scheduler)
    with tqdm(total=len(items), desc="verify", unit="case", leave=False,
              disable=None if progress is None else not progress) as bar:
        for name, result, _seconds, pid in stream:
            log.info("verify: %s %s (%.1f s, pid %d)", name, result.status, result.seconds, pid)
            results[name] = result
            bar.update(1)
    return [results[c.name] for c in cases]
