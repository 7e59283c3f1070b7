"""Model updating of mu and k_d from FRFs at several normal loads; the FRF CSV reader."""

from pathlib import Path

import numpy as np
import pytest

from fivid.damper.model import load_damper_model
from fivid.damper.updating import model_amplitudes, update_contact_parameters
from fivid.errors import DataQualityError, SchemaError, UnitError
from fivid.io.frf import read_frf_csv

CONFIGS = Path(__file__).resolve().parents[2] / "configs" / "dampers"


def _write_frf(path, f, amp, normal_load, unit="mm", phase=None):
    lines = ["# fivid-frf-csv: 1", "# synthetic: Model 1 HBM amplitudes x lognormal noise (tests/damper/test_damper_updating.py)",
             f"# normal_load: {normal_load} N", "# excitation_amplitude: 2 N"]
    scale = {"mm": 1e3, "m": 1.0, "m/N": 0.5}[unit]
    if phase is None:
        lines.append(f"frequency [Hz],amplitude [{unit}]")
        lines += [f"{a:.6f},{b * scale:.9e}" for a, b in zip(f, amp)]
    else:
        lines.append(f"frequency [Hz],amplitude [{unit}],phase [deg]")
        lines += [f"{a:.6f},{b * scale:.9e},{c:.6f}" for a, b, c in zip(f, amp, phase)]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize("start", [(0.55, 1e6), pytest.param((0.66, 3e7), marks=pytest.mark.slow)])
def test_recovers_model1(tmp_path, start):
    """Synthetic FRFs from Model 1 (mu 0.45, k_d 3.9e5 N/m) at 2, 10, 40 N with 2 % lognormal noise;
    the update starts elsewhere, in the slow variant from Model 2's literature values (0.66, 3e7 N/m)."""
    model = load_damper_model(CONFIGS / "seed004_model1.yaml")
    rng = np.random.default_rng(8)
    f = np.linspace(30, 120, 20)
    meas = []
    for i, fn in enumerate([2.0, 10.0, 40.0]):
        amp = model_amplitudes(model, fn, f) * np.exp(0.02 * rng.normal(size=f.size))
        meas.append(read_frf_csv(_write_frf(tmp_path / f"frf{i}.csv", f, amp, fn, unit=["mm", "m", "m/N"][i])))
    assert meas[2].kind == "receptance" and meas[0].kind == "displacement"
    upd = update_contact_parameters(model, meas, initial=start)
    # independent lognormal noise: the least-squares standard errors hold; 4 sigma ~ 6e-5 miss rate
    assert abs(upd.friction_coefficient - 0.45) <= 4 * upd.friction_coefficient_stderr
    assert abs(upd.contact_stiffness - 3.9e5) <= 4 * upd.contact_stiffness_stderr
    # the residual RMS estimates the noise level: 60 points -> relative sd ~ 1/sqrt(2 x 58) ~ 9 %, 3 sd
    assert upd.rms_log_residual == pytest.approx(0.02, rel=0.3)
    assert upd.n_points == 60


def test_frf_reader_layouts(tmp_path):
    f = np.array([10.0, 20.0, 30.0])
    a = np.array([1e-5, 2e-5, 3e-5])
    m = read_frf_csv(_write_frf(tmp_path / "a.csv", f, a, 2, phase=[0.0, 90.0, 180.0]))
    assert np.allclose(m.response, a * np.exp(1j * np.deg2rad([0, 90, 180])), rtol=1e-8)
    assert m.normal_load == 2.0 and m.excitation_amplitude == 2.0
    p = tmp_path / "b.csv"
    p.write_text("frequency [Hz],real [um],imag [um]\n10,1,2\n20,3,4\n")
    assert np.allclose(read_frf_csv(p).response, np.array([1 + 2j, 3 + 4j]) * 1e-6)


@pytest.mark.parametrize("text, error, match", [
    ("frequency [Hz],amplitude [N]\n10,1\n20,2\n", UnitError, "neither a displacement"),
    ("frequency [Hz],amplitude [m]\n20,1\n10,2\n", DataQualityError, "strictly increasing"),
    ("frequency [Hz],level [dB]\n10,1\n20,2\n", SchemaError, "amplitude"),
])
def test_frf_reader_errors(tmp_path, text, error, match):
    p = tmp_path / "bad.csv"
    p.write_text(text)
    with pytest.raises(error, match=match):
        read_frf_csv(p)
