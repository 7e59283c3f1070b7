"""The stage runner: plan → cached tasks → outputs, ``summary.json`` and an exit status.

:func:`run_pipeline` takes a validated :class:`~fivid.pipeline.config.Plan`, locks the output folder,
logs to ``<output>/fivid-run.log``, runs each stage's tasks that are not already in the cache (see
:mod:`fivid.pipeline.cache`), evaluates the scores against the configured thresholds and writes
``<output>/summary.json``. The exit status is for schedulers: 0 pass, 3 scores below thresholds,
2 bad input or configuration, 1 unexpected failure, 130/143 interrupted by SIGINT/SIGTERM (the
summary says ``interrupted`` with the signal and the stage; finished tasks stay in the cache). Once
``summary.json`` is written the outcome is settled (:meth:`~fivid.errors.Interrupted.settle`): a signal after
it (while the CLI prints, during the dask shutdown at exit) no longer changes the exit status.

Before the lock is taken the output folder is checked (:mod:`fivid.pipeline.output`): a folder of
unrelated files is refused unless ``force``; every task's outputs must lie inside the folder.
"""

from __future__ import annotations

import datetime as _dt
import logging
import platform
import signal
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from fivid import __version__
from fivid.errors import FividError, Interrupted, exit_status
from fivid.execution.cluster import check_scheduler_address
from fivid.execution.lock import OutputLock
from fivid.pipeline.cache import Task, TaskCache
from fivid.pipeline.config import STAGE_REQUIRES, Plan
from fivid.pipeline.output import (check_inside, check_output_folder, remove_stale_temporaries,
                                   write_output_manifest)
from fivid.pipeline.stages import STAGES, evaluate_thresholds
from fivid.storage import check_folder_writable, write_json

__all__ = ["Context", "StageStats", "run_pipeline", "EXIT_PASS", "EXIT_FAILURE", "EXIT_BAD_INPUT",
           "EXIT_BELOW_THRESHOLD"]

EXIT_PASS, EXIT_FAILURE, EXIT_BAD_INPUT, EXIT_BELOW_THRESHOLD = 0, 1, 2, 3

log = logging.getLogger("fivid")


@dataclass
class StageStats:
    """What one stage did: task counts, cache hits and wall time [s]."""

    name: str
    tasks: int = 0
    cached: int = 0
    ran: int = 0
    seconds: float = 0.0
    note: str = ""

    def as_dict(self) -> dict:
        """A JSON-ready dict of the stage's counts and wall time [s] (rounded to ms)."""
        return {"name": self.name, "tasks": self.tasks, "cached": self.cached, "ran": self.ran,
                "seconds": round(self.seconds, 3), "note": self.note}


@dataclass
class Context:
    """State shared by the stages of one run.

    ``digests[stage][task] = {label: sha256}`` of finished tasks' outputs; ``tasks[stage][task]`` the
    Task objects; ``data`` holds what stages hand each other (runs, conditions, scores).
    """

    plan: Plan
    out: Path
    cache: TaskCache
    workers: int = 2
    scheduler: str | None = None
    force: bool = False
    dry_run: bool = False
    progress: bool | None = None
    digests: dict = field(default_factory=dict)
    tasks: dict = field(default_factory=dict)
    data: dict = field(default_factory=dict)
    pending: set = field(default_factory=set)  # dry run: stages with work to do (their outputs' keys are unknown)
    notify: object = None  # callable(line): a line per stage and per finished task when no progress bar shows
    done: dict = field(default_factory=dict)  # stage -> tasks finished in this run
    todo: dict = field(default_factory=dict)  # stage -> tasks to run in this run

    @property
    def config(self):
        """The run configuration of the plan."""
        return self.plan.config

    def finish(self, task: Task, seconds: float) -> None:
        """Record a task whose outputs are written (manifest last, atomically); then honour a pending signal."""
        self.digests.setdefault(task.stage, {})[task.name] = self.cache.record(task, seconds=seconds)
        log.info("%s/%s done in %.2f s", task.stage, task.name, seconds)
        self.done[task.stage] = self.done.get(task.stage, 0) + 1
        if self.notify is not None:
            self.notify(f"  {task.stage}/{task.name} done in {seconds:.1f} s ({self.done[task.stage]} of "
                        f"{self.todo.get(task.stage, '?')})")
        Interrupted.raise_if_received()

    def output(self, stage: str, task: str, label: str) -> Path:
        """Path of the output ``label`` of task ``task`` of stage ``stage``."""
        return Path(self.tasks[stage][task].outputs[label])


