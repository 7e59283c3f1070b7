"""fivid.surface: the Dektak's own printed results, closed forms of ISO parameters and the Gaussian filter,
synthetic profiles recovered within their sampling error, and the ``fivid profile`` command."""

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from fivid.cli import main
from fivid.surface import (evaluate_profile, gaussian_mean_line, gaussian_weights, instrument_results,
                           make_profile, read_profile, remove_form)
from fivid.surface.gaussian_filter import ALPHA, gaussian_weighting_function
from fivid.surface.statistics import autocorrelation, correlation_length, profile_psd
from fivid.surface.synthesis import gaussian_random_profile, profile_from_psd
from fivid.verify import evaluate_case, find_real_data, select_cases
from fivid.verify.cases.surface_closed_forms import sine_profile
from fivid.verify.cases.surface_dektak import WINDOW

UM = 1e-6


@pytest.fixture
def dektak(real_data):
    return real_data / "profiles" / "dektak-1.csv"


# --- the instrument as oracle ---------------------------------------------------------------------------------

@pytest.mark.parametrize("name", ["dektak_ra", "dektak_rq"])
def test_dektak_parameters_match_the_instrument(dektak, name):
    """Cases dektak_ra, dektak_rq (the instrument's Ra, Rq within 2 %, the basis there), on ../shared's copy of the
    file. Further: RzDIN and Rsk within 5 %; the window holds the samples at i * 1500 um / 9600 within
    [468, 733] um: 2996 ... 4691; without the form removal the 11 um/mm tilt dominates, so the comparison is not
    trivially satisfied."""
    (case,) = select_cases([name])
    result = evaluate_case(case, False, dektak)
    assert result.status == "passed", result
    d = result.outcome.details
    assert d["RzDIN: fivid / instrument"] == pytest.approx(1.0, rel=0.05)
    assert d["Rsk: fivid / instrument"] == pytest.approx(1.0, rel=0.05)
    assert d["points in the window"] == 4691 - 2996 + 1
    p = read_profile(dektak)
    assert evaluate_profile(p, window=WINDOW, form="none").parameters["Ra"] > 100 * instrument_results(p)["Ra"]


def test_the_shipped_dektak_file_is_the_measured_one(dektak):
    """The verification cases run on the copy shipped in the package (MIT licence, fivid/verify/data/README.md)."""
    assert find_real_data("profiles/dektak-1.csv").read_bytes() == dektak.read_bytes()


def test_dektak_header_in_si(dektak):
    p = read_profile(dektak)
    assert p.attrs["instrument_window_start"] == pytest.approx(468e-6)
    assert p.attrs["instrument_window_end"] == pytest.approx(733e-6)
    assert instrument_results(p)["Ra"] == pytest.approx(5.25e-9)
    assert instrument_results(p)["Rsk"] == pytest.approx(6.96)
    assert p.attrs["scan_length"] == pytest.approx(1.5e-3)
    assert p.attrs["stylus"] == "Radius: 2.5 µm"  # the latin-1 byte 0xB5 decoded
    x = p["x"].values
    assert x.size == 9600 and np.diff(x) == pytest.approx(np.full(9599, 1.5e-3 / 9600))


# --- closed forms -------------------------------------------------------------------------------------------

def test_sine_closed_forms():
    """A = 1 um, λ = 100 um, 40 periods of 1000 samples. Over whole periods, Rq and RΔq of the samples are exact
    (discrete orthogonality; RΔq's 7-point slope drops 3 samples at each end, a fraction 6/40000 of the record,
    and its own error (2π Δx/λ)^6/140 is negligible); Ra's integrand |sin| has kinks, so its
    rectangle-rule error is O((2π Δx/λ)^2); the interpolated crossings make Rsm exact to O((Δx/λ)^2)."""
    a, lam, n = 1 * UM, 100 * UM, 1000
    ev = evaluate_profile(sine_profile(a, lam, 40, n), form="none")
    p = ev.parameters
    h = 2 * np.pi / n
    assert p["Ra"] == pytest.approx(2 * a / np.pi, rel=h**2)
    assert p["Rq"] == pytest.approx(a / np.sqrt(2), rel=1e-9)
    assert p["Rsm"] == pytest.approx(lam, rel=(1 / n) ** 2)
    assert p["Rdq"] == pytest.approx(2 * np.pi * a / (lam * np.sqrt(2)), rel=6 / (40 * n))
    assert p["Rt"] == pytest.approx(2 * a, rel=h**2) and p["Rz"] == p["Rt"]
    assert p["RzDIN"] == pytest.approx(2 * a, rel=h**2)  # each fifth holds 8 whole periods
    assert p["Rsk"] == pytest.approx(0, abs=1e-9) and p["Rku"] == pytest.approx(1.5, rel=1e-9)
    # mean |atan(k A cos)|: numerical quadrature over one period of the closed form
    theta = np.linspace(0, 2 * np.pi, 200_001)[:-1]
    expected = np.mean(np.abs(np.arctan(2 * np.pi * a / lam * np.cos(theta))))
    assert p["attack_angle"] == pytest.approx(expected, rel=6 / (40 * n) + h**2)  # same dropped ends as RΔq


