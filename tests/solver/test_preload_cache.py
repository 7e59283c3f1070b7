"""The static preload solved once per model, load and friction and read back from the cache (issue 30,
fivid/solver/preload_cache.py): the reference is a fresh :func:`fivid.fe.static.preload_state` solve."""

import dataclasses
import json
import os
import pickle
import subprocess
import sys
from pathlib import Path

import numpy as np

from tests.helpers.reduced_setup import COARSE, coarse, run_inputs  # noqa: F401  (coarse is a fixture)

ROOT = Path(__file__).resolve().parents[2]


def _assert_same_preload(a, b):
    """Every field of two preloads equal bit for bit, with the same types and dtypes."""
    for f in dataclasses.fields(a):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if f.name == "geometry":
            _assert_same_preload(x, y)
        elif isinstance(x, np.ndarray):
            assert isinstance(y, np.ndarray) and x.dtype == y.dtype and x.shape == y.shape, f.name
            np.testing.assert_array_equal(x, y, err_msg=f.name)
        else:
            assert type(x) is type(y) and x == y, (f.name, x, y)


def test_cached_preload_is_the_fresh_solve_bit_for_bit(coarse, tmp_path):
    """Solved and stored, then read back (from a model rebuilt by pickling, as a dask worker gets it): both equal a
    fresh ``preload_state`` exactly; without the cache nothing is stored."""
    from fivid.fe.static import preload_state
    from fivid.friction.curve import slave_coefficients
    from fivid.solver.preload_cache import cached_preload

    mu = slave_coefficients(coarse, 0.3)
    fresh = preload_state(coarse, 5.0, mu=mu)
    built, s1, t1 = cached_preload(coarse, 5.0, mu=mu, folder=tmp_path)
    read, s2, t2 = cached_preload(pickle.loads(pickle.dumps(coarse)), 5.0, mu=mu, folder=tmp_path)
    assert (s1, s2) == ("built", "cache") and t1 > 0 and t2 == 0
    _assert_same_preload(built, fresh)
    _assert_same_preload(read, fresh)
    assert len(list((tmp_path / "preloads").glob("*.npz"))) == 1
    _, s3, _ = cached_preload(coarse, 5.0, mu=mu, cache=False, folder=tmp_path / "none")
    assert s3 == "built (not cached)" and not (tmp_path / "none").exists()


def test_a_change_of_load_friction_or_model_misses_the_cache(coarse, tmp_path):
    """Another normal load, friction coefficient or material is another entry, solved afresh (and equal to its own
    fresh solve); the same model read again from its file hits."""
    from fivid.fe import load_model
    from fivid.fe.static import preload_state
    from fivid.friction.curve import slave_coefficients
    from fivid.solver.preload_cache import cached_preload, preload_key

    mu = slave_coefficients(coarse, 0.3)
    base, source, _ = cached_preload(coarse, 5.0, mu=mu, folder=tmp_path)
    assert source == "built"
    assert cached_preload(load_model(COARSE), 5.0, mu=mu, folder=tmp_path)[1] == "cache"
    text = COARSE.read_text()
    assert "E: 210 GPa" in text
    (tmp_path / "stiffer.yaml").write_text(text.replace("E: 210 GPa", "E: 212 GPa"))
    stiffer = load_model(tmp_path / "stiffer.yaml")
    cases = [(coarse, 6.0, mu), (coarse, 5.0, slave_coefficients(coarse, 0.2)), (stiffer, 5.0, mu)]
    keys = {preload_key(coarse, 5.0, mu)}
    for model, load, m in cases:
        state, source, _ = cached_preload(model, load, mu=m, folder=tmp_path)
        assert source == "built"
        _assert_same_preload(state, preload_state(model, load, mu=m))
        assert state.displacement != base.displacement
        keys.add(preload_key(model, load, m))
    assert len(keys) == 4 and len(list((tmp_path / "preloads").glob("*.npz"))) == 4


