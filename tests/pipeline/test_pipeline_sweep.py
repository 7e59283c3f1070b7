"""Monte-Carlo sweeps on dask.distributed: a 2-worker LocalCluster on 127.0.0.1."""

import os

import numpy as np
import pytest


def _law():
    from fivid.friction import AmplitudeModel, PerturbedCoulombLaw

    model = AmplitudeModel(form="constant", coefficients=np.array([0.01]), names=("amplitude",),
                           stderr=np.array([0.0]), covariance=np.zeros((1, 1)))
    f = np.linspace(100.0, 10000.0, 64)
    return PerturbedCoulombLaw(0.3, f, np.ones_like(f), model, (100.0, 10000.0))


def test_sweep_on_two_local_worker_processes_matches_serial():
    from fivid.execution.cluster import map_tasks

    law = _law()
    seeds = range(6)
    items = {f"seed{s}": (0.05, 51200.0, 0.01, 1e-6, s) for s in seeds}
    results, pids = {}, set()
    for name, mu_p, seconds, pid in map_tasks(law.sample, items, workers=2):
        results[name] = mu_p
        pids.add(pid)
        assert seconds >= 0
    assert len(pids) == 2 and os.getpid() not in pids  # two worker processes did the work
    for s in seeds:  # seeded synthesis: the same numbers on a worker as in this process
        np.testing.assert_array_equal(results[f"seed{s}"], law.sample(0.05, 51200.0, 0.01, 1e-6, s))


def test_no_workers_runs_the_tasks_here_in_order_and_call_applies_each_items_own_function():
    """``workers=0``: the tasks run in this process, in the items' order, with the results dask would give; ``call``
    runs items that carry their own function (the pipeline's simulations, the verification cases)."""
    from fivid.execution.cluster import call, map_tasks

    law = _law()
    items = {f"seed{s}": (law.sample, 0.05, 51200.0, 0.01, 1e-6, s) for s in (3, 1, 2)}
    out = list(map_tasks(call, items, workers=0))
    assert [name for name, *_ in out] == list(items)
    for name, mu_p, seconds, pid in out:
        assert pid == os.getpid() and seconds >= 0
        np.testing.assert_array_equal(mu_p, law.sample(*items[name][1:]))


def test_unreachable_scheduler_is_a_clear_input_error():
    from fivid.errors import FividError
    from fivid.execution.cluster import map_tasks

    with pytest.raises(FividError, match="cannot reach the dask scheduler"):
        list(map_tasks(len, {"a": ("x",)}, scheduler="tcp://127.0.0.1:9", connect_timeout=1.0))


def test_sweep_on_an_existing_scheduler_by_address():
    """``--scheduler tcp://...``: the tasks go to a cluster started elsewhere (here: a loopback LocalCluster)."""
    from distributed import LocalCluster

    from fivid.execution.cluster import map_tasks

    law = _law()
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster:
        out = list(map_tasks(law.sample, {"s3": (0.02, 51200.0, 0.01, 1e-6, 3)}, scheduler=cluster.scheduler_address))
    (name, mu_p, _, pid), = out
    assert name == "s3" and pid != os.getpid()  # computed in the cluster's worker process
    np.testing.assert_array_equal(mu_p, law.sample(0.02, 51200.0, 0.01, 1e-6, 3))
