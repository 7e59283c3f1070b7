"""Tasks on dask.distributed: the client (an embedded LocalCluster or an existing scheduler), the scheduler-address
check and :func:`map_tasks`, which yields results as they finish. Shared infrastructure of the pipeline, the
studies and the verification manual (below all three).

By default an embedded :class:`distributed.LocalCluster` (worker *processes*, one thread each, on the loopback
interface, ``n_workers`` from ``--workers``) is started and closed after the tasks; with ``--scheduler
tcp://host:port`` the tasks go to an existing cluster (``dask scheduler`` and ``dask worker tcp://host:port``
started by hand, see docs/pipeline.md). dask is imported here only, when tasks run.
"""

from __future__ import annotations

import contextlib
import logging
import os
import time

from fivid.errors import ConfigError, FividError, Interrupted

__all__ = ["dask_client", "check_scheduler_address", "map_tasks", "call", "SCHEDULER_SCHEMES"]

#: address schemes of dask.distributed's comm backends that reach a scheduler over the network
SCHEDULER_SCHEMES = ("tcp", "tls", "ws", "wss", "ucx")

log = logging.getLogger("fivid")


def check_scheduler_address(address: str, *, timeout: float = 3.0) -> str:
    """Check a dask scheduler address before any work: its form, then that something listens there.

    Parameters
    ----------
    address : str
        ``tcp://HOST:PORT`` (or ``tls``, ``ws``, ``wss``, ``ucx``), as ``dask scheduler`` prints it.
    timeout : float
        Seconds to wait for a TCP connection [s]: a scheduler on a reachable host answers within
        milliseconds, and 3 s covers a slow network without making a typo cost long.

    Returns
    -------
    str
        ``address`` unchanged.

    Raises
    ------
    ConfigError
        The address is malformed (naming what is wrong and the expected form) or nothing accepts a
        connection there (naming the host, port and the reason).
    """
    import socket
    from urllib.parse import urlsplit

    form = "tcp://HOST:PORT, e.g. tcp://10.0.0.5:8786 as 'dask scheduler' prints it"
    text = str(address).strip()
    parts = urlsplit(text) if "://" in text else None
    if parts is None:
        raise ConfigError(f"{text!r} is not a dask scheduler address; expected {form} (leave --scheduler out "
                          "for a local cluster)", key="--scheduler")
    if parts.scheme not in SCHEDULER_SCHEMES:
        raise ConfigError(f"{text!r}: scheme {parts.scheme!r} is not a dask scheme ({', '.join(SCHEDULER_SCHEMES)}); "
                          f"expected {form}", key="--scheduler")
    try:
        port = parts.port
    except ValueError:
        port = None
    if not parts.hostname or port is None or parts.path not in ("", "/"):
        raise ConfigError(f"{text!r} needs a host and a port number; expected {form}", key="--scheduler")
    if parts.scheme == "ucx":  # not a TCP socket: left to distributed
        return address
    try:
        socket.create_connection((parts.hostname, port), timeout=timeout).close()
    except OSError as exc:
        reason = "timed out" if isinstance(exc, TimeoutError) else (exc.strerror or str(exc))
        raise ConfigError(f"no dask scheduler answers at {text} ({parts.hostname} port {port}: {reason} within "
                          f"{timeout:g} s); start one with 'dask scheduler' and workers with 'dask worker {text}', "
                          "or leave --scheduler out for a local cluster", key="--scheduler") from None
    return address


@contextlib.contextmanager
def dask_client(*, workers: int = 2, scheduler: str | None = None, connect_timeout: float = 10.0):
    """A :class:`distributed.Client`: connected to ``scheduler``, or to a new loopback LocalCluster.

    Parameters
    ----------
    workers : int
        Worker processes of the LocalCluster (one thread each).
    scheduler : str, optional
        ``tcp://host:port`` of a running ``dask scheduler``.
    connect_timeout : float
        How long to try reaching ``scheduler`` [s].
    """
    from distributed import Client, LocalCluster

    if scheduler is not None:
        try:
            client = Client(scheduler, timeout=f"{connect_timeout}s")
        except (OSError, TimeoutError) as exc:
            raise FividError(f"cannot reach the dask scheduler at {scheduler!r} ({exc}); start one with "
                             "'dask scheduler' and workers with 'dask worker <address>'") from None
        log.info("dask: connected to %s (%d workers)", scheduler, len(client.scheduler_info().get("workers", {})))
        try:
            yield client
        finally:
            client.close()
        return
    _quiet_resource_tracker()
    # Each worker is a single-threaded process: numba/numpy threads inside are limited to 1 so that
    # n workers use n cores (the solver's kernels are serial).
    env = {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "NUMBA_NUM_THREADS": "1"}
    old = {k: os.environ.get(k) for k in env}
    os.environ.update(env)
    cluster = None
    try:
        # silence_logs=CRITICAL: a worker's heartbeat racing the scheduler's shutdown logs a
        # CommClosedError traceback at ERROR level that means nothing to the user; task failures still
        # reach the client as exceptions, with their own traceback.
        with _signals_deferred():  # Ctrl-C/SIGTERM during start-up: acted on once the cluster can be closed
            try:
                # the scheduler always serves HTTP (health routes), at 8787 when no address is given: with another
                # cluster on the machine that printed "Port 8787 is already in use"; ":0" takes a free port, and
                # dashboard=False keeps the (unused) dashboard off
                cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                                       dashboard_address=":0", scheduler_kwargs={"dashboard": False},
                                       silence_logs=logging.CRITICAL)
            finally:
                for k, v in old.items():
                    if v is None:
                        os.environ.pop(k, None)
                    else:
                        os.environ[k] = v
        log.info("dask: LocalCluster with %d worker process(es) at %s", workers, cluster.scheduler_address)
        with Client(cluster) as client:
            _workers_ignore_sigint(client)
            yield client
    finally:
        if cluster is not None:
            cluster.close()