def test_equal_friction_given_three_ways_is_one_entry(coarse, tmp_path):
    """None (each pair's own mu), that mu as a scalar and as the per-slave array: the solve is the same
    (preload_state resolves all three to one array), so the key and the entry are one; the read equals the solve."""
    from fivid.fe.static import preload_state
    from fivid.friction.curve import slave_coefficients
    from fivid.solver.preload_cache import cached_preload, preload_key

    own = float(coarse.contacts[0].mu)
    assert all(c.mu == own for c in coarse.contacts)
    ways = [None, own, slave_coefficients(coarse, own)]
    assert len({preload_key(coarse, 5.0, m) for m in ways}) == 1
    assert preload_key(coarse, 5.0, own) != preload_key(coarse, 5.0, own + 0.1)
    sources = [cached_preload(coarse, 5.0, mu=m, folder=tmp_path)[1] for m in ways]
    assert sources == ["built", "cache", "cache"]
    _assert_same_preload(cached_preload(coarse, 5.0, folder=tmp_path)[0], preload_state(coarse, 5.0))


_SOLVE = """
import json, sys
from fivid.fe import load_model
from fivid.friction.curve import slave_coefficients
from fivid.solver.preload_cache import cached_preload
model = load_model(sys.argv[1])
state, source, _ = cached_preload(model, 5.0, mu=slave_coefficients(model, 0.3), folder=sys.argv[2])
print(json.dumps({"source": source, "displacement": state.displacement}))
"""


def test_two_concurrent_processes_solve_the_preload_once(tmp_path):
    """Two processes started together on one model, load and friction with an empty cache: one solves and stores
    (under the entry's file lock), the other waits and reads; one entry, the same clamp displacement."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    cmd = [sys.executable, "-c", _SOLVE, str(COARSE), str(tmp_path / "cache")]
    procs = [subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for _ in range(2)]
    outs = [p.communicate(timeout=600) for p in procs]
    assert [p.returncode for p in procs] == [0, 0], [o[1] for o in outs]
    results = [json.loads(o[0]) for o in outs]
    assert sorted(r["source"] for r in results) == ["built", "cache"]
    assert results[0]["displacement"] == results[1]["displacement"]
    assert len(list((tmp_path / "cache" / "preloads").glob("*.npz"))) == 1


def test_a_run_from_the_cached_preload_equals_one_solved_afresh(coarse, tmp_path):
    """``simulate`` with the preload (and basis) from the cache gives the records of a run with both solved afresh
    (``basis_cache=False``), bit for bit."""
    from fivid.solver import simulate

    fresh = simulate(coarse, **run_inputs(1e-3, reduced="reduced", basis_cache=False))
    simulate(coarse, **run_inputs(1e-3, reduced="reduced", cache_dir=tmp_path))  # stores both
    assert len(list((tmp_path / "preloads").glob("*.npz"))) == 1
    cached = simulate(coarse, **run_inputs(1e-3, reduced="reduced", cache_dir=tmp_path))
    assert cached.attrs["reduced_basis_source"] == "cache"
    for name in ("acceleration", "friction_force", "normal_force"):
        np.testing.assert_array_equal(cached[name].values, fresh[name].values, err_msg=name)


def test_content_key_sees_every_field_and_hashes_objects_by_content():
    """A dataclass field, a mapping value or an array element changed changes the key; equal content built apart
    gives the same key; an object without a pickle is refused (TypeError), not keyed by its address."""
    import pytest

    from fivid.solver.basis_cache import content_key

    @dataclasses.dataclass
    class Pair:
        a: np.ndarray
        b: dict

    one = Pair(np.arange(4.0), {"x": 1.0, "y": (2, 3)})
    assert content_key("p", one) == content_key("p", Pair(np.arange(4.0), {"y": (2, 3), "x": 1.0}))
    assert content_key("p", one) != content_key("p", Pair(np.arange(4.0) + [0, 0, 0, 1e-12], one.b))
    assert content_key("p", one) != content_key("p", Pair(one.a, {"x": 1.0, "y": (2, 4)}))
    assert content_key("p", one) != content_key("q", one)
    with pytest.raises(TypeError, match="cannot hash"):
        content_key("p", lambda: 1)