def _upstream(name: str) -> set:
    """Every stage ``name`` needs, directly or through others."""
    out: set = set()
    todo = list(STAGE_REQUIRES[name])
    while todo:
        s = todo.pop()
        if s not in out:
            out.add(s)
            todo.extend(STAGE_REQUIRES[s])
    return out


def _run_stage(ctx: Context, name: str, stats: StageStats) -> list[str]:
    """Plan, look up and run one stage; returns dry-run lines."""
    stage = STAGES[name]
    t0 = time.perf_counter()
    # the report shows every earlier stage's outputs (modal too, which it does not require)
    waits = sorted(ctx.pending if name == "report" else _upstream(name) & ctx.pending)
    if waits:
        stats.note = "waits for upstream stages"
        ctx.pending.add(name)
        return [f"  {name:9s} runs after {', '.join(waits)} (its inputs are not computed yet)"]
    tasks = stage.plan(ctx)
    for task in tasks:  # names come from input files and conditions: none may lead out of the folder
        for path in task.outputs.values():
            check_inside(ctx.out, path, what=f"output of task {name}/{task.name}")
    ctx.tasks[name] = {t.name: t for t in tasks}
    todo = []
    for task in tasks:
        if ctx.force and not ctx.dry_run:
            ctx.cache.forget(task)
            hit = None
        else:
            hit = None if ctx.force else ctx.cache.lookup(task)
        if hit is None:
            todo.append(task)
        else:
            ctx.digests.setdefault(name, {})[task.name] = hit
    stats.tasks, stats.cached, stats.ran = len(tasks), len(tasks) - len(todo), len(todo)
    if ctx.dry_run:
        lines = [f"  {name:9s} {len(tasks)} task(s): {len(tasks) - len(todo)} cached, {len(todo)} to run"]
        lines += [f"      would run {t.name}" for t in todo]
        if todo:
            ctx.pending.add(name)
        else:
            stage.collect(ctx, tasks)
        return lines
    if ctx.notify is not None:
        ctx.notify(f"{name}: {len(tasks)} task(s), " + (f"{len(tasks) - len(todo)} cached, running {len(todo)}"
                                                        if todo else "all cached"))
    if todo:
        log.info("stage %s: %d task(s), %d cached, running %d", name, len(tasks), len(tasks) - len(todo), len(todo))
        ctx.todo[name] = len(todo)
        stage.execute(ctx, todo)
    else:
        log.info("stage %s: %d task(s), all cached", name, len(tasks))
    stage.collect(ctx, tasks)
    stats.seconds = time.perf_counter() - t0
    return []


def _evaluate(ctx: Context) -> tuple[list[dict], bool]:
    """Check every condition's scores against the thresholds; returns (checks, all passed)."""
    checks = evaluate_thresholds(ctx.data.get("scores", {}), ctx.config.thresholds)
    return checks, all(c["pass"] for c in checks)


def _file_handler(out: Path) -> logging.Handler:
    handler = logging.FileHandler(out / "fivid-run.log", encoding="utf-8")
    handler.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(message)s"))
    handler.setLevel(logging.INFO)
    return handler


