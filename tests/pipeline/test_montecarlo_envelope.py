"""Uncertainty to spectra (issue 16 item 3): Monte-Carlo PSD envelopes and their coverage of a measured PSD,
and the domain check of ``fivid simulate --law`` (item 2).

Oracles: numpy's own quantiles on known samples; the order statistics of exchangeable samples (a record drawn
like the samples falls inside the type-7 [5 %, 95 %] quantiles of N samples with probability
(N - 1 - 2 floor(0.05 (N - 1))) / (N + 1) when 0.05 (N - 1) is an integer); the multivariate normal's covariance;
and, slow, the acceptance of the issue: a run simulated from the law itself lies inside the envelope in >= 90 %
of the 1/3-octave bands, while one with 3x the amplitude (+9.5 dB) does not.
"""

import json
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from tests.helpers.montecarlo_laws import DOMAIN, uncertain_law, write_uncertain_law

from fivid.cli import main
from fivid.identify.montecarlo import draw_coefficients, law_with_coefficients, monte_carlo_laws, sample_seeds
from fivid.score.envelope import (
    add_envelope_coverage,
    band_levels_of_samples,
    envelope_coverage,
    envelope_dataset,
    psd_quantiles,
    read_envelope,
)
from fivid.signal.welch import welch_psd

ROOT = Path(__file__).resolve().parents[2]
COARSE = str(ROOT / "configs" / "models" / "triboair_coarse.yaml")


def test_quantiles_are_numpys_type_7_on_known_samples():
    """On 0..100 (101 samples) the type-7 quantiles are exactly 5, 50, 95; on random data, numpy's."""
    x = np.arange(101.0)[:, None] * np.ones((1, 3))
    np.testing.assert_array_equal(psd_quantiles(x), [[5.0] * 3, [50.0] * 3, [95.0] * 3])
    rng = np.random.default_rng(3)
    y = rng.lognormal(size=(37, 11))
    np.testing.assert_allclose(psd_quantiles(y), np.quantile(y, [0.05, 0.5, 0.95], axis=0), rtol=0, atol=0)
    with pytest.raises(ValueError, match="at least 2"):
        psd_quantiles(y[:1])


def test_coefficient_draws_have_the_laws_covariance_and_spawned_seeds_differ():
    """20 000 draws: sample mean within 4 standard errors, sample covariance within 4 of its standard errors
    (var of a sample covariance entry (Σ_ii Σ_jj + Σ_ij²)/n); a rank-deficient Σ with a round-off negative
    eigenvalue is accepted; a NaN Σ is not sampled."""
    mean = np.array([1.0, -2.0, 0.5])
    a = np.array([[0.3, 0.0, 0.0], [0.1, 0.2, 0.0], [-0.05, 0.04, 0.1]])
    cov = a @ a.T
    n = 20000
    x, used = draw_coefficients(mean, cov, n, np.random.default_rng(1))
    assert used and x.shape == (n, 3)
    assert np.all(np.abs(x.mean(axis=0) - mean) < 4 * np.sqrt(np.diag(cov) / n))
    se = np.sqrt((np.outer(np.diag(cov), np.diag(cov)) + cov**2) / n)
    assert np.all(np.abs(np.cov(x.T) - cov) < 4 * se)
    singular = np.array([[1.0, 1.0], [1.0, 1.0 - 1e-17]])
    y, used = draw_coefficients([0.0, 0.0], singular, 100, np.random.default_rng(2))
    assert used and np.allclose(y[:, 0], y[:, 1])
    z, used = draw_coefficients(mean, np.full((3, 3), np.nan), 5, np.random.default_rng(3))
    assert not used and np.all(z == mean)
    seeds = sample_seeds(7, 50)
    assert len(set(seeds.tolist())) == 50 and np.array_equal(seeds, sample_seeds(7, 50))