def test_form_removal_is_tilt_invariant_and_exact_on_polynomials():
    x = np.linspace(0, 1e-3, 2001)
    cubic = 1e-6 * (0.3 - 2 * (x / 1e-3) + 5 * (x / 1e-3) ** 2 - 4 * (x / 1e-3) ** 3)
    residual, form = remove_form(x, cubic, 3)
    assert np.max(np.abs(residual)) < 1e-12 * np.max(np.abs(cubic)) * 1e3
    sine = sine_profile(1 * UM, 100 * UM, 20, 200)
    tilted = make_profile(sine["x"].values, sine.values + 0.01 * sine["x"].values + 3 * UM)
    assert evaluate_profile(tilted).parameters == pytest.approx(evaluate_profile(sine).parameters, rel=1e-9)


def test_gaussian_weights_are_the_standards_function():
    """Δx s(kΔx), normalised: the truncated mass beyond ±λc is erfc(sqrt(π)/α) = 1.3e-7, so the normalised
    weights equal Δx s(x) of ISO 16610-21 to ~1e-7; s(0) = 1/(α λc) and α = sqrt(ln2/π)."""
    dx, lc = 0.5 * UM, 80 * UM
    x, w = gaussian_weights(dx, lc)
    assert x[0] == pytest.approx(-lc) and x[-1] == pytest.approx(lc) and w.sum() == pytest.approx(1, abs=1e-15)
    s = np.exp(-np.pi * (x / (ALPHA * lc)) ** 2) / (ALPHA * lc)
    assert w == pytest.approx(dx * s, rel=1e-6)
    assert gaussian_weighting_function(0.0, lc) == pytest.approx(1 / (ALPHA * lc))
    assert ALPHA == pytest.approx(0.4697, abs=1e-4)


def test_gaussian_filter_transmission():
    """The mean line passes exp(-π(α λc/λ)²) of a sine's amplitude, 50 % at λ = λc: case gaussian_filter_cutoff
    (λ/λc = 0.5-2, the tolerance's basis there)."""
    (case,) = select_cases(["gaussian_filter_cutoff"])
    result = evaluate_case(case, False, None)
    assert result.status == "passed", result
    assert result.outcome.details["largest |measured - closed form| over λ/λc = 0.5-2"] < 1e-6


def test_mean_line_of_a_constant_is_the_constant_to_the_ends():
    z = np.full(500, 3e-6)
    assert gaussian_mean_line(z, 1 * UM, 80 * UM) == pytest.approx(z, rel=1e-12)


@pytest.mark.parametrize("kwargs", [{}, {"cutoff": 80 * UM}, {"cutoff": 80 * UM, "short_cutoff": 2.5 * UM}])
def test_flat_profile_gives_zeros(kwargs):
    """z = 0: exactly zero heights, Rsk and Rku undefined (NaN), no profile element. A tilted plane 2 um up: the
    line fit leaves round-off, below 1000 eps × 2 um (slopes: that over one step)."""
    x = np.arange(4000) * 0.25 * UM
    heights = ("Ra", "Rq", "Rz", "RzDIN", "Rt", "Rp", "Rv", "Rdq", "attack_angle")
    p = evaluate_profile(make_profile(x, np.zeros(x.size)), **kwargs).parameters
    assert all(p[k] == 0 for k in heights), p
    assert math.isnan(p["Rsk"]) and math.isnan(p["Rku"]) and math.isnan(p["Rsm"])
    p = evaluate_profile(make_profile(x, 2 * UM + 1e-3 * x), **kwargs).parameters
    roundoff = 1000 * np.finfo(float).eps * 2 * UM
    for k in heights:  # slopes: height round-off over one step
        assert p[k] == pytest.approx(0, abs=roundoff / (0.25 * UM if k in ("Rdq", "attack_angle") else 1)), k


