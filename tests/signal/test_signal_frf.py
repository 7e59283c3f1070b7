"""H1/H2 and coherence: a single-degree-of-freedom oscillator against its analytic FRF, scipy.signal.coherence,
coherence 1 without noise, H1/H2 = γ². Synthetic signals from numpy Generators with the seeds given."""

import numpy as np
import pytest
import scipy.signal
import xarray as xr

from fivid.errors import ConfigError
from fivid.signal.frf import coherence, frf

FS = 1000.0


def channel(values, name, units):
    t = np.arange(values.size) / FS
    return xr.DataArray(values, dims="time", coords={"time": t}, name=name, attrs={"units": units})


def sdof(n=2**20, seed=0, noise=0.0):
    """Force (white) and displacement of m x'' + c x' + k x = F, digitised by the bilinear transform.

    The digital filter's FRF is exactly the analogue one at the pre-warped frequency
    ``Ω = 2 fs tan(π f / fs)`` (bilinear transform), which is the closed form the test compares with.
    """
    m, fn, zeta = 1.0, 50.0, 0.05
    k = m * (2 * np.pi * fn) ** 2
    c = 2 * zeta * np.sqrt(k * m)
    bd, ad = scipy.signal.bilinear([1.0], [m, c, k], FS)
    rng = np.random.default_rng(seed)
    force = rng.standard_normal(n)
    disp = scipy.signal.lfilter(bd, ad, force)
    sigma_noise = noise * np.std(disp)
    disp = disp + sigma_noise * rng.standard_normal(n)

    def analytic(f):
        w = 2 * FS * np.tan(np.pi * f / FS)
        return 1.0 / (k - m * w**2 + 1j * c * w)

    def true_coherence(f):  # |H|^2 Sxx / (|H|^2 Sxx + Snn) with white Sxx = 2/fs, Snn = 2 sigma_noise^2/fs
        h2 = np.abs(analytic(f)) ** 2
        return h2 / (h2 + sigma_noise**2)

    return (channel(force, "force", "N"), channel(disp, "displacement", "m"), analytic, 2 * zeta * fn,
            true_coherence)


@pytest.mark.parametrize("noise", [0.0, 0.3])
def test_h1_of_sdof_matches_analytic_frf(noise):
    x, y, analytic, half_power_bandwidth, true_coherence = sdof(noise=noise)
    nperseg = 8192
    h = frf(x, y, nperseg=nperseg, estimator="H1")
    f = h["frequency"].values
    sel = (f > 1) & (f < 400)
    rel = np.abs(h.values[sel] / analytic(f[sel]) - 1)
    # Bendat & Piersol (Random Data, 4th ed.): resolution bias at a resonance -(1/3)(B_e/B_r)^2 with the Hann
    # noise bandwidth B_e = 1.5 fs/N and the half-power bandwidth B_r = 2 zeta f_n; random error of |H1| (and of
    # its phase in rad) sqrt(1 - g2) / (|g| sqrt(2 n_d)), n_d = equivalent averages. Complex relative error:
    # sqrt 2 times that; 5 sigma over ~3000 bins. The true coherence is used: where it is tiny the estimate is
    # biased up by ~1/n_d and would understate the error. Without noise, the window's transient gives 1 - g2 ~ 1e-3.
    gamma2 = true_coherence(f[sel]) if noise else h["coherence"].values[sel]
    n_d = h.attrs["equivalent_averages"]
    bias = (1 / 3) * (1.5 * FS / nperseg / half_power_bandwidth) ** 2
    random = np.sqrt(2) * np.sqrt(1 - gamma2) / (np.sqrt(gamma2) * np.sqrt(2 * n_d))
    assert np.all(rel <= bias + 5 * random + 1e-9)
    assert h.attrs["units"] == "m N-1"


def test_h2_over_h1_is_inverse_coherence():
    x, y, *_ = sdof(n=2**17, noise=0.5)
    h1 = frf(x, y, nperseg=1024, estimator="H1")
    h2 = frf(x, y, nperseg=1024, estimator="H2")
    np.testing.assert_allclose((h1 / h2).values[1:], h1["coherence"].values[1:], rtol=1e-10)
    # output noise biases H2 upward by 1/gamma^2 at the resonance, H1 is unbiased
    assert np.all(np.abs(h2.values[1:]) >= np.abs(h1.values[1:]) * (1 - 1e-12))


def test_coherence_equals_scipy():
    x, y, *_ = sdof(n=2**16, noise=0.2)
    g = coherence(x, y, nperseg=512, noverlap=128)
    _, ref = scipy.signal.coherence(x.values, y.values, fs=FS, nperseg=512, noverlap=128, window="hann")
    np.testing.assert_allclose(g.values, ref, rtol=1e-9, atol=1e-12)


def test_coherence_is_one_without_noise():
    rng = np.random.default_rng(4)
    x = rng.standard_normal(2**15)
    g = coherence(channel(x, "force", "N"), channel(-3.0 * x, "force2", "N"), nperseg=1024)
    # |Pxy|^2 / (Pxx Pyy) of exactly proportional spectra: 1 up to round-off of the ratio
    np.testing.assert_allclose(g.values[1:], 1.0, atol=1e-12)


def test_unknown_estimator():
    x, y, *_ = sdof(n=4096)
    with pytest.raises(ConfigError, match="H3"):
        frf(x, y, nperseg=256, estimator="H3")


def test_input_noise_biases_h1_by_a_closed_form_factor_and_not_h2():
    # Measured input x + m with white m of variance 0.09 (input variance 1) and a noise-free output:
    # H1 = H Sxx / (Sxx + Smm) = H / 1.09 and H2 = H in expectation, coherence 1/1.09 at every frequency (Bendat &
    # Piersol §9.2.2). Averaged over the m bins of 1-400 Hz (away from Nyquist, where the bilinear map is singular);
    # random error of the mean ~ sqrt(2) sqrt(1 - g2)/(g sqrt(2 n_d)) / sqrt(m / 1.94) (Hann bin correlation), 5 sigma.
    x, y, analytic, *_ = sdof(n=2**19, seed=5)
    noisy = x + 0.3 * np.random.default_rng(6).standard_normal(x.size)
    noisy.attrs = dict(x.attrs)
    h1 = frf(noisy, y, nperseg=4096, estimator="H1")
    h2 = frf(noisy, y, nperseg=4096, estimator="H2")
    f = h1["frequency"].values
    sel = (f > 1) & (f < 400)
    g2 = 1 / 1.09
    n_d = h1.attrs["equivalent_averages"]
    sd_gamma2 = np.sqrt(2 / n_d) * g2 * (1 - g2)  # Bendat & Piersol eq. 9.82 (random error of the coherence)
    assert np.mean(h1["coherence"].values[sel]) == pytest.approx(g2, abs=5 * sd_gamma2 / np.sqrt(sel.sum() / 1.94)
                                                                  + 1 / n_d)  # + its bias ~ (1 - g2)^2 / n_d
    ha = analytic(f[sel])
    err = np.sqrt(2) * np.sqrt(1 - g2) / (np.sqrt(g2) * np.sqrt(2 * n_d))
    tol = 5 * err / np.sqrt(sel.sum() / 1.94)
    assert np.mean(np.abs(h1.values[sel] / ha)) == pytest.approx(1 / 1.09, abs=tol)
    assert np.mean(np.abs(h2.values[sel] / ha)) == pytest.approx(1.0, abs=tol)