def test_monte_carlo_laws_vary_the_amplitude_only():
    law = uncertain_law()
    draws = monte_carlo_laws(law, 400, seed=5)
    amps = np.array([lw.amplitude(0.01, 1e-6) for lw in draws["laws"]])
    # ln A at V = 10 mm/s, Ra = 1 um: var = s_c^2 + (ln 10)^2 s_v^2 (log_prefactor and velocity exponent)
    sd = np.hypot(0.15, np.log(10.0) * 0.05)
    assert abs(np.std(np.log(amps)) / sd - 1) < 4 / np.sqrt(2 * 400)
    one = draws["laws"][0]
    assert one.mu0 == law.mu0 and np.array_equal(one.shape, law.shape) and one.band == law.band
    assert law_with_coefficients(law, law.amplitude_model.coefficients).sha256 == law.sha256
    with pytest.raises(ValueError, match="perturbed Coulomb"):
        from fivid.friction import CoulombLaw

        monte_carlo_laws(CoulombLaw(0.3), 10)
    with pytest.raises(ValueError, match=">= 2"):
        monte_carlo_laws(law, 1)


def _white_psds(n, seed, *, fs=8192.0, nperseg=256, records=2048):
    """Welch PSDs of n independent Gaussian white-noise records (level 2 sigma^2 / fs, sigma 1 m s-2)."""
    rng = np.random.default_rng(seed)
    t = np.arange(records) / fs
    out = []
    for _ in range(n):
        da = xr.DataArray(rng.standard_normal(records), dims="time", coords={"time": t}, attrs={"units": "m s-2"})
        out.append(welch_psd(da, nperseg=nperseg, fs=fs))
    return out[0]["frequency"].values, np.stack([p.values for p in out])


def test_a_record_drawn_like_the_samples_is_inside_at_the_order_statistics_rate():
    """N = 21 white-noise PSDs make the envelope; 400 further records of the same noise are each inside a band
    with probability (N - 1 - 2) / (N + 1) = 18/22 = 0.818 (type-7 quantiles at 0.05 (N - 1) = 1: the 2nd
    smallest and 2nd largest of 21). Averaged over the 400 records and all bands the observed rate has a standard
    deviation below sqrt(p (1 - p) / 400) = 0.019 (bands and records give at least 400 independent trials): within
    4 of it. The band levels of the envelope are the samples' band levels, their quantiles numpy's."""
    f, samples = _white_psds(21, seed=11)
    env = envelope_dataset(f, samples, "m s-2", attrs={"variable": "acceleration"})
    lo, hi = env["band_lower"].values, env["band_upper"].values
    assert lo.size >= 8
    levels = band_levels_of_samples(f, samples, lo, hi)
    np.testing.assert_allclose(env["band_level_sample"].values, levels)
    np.testing.assert_allclose(env["band_level_p95"].values, np.quantile(levels, 0.95, axis=0))
    np.testing.assert_allclose(env["psd_median"].values, np.median(samples, axis=0))
    _, others = _white_psds(400, seed=12)
    rates = [envelope_coverage(env, lo, hi, lev)["coverage"] / 100 for lev in band_levels_of_samples(f, others, lo, hi)]
    p = 18 / 22
    assert abs(np.mean(rates) - p) < 4 * np.sqrt(p * (1 - p) / 400)
    # 3x the RMS (+9.5 dB) is far outside the spread of a 2048-sample record's band levels
    loud = band_levels_of_samples(f, 9.0 * others[:1], lo, hi)[0]
    assert envelope_coverage(env, lo, hi, loud)["coverage"] == 0.0


def _scores_stub(lo, hi, measured_db, units="m s-2"):
    centre = np.sqrt(lo * hi)
    return xr.Dataset({"band_level_measured_db": ("band_centre", measured_db)},
                      coords={"band_centre": centre, "band_lower": ("band_centre", lo),
                              "band_upper": ("band_centre", hi)},
                      attrs={"variable": "acceleration", "variable_units": units, "frequency_resolution": 32.0})