def run_pipeline(plan: Plan, *, workers: int = 2, scheduler: str | None = None, dry_run: bool = False,
                 force: bool = False, progress: bool | None = None, echo=None, notify=None) -> tuple[int, dict]:
    """Run a validated plan; returns ``(exit status, summary)``.

    Parameters
    ----------
    plan : Plan
        From :func:`fivid.pipeline.config.load_plan`.
    workers : int
        Worker processes of the local dask cluster (ignored with ``scheduler``).
    scheduler : str, optional
        Address ``tcp://host:port`` of an existing dask scheduler.
    dry_run : bool
        Only report what would run (nothing is written, no lock is taken).
    force : bool
        Re-run every task, ignoring the cache; also write into an existing folder that is not a fivid
        output (refused otherwise).
    progress : bool, optional
        Progress bars (default: when stderr is a terminal).
    echo : callable, optional
        Receives the dry-run plan lines.
    notify : callable, optional
        Receives a line per stage and per finished task when no progress bar shows (``progress`` False, or
        None and stderr not a terminal), so that a run without a terminal is not silent for minutes.

    Returns
    -------
    status : int
        0 pass, 3 scores below thresholds, 2 bad input, 1 failure. An interruption (Ctrl-C, SIGTERM
        through the CLI) is re-raised as :class:`~fivid.errors.Interrupted` after the summary is written.
    summary : dict
        The content of ``summary.json`` (empty for a dry run).
    """
    if scheduler is not None:  # before any work: a bad address used to fail after three stages
        check_scheduler_address(scheduler)
    out = plan.config.output
    check_output_folder(out, force=force)
    bars = progress if progress is not None else sys.stderr.isatty()
    ctx = Context(plan=plan, out=out, cache=TaskCache(out), workers=workers, scheduler=scheduler, force=force,
                  dry_run=dry_run, progress=progress, notify=None if bars or dry_run else notify)
    stats = [StageStats(name) for name in plan.stages]
    if dry_run:
        lines = [f"pipeline {plan.name!r} ({plan.path}) with {plan.config.path}", f"output folder: {out}",
                 f"inputs: {len(plan.config.input_files)} file(s) in {plan.config.input_folder}"]
        for name, st in zip(plan.stages, stats):
            lines += _run_stage(ctx, name, st)
        for line in lines:
            (echo or log.warning)(line)
        return EXIT_PASS, {}

    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise FividError(f"cannot create the output folder {str(out)!r}: {exc.strerror or exc}") from None
    check_folder_writable(out)
    lock = OutputLock(out)
    lock.acquire()
    flog = logging.getLogger("fivid")
    handler = _file_handler(out)
    old_level = flog.level
    stream_levels = [(h, h.level) for h in flog.handlers]
    for h, lvl in stream_levels:
        if lvl == logging.NOTSET:
            h.setLevel(old_level or logging.WARNING)
    flog.addHandler(handler)
    flog.setLevel(min(old_level or logging.WARNING, logging.INFO))
    started = _dt.datetime.now(_dt.timezone.utc)
    t0 = time.perf_counter()
    status, error, interrupted, current = EXIT_FAILURE, None, None, None
    if lock.took_over:
        log.warning("previous run (pid %s, started %s) did not finish; its completed tasks are reused",
                    lock.took_over.get("pid"), lock.took_over.get("started"))
    log.info("fivid %s: pipeline %s, config %s, output %s", __version__, plan.path, plan.config.path, out)
    try:
        remove_stale_temporaries(out)  # under the lock: no other run is writing them
        write_output_manifest(out, f"fivid run {plan.path} --config {plan.config.path} --output {out}")
        for name, st in zip(plan.stages, stats):
            current = name
            Interrupted.raise_if_received()
            _run_stage(ctx, name, st)
        current = None
        status = EXIT_PASS if _evaluate(ctx)[1] else EXIT_BELOW_THRESHOLD
    except FividError as exc:
        status, error = EXIT_BAD_INPUT, exc
        log.info("stopped on bad input: %s", exc)  # the CLI prints it on stderr; this goes to the log file
        raise
    except KeyboardInterrupt as exc:  # Ctrl-C, or SIGTERM raised as Interrupted by the CLI
        signum = getattr(exc, "signum", signal.SIGINT)
        interrupted = {"signal": signal.Signals(signum).name, "stage": current}
        status, error = 128 + int(signum), exc
        # to the log file only: the CLI prints the Interrupted message (once) on stderr
        log.info("interrupted by %s during stage %s; finished tasks are kept", interrupted["signal"], current)
        raise Interrupted(signum, f"during stage {current!r}; finished tasks are kept: run the same command "
                          "again to resume") from None
    except BaseException as exc:
        status, error = exit_status(exc), exc  # as the CLI will exit (a MemoryError is 2): summary.json agrees
        if status == EXIT_BAD_INPUT:
            log.info("stopped: %s: %s", type(exc).__name__, exc)
        else:
            log.exception("pipeline failed")
        raise
    finally:
        held = _ignore_signals()  # a second Ctrl-C must not lose the summary or leave the lock
        checks, ok = _evaluate(ctx) if status in (EXIT_PASS, EXIT_BELOW_THRESHOLD) else ([], False)
        summary = _summary(ctx, stats, checks, status, error, started, time.perf_counter() - t0, lock)
        summary["interrupted"] = interrupted
        try:
            write_json(out / "summary.json", summary)
            Interrupted.settle()  # outputs and summary complete: a later signal keeps this status (fivid.cli.main)
            log.info("summary: %s (exit %d), %.1f s", summary["status"], status, summary["seconds"])
        finally:
            flog.removeHandler(handler)
            handler.close()
            flog.setLevel(old_level)
            for h, lvl in stream_levels:
                h.setLevel(lvl)
            lock.release()
            for signum, previous in held.items():
                signal.signal(signum, previous)
    return status, summary