def test_rz_over_five_sampling_lengths_with_a_cutoff():
    """λ = λc/8: the roughness passes 1 - exp(-π (8α)²) = 1 - 1e-19 of the sine. A window of 6 λc leaves 5 λc after
    trimming λc/2 at each end: 5 sampling lengths; Rz = 2A, Rsm = λ; Wa, Wq of the waviness ~ 0."""
    a, lc, dx = 1 * UM, 80 * UM, 0.1 * UM
    x = np.arange(int(round(6 * lc / dx)) + 1) * dx
    p = make_profile(x, a * np.sin(2 * np.pi * x / (lc / 8)) + 0.05 * a * np.sin(2 * np.pi * x / (40 * lc)))
    ev = evaluate_profile(p, cutoff=lc, form="line")
    assert ev.settings["Rz_sampling_lengths"] == 5
    assert ev.parameters["Rz"] == pytest.approx(2 * a, rel=1e-3)
    assert ev.parameters["Rsm"] == pytest.approx(lc / 8, rel=1e-3)
    assert ev.parameters["Rq"] == pytest.approx(a / np.sqrt(2), rel=2e-3)
    assert ev.parameters["Wq"] < 0.01 * a


# --- synthesis ----------------------------------------------------------------------------------------------

def _bartlett_std_of_correlation_length(xi_samples, n):
    """Std of the 1/e lag estimate of a Gaussian ACF: Bartlett's variance of ρ̂(ξ) over |ρ'(ξ)| = 2/(e ξ)."""
    k = np.arange(-20 * xi_samples, 20 * xi_samples + 1.0)
    r = lambda u: np.exp(-((u / xi_samples) ** 2))  # noqa: E731
    t = xi_samples
    var = np.sum(r(k) ** 2 + r(k + t) * r(k - t) - 4 * r(t) * r(k) * r(k - t) + 2 * r(t) ** 2 * r(k) ** 2) / n
    return np.sqrt(var) / (2 / (np.e * xi_samples))


def test_gaussian_profiles_recover_rq_and_correlation_length():
    """16 seeds, L = 1000 ξ, Δx = ξ/10. Rq's relative std per profile is sqrt(ξ sqrt(2π)/L)/2 = 2.5 %, the 1/e lag's
    follows from Bartlett's formula (≈ 0.034 ξ); the means over seeds are within 3 standard errors."""
    rq, xi, dx, n, seeds = 1 * UM, 10 * UM, 1 * UM, 10_000, range(16)
    rqs, xis = [], []
    for seed in seeds:
        p = gaussian_random_profile(rq, xi, n * dx, dx, seed=seed)
        assert p.attrs["synthetic"] == "yes" and p.attrs["seed"] == seed
        rqs.append(float(np.sqrt(np.mean(p.values**2))))
        xis.append(correlation_length(autocorrelation(p, max_lag=10 * xi)))
    se_rq = rq * 0.5 * np.sqrt(xi * np.sqrt(2 * np.pi) / (n * dx)) / np.sqrt(len(seeds))
    assert abs(np.mean(rqs) - rq) < 3 * se_rq
    sd_xi = _bartlett_std_of_correlation_length(xi / dx, n) * dx
    assert abs(np.mean(xis) - xi) < 3 * sd_xi / np.sqrt(len(seeds))
    assert 0.5 < np.std(xis, ddof=1) / sd_xi < 2  # the predicted scatter is the observed one


def test_synthesis_is_reproducible_and_seeded():
    a = gaussian_random_profile(1 * UM, 10 * UM, 1e-3, 1 * UM, seed=7)
    b = gaussian_random_profile(1 * UM, 10 * UM, 1e-3, 1 * UM, seed=7)
    c = gaussian_random_profile(1 * UM, 10 * UM, 1e-3, 1 * UM, seed=8)
    assert np.array_equal(a.values, b.values) and not np.array_equal(a.values, c.values)