def test_coverage_flags_and_percent_on_hand_made_bands(tmp_path):
    """Two samples 0 and 10 dB over flat PSDs: p05/p95 = 0.5/9.5 dB; levels 5, 0, 12 dB -> inside, out, out."""
    f = np.arange(0.0, 4097.0, 32.0)
    samples = np.stack([np.ones_like(f), 10.0 * np.ones_like(f)]) / 1000.0  # 1 kHz wide bands: 0 and 10 dB
    env = envelope_dataset(f, samples, "m s-2", band=(500.0, 3500.0), attrs={"variable": "acceleration"})
    lo, hi = np.array([1000.0, 2000.0, 3000.0]), np.array([2000.0, 3000.0, 4000.0])
    out = add_envelope_coverage(_scores_stub(lo, hi, np.array([5.0, 0.0, 12.0])), env, envelope_file="e.nc")
    np.testing.assert_allclose(out["envelope_band_level_p05"], 0.5, atol=1e-9)
    np.testing.assert_allclose(out["envelope_band_level_p95"], 9.5, atol=1e-9)
    assert out["envelope_inside"].values.tolist() == [1, 0, 0]
    assert float(out["envelope_coverage"]) == pytest.approx(100 / 3)
    with pytest.raises(ValueError, match="m s-1"):
        add_envelope_coverage(_scores_stub(lo, hi, np.zeros(3), units="m s-1"), env)
    path = tmp_path / "env.nc"
    env.to_netcdf(path)
    assert read_envelope(path).sizes["sample"] == 2
    with pytest.raises(ValueError, match="not a fivid Monte-Carlo envelope"):
        read_envelope(tmp_path / "env.nc" if False else _not_an_envelope(tmp_path))


def _not_an_envelope(tmp_path):
    p = tmp_path / "other.nc"
    xr.Dataset({"x": ("t", [1.0])}).to_netcdf(p)
    return p


def test_simulate_checks_the_laws_domain_and_strict_exits_2(tmp_path, capsys):
    """Outside the identified domain a warning names the variable and the range; --strict refuses (exit 2)
    before any simulation (--dry-run: nothing integrated); inside: no warning."""
    law = tmp_path / "law.nc"
    write_uncertain_law(law)
    common = ["simulate", COARSE, "--law", str(law), "--roughness", "1 um", "--load", "5 N", "-o",
              str(tmp_path / "x.nc"), "--dry-run"]
    assert main([*common, "--velocity", "40 mm/s"]) == 0
    err = capsys.readouterr().err
    assert "fivid simulate: warning: extrapolation: sliding_velocity = 40 mm/s is outside the identified range " \
           "5 mm/s to 20 mm/s" in err
    assert main([*common, "--velocity", "40 mm/s", "--strict"]) == 2
    err = capsys.readouterr().err
    assert "sliding_velocity = 40 mm/s" in err and "strict" in err
    assert main([*common, "--velocity", "10 mm/s", "--strict"]) == 0  # inside the convex hull
    assert "warning" not in capsys.readouterr().err
    # the default velocity is the model's base velocity (10 mm/s): a load outside the one identified value
    assert main(["simulate", COARSE, "--law", str(law), "--roughness", "1 um", "--load", "8 N", "-o",
                 str(tmp_path / "x.nc"), "--dry-run"]) == 0
    assert "normal_load = 8 N is outside the one value identified, 5 N" in capsys.readouterr().err
    assert main(["simulate", COARSE, "--mu", "0.3", "--samples", "3", "-o", str(tmp_path / "e.nc")]) == 2
    assert DOMAIN.shape == (4, 3)