def _ignore_signals() -> dict:
    """Ignore SIGINT and SIGTERM (main thread only); returns the previous handlers to restore."""
    import threading

    if threading.current_thread() is not threading.main_thread():
        return {}
    return {signum: signal.signal(signum, signal.SIG_IGN) for signum in (signal.SIGINT, signal.SIGTERM)}


def _summary(ctx, stats, checks, status, error, started, seconds, lock) -> dict:
    plan = ctx.plan
    names = {EXIT_PASS: "pass", EXIT_BELOW_THRESHOLD: "below_threshold", EXIT_BAD_INPUT: "bad_input",
             EXIT_FAILURE: "failure", 128 + signal.SIGINT: "interrupted", 128 + signal.SIGTERM: "interrupted"}
    return {
        "status": names[status],
        "exit_code": status,
        "error": None if error is None else f"{type(error).__name__}: {error}",
        "pipeline": {"name": plan.name, "path": str(plan.path), "sha256": plan.recipe_sha256, "stages": list(plan.stages)},
        "config": {"path": str(plan.config.path), "sha256": plan.config.sha256},
        "output": str(ctx.out),
        "started": started.strftime("%Y-%m-%dT%H:%M:%SZ"),
        "seconds": round(seconds, 3),
        "fivid_version": __version__,
        "python": platform.python_version(),
        "host": platform.node(),
        "took_over_stale_lock": lock.took_over,
        "stages": [s.as_dict() for s in stats],
        "cache": {"tasks": sum(s.tasks for s in stats), "cached": sum(s.cached for s in stats),
                  "ran": sum(s.ran for s in stats)},
        "inputs": ctx.data.get("input_sha256", {}),
        "law": ctx.data.get("law_summary"),
        "discretisation": ctx.data.get("discretisation"),
        "scores": ctx.data.get("scores", {}),
        "thresholds": [t.describe() for t in plan.config.thresholds],
        "checks": checks,
        "verdict": "pass" if status == EXIT_PASS else names[status],
    }
