"""Coverage of the reported 95 % intervals over many seeds (SYNTHETIC runs; slow, ~2-3 min on 2 cores).

For N independent seeds the number of intervals that contain the truth is Binomial(N, 0.95) when the
intervals are right: mean 0.95 N, sd sqrt(N 0.95 0.05). The checks accept ±3.5 sd (two-sided
~5e-4 false-alarm rate per count); too-narrow intervals fail the lower bound, too-wide ones the
upper bound (checked where N is large enough for it to be below N).
"""

import numpy as np
import pytest
from tests.helpers.synthetic_friction_runs import ANALYSIS_BAND, MU0, band_amplitude, band_fraction, run_grid, true_law

from fivid.identify import identify_friction_law

N_SEEDS = 50


def _bounds(n):
    sd = np.sqrt(n * 0.95 * 0.05)
    return 0.95 * n - 3.5 * sd, 0.95 * n + 3.5 * sd


@pytest.mark.slow
def test_intervals_cover_the_truth_at_the_nominal_rate():
    law = true_law("linear_velocity")
    truth_coeff = law.amplitude_model.coefficients * np.sqrt(band_fraction(law))
    hits = {"mu0": 0, "run_mu": 0, "run_a": 0, "coeff": np.zeros(4, int)}
    n_runs = 0
    for seed in range(N_SEEDS):
        runs = run_grid(law, seed=100 + seed, velocities=(0.002, 0.005, 0.01, 0.02), duration=2.4)
        res = identify_friction_law(runs, band=ANALYSIS_BAND, tare=(0.0, 0.5), nperseg=2048, categorical=True)
        assert res.chosen.form != "constant"
        hits["mu0"] += res.mu0_ci[0] <= MU0 <= res.mu0_ci[1]
        for r in res.runs:
            n_runs += 1
            hits["run_mu"] += r.mu_mean_ci[0] <= MU0 <= r.mu_mean_ci[1]
            a = band_amplitude(law, r.sliding_velocity, r.roughness_ra, r.normal_load)
            hits["run_a"] += abs(r.mu_rms - a) <= 1.959964 * r.mu_rms_stderr
        lin = next(f for f in res.form_fits if f.form == "linear_velocity")
        hits["coeff"] += (lin.conf_int[:, 0] <= truth_coeff) & (truth_coeff <= lin.conf_int[:, 1])
    print("coverage counts", {k: (v.tolist() if isinstance(v, np.ndarray) else int(v)) for k, v in hits.items()},
          "of", N_SEEDS, "seeds,", n_runs, "runs")
    lo, hi = _bounds(n_runs)
    assert lo <= hits["run_mu"] <= hi
    assert lo <= hits["run_a"] <= hi
    lo, _ = _bounds(N_SEEDS)
    assert hits["mu0"] >= lo
    assert np.all(hits["coeff"] >= lo)


@pytest.mark.slow
def test_power_law_intervals_cover_the_truth():
    """The log-log WLS power law with a load factor: its 95 % intervals over 20 seeds (12 runs each)."""
    law = true_law("power_law_load")
    truth = dict(zip(law.amplitude_model.names, law.amplitude_model.coefficients))
    truth["log_prefactor"] += 0.5 * np.log(band_fraction(law))  # A is the band RMS
    n_seeds = 20
    hits = np.zeros(4, int)
    chosen = 0
    for seed in range(n_seeds):
        runs = run_grid(law, seed=500 + seed, velocities=(0.002, 0.005, 0.02), roughnesses=(0.4e-6, 1.6e-6),
                        loads=(2.0, 8.0), duration=2.4)
        res = identify_friction_law(runs, band=ANALYSIS_BAND, tare=(0.0, 0.5), nperseg=2048)
        pl = next(f for f in res.form_fits if f.form == "power_law")  # the load enters: the runs differ in load
        t = np.array([truth[n] for n in pl.model.names])
        hits += (pl.conf_int[:, 0] <= t) & (t <= pl.conf_int[:, 1])
        chosen += res.law.amplitude_model.form == "power_law"
    print("power-law coverage", dict(zip(pl.model.names, hits.tolist())), "of", n_seeds, "; chosen", chosen)
    lo, _ = _bounds(n_seeds)
    assert np.all(hits >= lo)
    assert chosen >= n_seeds - 2  # the generating form wins the AIC comparison