def test_envelope_cli_end_to_end_small(tmp_path, capsys):
    """3 samples of a short run in this process: the file's provenance, its quantiles from its samples, and
    'fivid score --envelope' in JSON and netCDF (coverage = share of the flags)."""
    law = tmp_path / "law.nc"
    write_uncertain_law(law)
    env_path = tmp_path / "env.nc"
    cond = ["--velocity", "10 mm/s", "--roughness", "1 um", "--load", "5 N", "--duration", "0.012"]
    assert main(["simulate", COARSE, "--law", str(law), *cond, "--samples", "3", "--workers", "0", "--nperseg",
                 "256", "--seed", "4", "--no-progress", "-o", str(env_path), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    env = read_envelope(env_path)
    assert summary["samples"] == 3 and env.attrs["n_samples"] == 3 and env.attrs["seed"] == 4
    assert summary["law_domain"] == {"checked": True, "inside": True, "warnings": []}
    assert env.attrs["law_domain_check"] == "inside the identified domain"
    assert env["sample_seed"].values.tolist() == summary["seeds"] == sample_seeds(4, 3).tolist()
    import hashlib

    assert env.attrs["law_file_sha256"] == hashlib.sha256(law.read_bytes()).hexdigest()
    assert "--samples 3" in env.attrs["history"] and env.attrs["variable"] == "acceleration"
    np.testing.assert_allclose(env["psd_p95"], np.quantile(env["psd_sample"].values, 0.95, axis=0))
    assert np.all(env["psd_p05"] <= env["psd_median"]) and np.all(env["psd_median"] <= env["psd_p95"])
    meas = tmp_path / "meas.nc"
    assert main(["simulate", COARSE, "--law", str(law), *cond, "--seed", "99", "-o", str(meas)]) == 0
    capsys.readouterr()
    steady = tmp_path / "steady.nc"
    from fivid.io import read_run, write_run

    ds = read_run(meas)
    write_run(ds.sel(time=slice(ds.attrs["transient_end"], None)), steady)
    out = tmp_path / "scores.nc"
    assert main(["score", str(steady), str(steady), "--nperseg", "256", "--envelope", str(env_path), "-o", str(out),
                 "--json"]) == 0
    j = json.loads(capsys.readouterr().out)["envelope"]
    flags = [b["inside"] for b in j["bands"]]
    assert j["n_samples"] == 3 and j["inside_count"] == sum(flags)
    assert j["coverage_percent"] == pytest.approx(100 * sum(flags) / len(flags))
    sc = xr.open_dataset(out)
    assert float(sc["envelope_coverage"]) == pytest.approx(j["coverage_percent"])
    assert sc["envelope_inside"].values.tolist() == [int(x) for x in flags]
    assert sc.attrs["envelope_resolution_note"] == "same resolution as the scores"
    assert main(["score", str(steady), str(steady), "--envelope", str(steady)]) == 2  # a run is no envelope


@pytest.mark.slow
def test_a_run_from_the_law_lies_inside_its_envelope(tmp_path, capsys):
    """Acceptance (issue 16 item 3): 40 samples on the dask LocalCluster (2 workers), 0.04 s of steady sliding
    each; a 'measured' run simulated from the law as identified (another seed) lies inside the 5-95 % envelope in
    >= 90 % of the 1/3-octave bands. The same run with 3x the amplitude (+9.5 dB of friction excitation) lies
    outside in most bands: the envelope is not wide enough to hold anything."""
    law_path = tmp_path / "law.nc"
    law = write_uncertain_law(law_path)
    cond = ["--velocity", "10 mm/s", "--roughness", "1 um", "--load", "5 N", "--duration", "0.04"]
    env_path = tmp_path / "env.nc"
    assert main(["simulate", COARSE, "--law", str(law_path), *cond, "--samples", "40", "--workers", "2",
                 "--nperseg", "512", "--no-progress", "-o", str(env_path)]) == 0
    from fivid.friction import law_dataset, write_law
    from fivid.io import read_run, write_run

    loud = tmp_path / "loud.nc"
    write_law(law_dataset(law.scaled(3.0)), loud)
    coverage = {}
    for name, lp in (("law", law_path), ("loud", loud)):
        meas = tmp_path / f"measured_{name}.nc"
        assert main(["simulate", COARSE, "--law", str(lp), *cond, "--seed", "2024", "-o", str(meas)]) == 0
        ds = read_run(meas)
        steady = tmp_path / f"{name}_steady.nc"
        write_run(ds.sel(time=slice(ds.attrs["transient_end"], None)), steady)
        capsys.readouterr()
        assert main(["score", str(steady), str(steady), "--nperseg", "512", "--envelope", str(env_path),
                     "--json"]) == 0
        coverage[name] = json.loads(capsys.readouterr().out)["envelope"]
    print("coverage", {k: (v["coverage_percent"], v["inside_count"], len(v["bands"])) for k, v in coverage.items()})
    assert coverage["law"]["coverage_percent"] >= 90.0
    assert coverage["loud"]["coverage_percent"] < 50.0


def test_pipeline_plans_one_envelope_per_condition_when_samples_is_set(tmp_path):
    """``simulate.samples`` of the run configuration (read from its parsed content, default 0: off) adds one
    envelope task per condition beside the seeds' simulations; the score stage still sees only the seeds; a bad
    value names the key."""
    from types import SimpleNamespace

    from fivid.errors import ConfigError
    from fivid.pipeline.stages import Simulate, envelope_samples

    def config(raw):
        return SimpleNamespace(raw=raw, path=tmp_path / "run.yaml", model=COARSE, seeds=(0, 1), duration=0.3,
                               sample_rate=51200.0, nperseg=2048, settle=0.1)

    conds = {"v10-fn5-ra1": {"sliding_velocity": 0.01, "normal_load": 5.0, "roughness_ra": 1e-6}}
    ctx = SimpleNamespace(config=config({"simulate": {"samples": 20}}), digests={"identify": {"law": {"law": "0"}}},
                          data={"conditions": conds}, out=tmp_path)
    tasks = Simulate().plan(ctx)
    names = sorted(t.name for t in tasks)
    assert names == ["v10-fn5-ra1-envelope", "v10-fn5-ra1-seed0", "v10-fn5-ra1-seed1"]
    env = next(t for t in tasks if t.name.endswith("envelope"))
    assert env.params["samples"] == 20 and env.params["nperseg"] == 2048 and "envelope" in env.outputs
    Simulate().collect(ctx, tasks)
    assert ctx.data["envelopes"] == {"v10-fn5-ra1": env.outputs["envelope"]}
    assert len(ctx.data["sims"]["v10-fn5-ra1"]) == 2
    ctx.config = config({"simulate": {"duration": "0.3 s"}})
    assert envelope_samples(ctx.config) == 0 and len(Simulate().plan(ctx)) == 2
    for bad in (1, -3, 2.5, True, "20"):
        with pytest.raises(ConfigError, match="simulate.samples"):
            envelope_samples(config({"simulate": {"samples": bad}}))


def test_envelope_file_passes_the_cf_checker(tmp_path, request):
    """cfchecks: no errors; the one warning allowed is the string coordinate of the coefficient names (the
    law file has the same)."""
    from tests.helpers import cf_checks

    from fivid.storage import write_netcdf

    table = cf_checks.table_or_skip(request.config)
    f, samples = _white_psds(5, seed=1)
    env = envelope_dataset(f, samples, "m s-2", seeds=sample_seeds(0, 5), coefficients=np.zeros((5, 2)),
                           coefficient_names=["log_prefactor", "velocity_exponent"], amplitudes=np.ones(5),
                           attrs={"variable": "acceleration"})
    path = write_netcdf(env, tmp_path / "env.nc")
    errors, warnings, out = cf_checks.cf_check(path, table)
    assert errors == 0, out
    assert warnings <= 1, out
