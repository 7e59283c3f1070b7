"""Calibration of the significance flags: for pairs of independent synthetic runs of one process, each
flag must be raised in about 1 - confidence of the pairs (Monte Carlo; slow)."""

import numpy as np
import pytest

from tests.helpers.resonance_runs import resonance_run

from fivid.score import score_runs

PAIRS = 200


@pytest.mark.slow
@pytest.mark.parametrize("n_measured, n_simulated, nperseg", [
    (2**16, 2**16, 1024),  # nu ~ 240 both
    (2**16, 2**13, 1024),  # nu ~ 240 against ~ 29: the bias of the log of an average differs
    (2**13, 2**13, 2048),  # nu ~ 13: strongly skewed log-chi2 noise
])
def test_false_alarm_rates_match_the_confidence(n_measured, n_simulated, nperseg):
    # 10-30 s each on the shared 2-core machine. With 200 pairs a rate p = 0.05 has binomial sd
    # sqrt(p(1-p)/200) = 0.0154; 4 sd either side.
    names = ("lsd_db", "level_diff_db", "band_level_rms_error_db", "shape_correlation")
    flags = {k: [] for k in names}
    bands, peak_f, peak_l = [], [], []
    for i in range(PAIRS):
        sc = score_runs(resonance_run(1000 + 2 * i, n=n_measured),
                        resonance_run(1001 + 2 * i, n=n_simulated, run_id="S"), nperseg=nperseg, confidence=0.95)
        for k in names:
            flags[k].append(bool(sc[f"{k}_significant"]))
        bands.extend(sc.band_level_error_db_significant.values.tolist())
        peak_f.extend(sc.peak_frequency_error_significant.values.tolist())
        peak_l.extend(sc.peak_level_diff_db_significant.values.tolist())
    sd = np.sqrt(0.05 * 0.95 / PAIRS)
    for k in ("lsd_db", "level_diff_db", "band_level_rms_error_db"):
        assert abs(np.mean(flags[k]) - 0.05) < 4 * sd, k
    # per-band flags: bands of one pair are nearly independent (they share at most an edge bin)
    assert abs(np.mean(bands) - 0.05) < 4 * np.sqrt(0.05 * 0.95 / len(bands))
    # conservative ones: the correlation bound uses fewer effective bins than Bartlett's formula would allow, the
    # peak level compares maxima and the peak frequency never goes below one bin; they may alarm less often
    # than 5 %, not more
    for name, values in (("shape_correlation", flags["shape_correlation"]), ("peak_frequency", peak_f),
                         ("peak_level", peak_l)):
        assert np.mean(values) < 0.05 + 4 * np.sqrt(0.05 * 0.95 / len(values)), name
