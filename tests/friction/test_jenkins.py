"""Jenkins element and Iwan series: closed-form energy per cycle, Masing's rule, naive reference."""

import numpy as np
import pytest

from fivid.errors import FividError
from fivid.friction import (iwan_energy_per_cycle, iwan_force, iwan_uniform_elements, jenkins_energy_per_cycle,
                            jenkins_force, jenkins_periodic_force, loop_energy)


def _naive_jenkins(x, k, fs):
    """Obviously-correct reference: slider position z, force k (x - z), slip when |force| > fs."""
    z = x[0]
    out = []
    for xi in x:
        f = k * (xi - z)
        if f > fs:
            z = xi - fs / k
        elif f < -fs:
            z = xi + fs / k
        out.append(k * (xi - z))
    return np.array(out)


def _cycles(amplitude, n_cycles=3, n=4000):
    t = np.linspace(0, n_cycles, n_cycles * n + 1)
    return t, amplitude * np.sin(2 * np.pi * t)


def test_kernel_matches_naive_reference():
    rng = np.random.default_rng(4)
    x = np.cumsum(rng.normal(size=3000)) * 1e-4
    assert np.allclose(jenkins_force(x - x[0], 2e4, 1.5), _naive_jenkins(x - x[0], 2e4, 1.5), atol=1e-12)


@pytest.mark.parametrize("ratio", [1.5, 2.0, 5.0, 40.0])
def test_energy_per_cycle_closed_form(ratio):
    k, fs = 3.9e5, 0.45 * 10
    a = ratio * fs / k
    t, x = _cycles(a)
    f = jenkins_force(x, k, fs)
    n = 4000
    # last full cycle, steady; the loop is a parallelogram with straight sides, so the trapezoidal
    # rule is exact except over the two samples where stick turns to slip: error <= 2 * fs * |dx|
    # with |dx| <= 2 pi a / n (the largest displacement step)
    w = loop_energy(x[-n - 1:], f[-n - 1:])
    tol = 2 * fs * 2 * np.pi * a / n
    assert abs(w - 4 * fs * (a - fs / k)) <= tol
    assert jenkins_energy_per_cycle(a, k, fs) == pytest.approx(4 * fs * (a - fs / k), rel=1e-15)


def test_no_dissipation_below_slip():
    k, fs = 1e5, 2.0
    t, x = _cycles(0.9 * fs / k)
    f = jenkins_force(x, k, fs)
    assert np.allclose(f, k * x, rtol=0, atol=1e-12)
    assert jenkins_energy_per_cycle(0.9 * fs / k, k, fs) == 0.0


def test_periodic_force_forgets_its_start():
    k, fs = 1e5, 2.0
    n = 256
    x = 3 * fs / k * np.cos(2 * np.pi * np.arange(n) / n + 0.3)
    f2, _ = jenkins_periodic_force(x[None, :], k, fs, n_passes=2)
    f5, _ = jenkins_periodic_force(x[None, :], k, fs, n_passes=5)
    assert np.array_equal(f2, f5)
    # half-wave symmetry of the steady loop
    assert np.allclose(f2[0, : n // 2], -f2[0, n // 2:], atol=1e-12 * fs)


def test_iwan_masing_rule():
    # Masing: the unloading branch from (a, F(a)) is F(a) - 2 F_backbone((a - x) / 2)
    k, fs = 1e5, 3.0
    ks, fss = iwan_uniform_elements(k, fs, 50)
    a = 1.5 * fs / k
    up = np.linspace(0, a, 3001)
    down = np.linspace(a, -a, 6001)
    x = np.concatenate([up, down[1:]])
    f = iwan_force(x, ks, fss)
    backbone = f[: up.size]
    branch = f[up.size - 1:]
    expected = backbone[-1] - 2 * np.interp((a - down) / 2, up, backbone)
    assert np.allclose(branch, expected, atol=1e-9 * fs)
    # initial stiffness k and full slip force fs
    assert (f[1] - f[0]) / (x[1] - x[0]) == pytest.approx(k, rel=1e-12)
    assert np.max(iwan_force(np.linspace(0, 3 * fs / k, 100), ks, fss)) == pytest.approx(fs, rel=1e-12)


def test_iwan_energy_is_sum_of_elements():
    k, fs = 1e5, 3.0
    ks, fss = iwan_uniform_elements(k, fs, 20)
    a = 1.2 * fs / k
    t, x = _cycles(a, n=20000)
    f = iwan_force(x, ks, fss)
    w = loop_energy(x[-20001:], f[-20001:])
    # trapezoid error bound as in the single element, summed over the elements: 2 fs |dx|max
    assert abs(w - iwan_energy_per_cycle(a, ks, fss)) <= 2 * fs * 2 * np.pi * a / 20000


def test_iwan_energy_accepts_an_amplitude_array_like_jenkins():
    # an array of amplitudes gives the array of scalar results (jenkins_energy_per_cycle does the same)
    ks, fss = iwan_uniform_elements(1e3, 1.0, 10)
    a = np.array([0.5e-3, 1e-3, 3e-3])
    w = iwan_energy_per_cycle(a, ks, fss)
    assert w.shape == a.shape
    assert np.array_equal(w, [iwan_energy_per_cycle(ai, ks, fss) for ai in a])


@pytest.mark.parametrize("k, fs", [(0.0, 1.0), (1.0, -1.0), (np.nan, 1.0), (1.0, np.inf)])
def test_bad_parameters(k, fs):
    with pytest.raises(FividError, match="must be finite and > 0"):
        jenkins_force(np.zeros(3), k, fs)


from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402


@settings(max_examples=50, deadline=None)
@given(
    steps=st.lists(st.floats(-1.0, 1.0, allow_nan=False), min_size=2, max_size=200),
    k=st.floats(1.0, 1e7),
    fs=st.floats(1e-3, 1e3),
)
def test_kernel_matches_naive_reference_on_random_paths(steps, k, fs):
    x = np.cumsum(steps) * (3 * fs / k)  # increments up to 3 slip displacements: stick and slip both occur
    x -= x[0]
    ref = _naive_jenkins(x, k, fs)
    got = jenkins_force(x, k, fs)
    assert np.all(np.abs(got) <= fs * (1 + 1e-15))
    # the naive reference recomputes k (x - z) each step; the kernel accumulates increments: rounding
    # ~ eps x (number of steps) x k |x|max
    assert np.allclose(got, ref, rtol=0, atol=1e-15 * len(x) * k * np.max(np.abs(x)) + 1e-12 * fs)