def test_exponential_profile_correlation_length():
    """Exponential ACF, Δx = ξ/10: the PSD beyond the Nyquist frequency is missing, a fraction
    1 - (2/π) atan(2π f_N ξ) = 2 % of the variance, which raises ρ(ξ) by that fraction and the 1/e lag by ~2 %."""
    rq, xi, dx, n = 1 * UM, 10 * UM, 1 * UM, 20_000
    xis = [correlation_length(autocorrelation(gaussian_random_profile(rq, xi, n * dx, dx, acf="exponential",
                                                                      seed=s), max_lag=10 * xi)) for s in range(12)]
    tail = 1 - 2 / np.pi * np.arctan(2 * np.pi * (0.5 / dx) * xi)
    se = np.std(xis, ddof=1) / np.sqrt(len(xis))
    assert abs(np.mean(xis) / xi - 1) < tail + 3 * se / xi


def test_profile_from_a_flat_band_psd():
    """G = G0 on [f1, f2]: expected Rq² = G0 (f2 - f1); Welch's in-band level is G0 within its χ² error
    (≈ 1/sqrt(bins × averages) ~ 1 %, checked at 5 %)."""
    g0, f1, f2, dx = 1e-20, 2e3, 2e4, 1 * UM
    p = profile_from_psd((np.array([f1, f1, f2, f2]) + [-1e-9, 0, 0, 1e-9], [0, g0, g0, 0]), 0.2, dx, seed=3)
    assert p.attrs["expected_rq"] == pytest.approx(np.sqrt(g0 * (f2 - f1)), rel=0.01)
    psd = profile_psd(p, nperseg=2048)
    f = psd["spatial_frequency"].values
    band = (f > 1.2 * f1) & (f < 0.9 * f2)
    assert psd.values[band].mean() == pytest.approx(g0, rel=0.05)


# --- command line -------------------------------------------------------------------------------------------

def test_cli_json_on_the_dektak_file(dektak, capsys):
    assert main(["profile", str(dektak), "--window", "468 um", "733 um", "--json"]) == 0
    j = json.loads(capsys.readouterr().out)
    assert j["Ra"] == pytest.approx(5.25e-9, rel=0.02) and j["units"]["Ra"] == "m"
    assert j["instrument"]["RzDIN"] == pytest.approx(4.917e-8)
    assert abs(j["relative_difference"]["Rq"]) < 0.02
    assert j["settings"]["window_start"] == pytest.approx(468e-6)


def test_cli_as_a_process_exit_codes(dektak):
    ok = subprocess.run([sys.executable, "-m", "fivid", "profile", str(dektak), "--window", "468 um", "733 um",
                         "--json"], capture_output=True, text=True)
    assert ok.returncode == 0, ok.stderr
    assert json.loads(ok.stdout)["Rq"] == pytest.approx(1.143e-8, rel=0.02)
    bad = subprocess.run([sys.executable, "-m", "fivid", "profile", str(dektak), "--window", "468", "733"],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "Traceback" not in bad.stderr
    assert "--window" in bad.stderr and "'468 um'" in bad.stderr


@pytest.mark.parametrize("window, words", [(["733 um", "468 um"], "less than"), (["468 kg", "733 um"], "kg"),
                                           (["2 m", "3 m"], "outside")])
def test_cli_bad_window_exits_2(dektak, capsys, window, words):
    assert main(["profile", str(dektak), "--window", *window]) == 2
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err


def test_cli_netcdf_and_plot(dektak, tmp_path, capsys):
    import xarray as xr

    out, png = tmp_path / "p.nc", tmp_path / "p.png"
    args = ["profile", str(dektak), "--cutoff", "80 um", "-o", str(out), "--plot", str(png), "--json"]
    assert main(args) == 0
    j = json.loads(capsys.readouterr().out)
    with xr.open_dataset(out) as ds:
        assert float(ds["Ra"]) == pytest.approx(j["Ra"]) and ds["Ra"].attrs["units"] == "m"
        assert ds["height"].sizes["x"] == 9600 and ds["roughness"].dims == ("x_evaluation",)
        assert ds.attrs["evaluation_cutoff"] == pytest.approx(80e-6) and "history" in ds.attrs
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(args) == 2  # exists, no --overwrite
    assert "exists" in capsys.readouterr().err