def _quiet_resource_tracker() -> None:
    """Start multiprocessing's resource tracker (if not running) without its "leaked semaphore" warning.

    A worker stopped in the middle of a task (Ctrl-C, SIGTERM) cannot release the semaphores of its process
    queues; the tracker releases them at exit, as it should, but also printed "There appear to be 2 leaked
    semaphore objects to clean up at shutdown" after fivid's own message: nothing the user can act on. The
    tracker is a separate process started with the interpreter's ``-W`` options: the one option is added for
    its start only, so no warning filter changes in this process.
    """
    import sys
    from multiprocessing import resource_tracker

    if getattr(resource_tracker._resource_tracker, "_fd", None) is not None:
        return  # already running (with whatever options it was started with)
    saved = list(sys.warnoptions)
    sys.warnoptions.append("ignore:resource_tracker:UserWarning")
    try:
        resource_tracker.ensure_running()
    finally:
        sys.warnoptions[:] = saved


def _ignore_sigint():
    """In a worker process: ignore SIGINT (a plain function, so that it pickles to the workers)."""
    import signal
    import threading

    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)


def _workers_ignore_sigint(client) -> None:
    """Ctrl-C reaches the whole process group: the local workers ignore it and the client closes them.

    A worker killed by its own KeyboardInterrupt leaves its multiprocessing semaphores behind, and the resource
    tracker warned about "leaked semaphore objects" at exit; closed by the client they clean up. A worker's loop
    runs in its process's main thread, where ``Client.run`` calls the function.
    """
    client.run(_ignore_sigint)


@contextlib.contextmanager
def _signals_deferred():
    """Hold SIGINT and SIGTERM for the block, then act on the first one received as its handler would.

    An interrupt inside ``LocalCluster(...)`` leaves a half-started cluster that cannot be closed (its
    workers are still initialising) and whose close at exit prints a traceback. Main thread only.
    """
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    received: list[int] = []
    previous = {s: signal.signal(s, lambda signum, frame: received.append(signum))
                for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
    if received:
        handler = previous[received[0]]
        if callable(handler):
            handler(received[0], None)  # raises KeyboardInterrupt / Interrupted
        elif handler == signal.SIG_DFL:
            signal.raise_signal(received[0])


def map_tasks(func, items: dict, *, workers: int = 2, scheduler: str | None = None, connect_timeout: float = 10.0):
    """Run ``func(*args)`` for each ``name -> args`` on dask; yield ``(name, result, seconds, pid)`` as they finish.

    ``seconds`` is the wall time of the task on its worker [s], ``pid`` the worker's process id. With ``workers=0``
    and no ``scheduler`` the tasks run in this process, one after the other in the order of ``items``, without dask
    (``pid`` is then this process's); any other ``workers`` below 1 means one worker.
    """
    if workers == 0 and scheduler is None:
        for name, args in items.items():
            yield (name, *_timed_call(func, *args))
        return
    from distributed import as_completed

    workers = max(int(workers), 1)
    with dask_client(workers=workers, scheduler=scheduler, connect_timeout=connect_timeout) as client:
        Interrupted.raise_if_received()  # a signal during the cluster's start-up
        futures = {client.submit(_timed_call, func, *args, key=f"fivid-{name}-{os.getpid()}-{time.time_ns()}",
                                 pure=False): name for name, args in items.items()}
        for fut in as_completed(futures):
            result, seconds, pid = fut.result()
            yield futures[fut], result, seconds, pid


def call(func, *args):
    """``func(*args)``: the task function of :func:`map_tasks` when each item carries its own function as its first
    argument (``name -> (func, *args)``)."""
    return func(*args)


def _timed_call(func, *args):
    t0 = time.perf_counter()
    out = func(*args)
    return out, time.perf_counter() - t0, os.getpid()
