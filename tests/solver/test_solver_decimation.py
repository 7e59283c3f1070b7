"""The solver output's decimation (fivid.solver.output._decimate) is scipy.signal.decimate's zero-phase FIR.

Reference implementation: scipy.signal.decimate(x, q, ftype="fir", zero_phase=True) itself. The two sum the same
20 q + 1 products in another order, so they agree to the round-off of that sum: at most (20 q + 1) eps times
sum |h| max |x| (sum |h| < 1.2 for these Hamming-windowed sincs).
"""

import numpy as np
import pytest
import scipy.signal

from fivid.solver.output import _decimate, _decimation_filter


@pytest.mark.parametrize("q", [2, 3, 4, 5, 8])
def test_the_filter_is_firwin_hamming_at_the_new_nyquist(q):
    reference = scipy.signal.firwin(20 * q + 1, 1.0 / q, window="hamming")
    np.testing.assert_allclose(_decimation_filter(q), reference, rtol=0, atol=(20 * q + 1) * np.finfo(float).eps)


@pytest.mark.parametrize("q", [2, 3, 4, 5])
@pytest.mark.parametrize("n", [1000, 1001, 1003, 22120])
def test_decimation_matches_scipy_decimate(q, n):
    # synthetic: white noise on an offset (a force record), two columns (sensors), generator numpy default_rng(q n)
    x = np.random.default_rng(q * n).standard_normal((n, 2)) + 5.0
    got = _decimate(x, q)
    want = scipy.signal.decimate(x, q, ftype="fir", axis=0, zero_phase=True)[:n // q]
    assert got.shape == want.shape == (n // q, 2)
    bound = (20 * q + 1) * np.finfo(float).eps * 1.2 * np.abs(x).max()
    np.testing.assert_allclose(got, want, rtol=0, atol=bound)
    assert np.allclose(_decimate(x[:, 0], q), want[:, 0], rtol=0, atol=bound)  # one-dimensional records too
