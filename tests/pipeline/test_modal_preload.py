"""The pipeline's modal stage linearises about the static preload from the cache (fivid/solver/preload_cache.py):
the reference is :func:`fivid.fe.modal.modal_analysis` solving that preload itself."""

import numpy as np

from tests.helpers.reduced_setup import COARSE


def test_modal_stage_reads_the_cached_preload_and_gives_the_same_modes(tmp_path, monkeypatch):
    """The modal stage's analysis equals one that solves its own preload, bit for bit, and its preload is the cache
    entry ``cached_preload(model, load)`` finds (a second stage run reads it)."""
    from fivid.fe import load_model
    from fivid.fe.modal import modal_analysis
    from fivid.pipeline.stages import _modes
    from fivid.solver.preload_cache import cached_preload

    monkeypatch.setenv("FIVID_CACHE_DIR", str(tmp_path))
    model = load_model(COARSE)
    staged = _modes(model, 6, 5.0)
    assert cached_preload(model, 5.0)[1] == "cache"
    again = _modes(load_model(COARSE), 6, 5.0)
    fresh = modal_analysis(model, n_modes=6, include_contact=True, normal_load=5.0)
    for ds in (staged, again):
        for name in ("frequency", "eigenvalue"):
            np.testing.assert_array_equal(ds[name].values, fresh[name].values, err_msg=name)
        for key in ("preload_displacement", "normal_load", "closed_slave_nodes", "closed_normal_force"):
            np.testing.assert_array_equal(ds.attrs[key], fresh.attrs[key], err_msg=key)
    assert len(list((tmp_path / "preloads").glob("*.npz"))) == 1
