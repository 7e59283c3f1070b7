"""Jenkins identification from hysteresis loops: synthetic recovery, real damper loops, bad input."""

import json

import numpy as np
import pytest

from fivid.damper.loop_fit import fit_jenkins_loop
from fivid.errors import DataQualityError, SchemaError, UnitError
from fivid.friction.jenkins import jenkins_energy_per_cycle, jenkins_force
from fivid.io.hysteresis import read_hysteresis
from fivid.verify import evaluate_case, select_cases
from fivid.verify.cases.friction_jenkins import real_loop_fits



def synthetic_loop(k=2e6, fs=4000.0, amplitude=0.025, cycles=6, fs_rate=1024, noise=5.0, seed=0):
    """Synthetic (labelled): a ramped 1 Hz sine imposed on a Jenkins element, plus white force noise
    (a noiseless slip plateau is a run of identical samples, which the quality check calls clipping)."""
    t = np.arange(0, cycles + 2, 1 / fs_rate)
    env = np.clip(t, 0, 1) * np.clip(cycles + 2 - t, 0, 1)
    x = amplitude * env * np.sin(2 * np.pi * t)
    f = jenkins_force(x, k, fs) + noise * np.random.default_rng(seed).normal(size=t.size)
    return t, x, f


def write_json(path, t, x, f, *, x_units="m", f_units="N"):
    rows = np.column_stack([t, x, f]).tolist()
    doc = {"dt": float(t[1] - t[0]), "time units": "s", "displacement units": x_units, "friction force units": f_units,
           "data": rows}
    path.write_text(json.dumps(doc))
    return path


def test_recovers_synthetic_parameters_within_their_errors(tmp_path):
    k, fs, sigma = 2e6, 4000.0, 50.0
    t, x, f = synthetic_loop(k, fs, noise=sigma)
    rec = read_hysteresis(write_json(tmp_path / "syn.json", t, x, f))
    fit = fit_jenkins_loop(rec.displacement, rec.force)
    # independent noise: the least-squares standard errors are valid; 4 sigma is a 6e-5 two-sided miss rate
    assert abs(fit.slip_force - fs) <= 4 * fit.slip_force_stderr
    assert abs(fit.stiffness - k) <= 4 * fit.stiffness_stderr
    assert fit.rms_residual == pytest.approx(sigma, rel=0.1)  # ~7000 samples: rel. sd of the RMS ~ 1/sqrt(2n)
    # energy per cycle: the model loop reproduces the closed form cycle by cycle
    assert np.allclose(fit.energy_per_cycle_model, jenkins_energy_per_cycle(fit.cycle_amplitudes, fit.stiffness, fit.slip_force),
                       rtol=2 * np.pi / 1024 * 2)  # trapezoid error <= 2 F_s |dx|max per loop, relative 2 pi/n x 2
    assert fit.energy_per_cycle_measured.size == 6


def test_csv_reader_with_units(tmp_path):
    t, x, f = synthetic_loop()
    p = tmp_path / "loop.csv"
    body = "\n".join(f"{a:.6f},{b * 1e3:.9f},{c / 1e3:.9f}" for a, b, c in zip(t, x, f))
    p.write_text("# fivid-hysteresis-csv: 1\n# source: synthetic\ntime [s],displacement [mm],force [kN]\n" + body + "\n")
    rec = read_hysteresis(p)
    assert np.allclose(rec.displacement, x, atol=1e-12)
    assert np.allclose(rec.force, f, atol=1e-6)
    assert rec.metadata["source"].startswith("loop.csv sha256:")


def test_real_damper_loops(real_data):
    """Case jenkins_real_loops (the fitted element's energy per cycle within 10 % of each measured loop's, the
    basis there). Further: a Jenkins element explains most of the force (R² > 0.9: backlash ringing and rounded
    corners remain); the slip force ~ the force plateau (half the 5-95 % force range); friction grows with band
    tension 20 -> 35 -> 80 lb."""
    (case,) = select_cases(["jenkins_real_loops"])
    result = evaluate_case(case, False, real_data / "friction_damper")
    assert result.status == "passed", result
    fits = real_loop_fits(real_data / "friction_damper")
    for name, rec, fit in fits:
        assert rec.metadata["original_units"]["displacement units"] == "in"
        assert fit.summary()["r_squared"] > 0.9
        assert abs(fit.summary()["energy_relative_error"]) < case.compute(False, real_data / "friction_damper").tolerance
        plateau = 0.5 * (np.percentile(rec.force, 95) - np.percentile(rec.force, 5))
        assert 0.7 * plateau < fit.slip_force < 1.1 * plateau
    slip = [f.slip_force for _, _, f in fits]
    assert slip[0] < slip[1] < slip[2]


def test_too_few_cycles(tmp_path):
    t, x, f = synthetic_loop(cycles=1)
    with pytest.raises(DataQualityError, match="full displacement cycle"):
        fit_jenkins_loop(x, f)


def test_drift(tmp_path):
    t, x, f = synthetic_loop()
    with pytest.raises(DataQualityError, match="drifts"):
        fit_jenkins_loop(x + 0.01 * t, f)


@pytest.mark.parametrize("which", ["displacement", "force"])
def test_clipped(which):
    t, x, f = synthetic_loop()
    if which == "displacement":
        x = np.clip(x, -0.8 * x.max(), 0.8 * x.max())
    else:
        f = np.clip(f, -0.9 * f.max(), 0.9 * f.max())
    with pytest.raises(DataQualityError, match=f"{which} looks clipped"):
        fit_jenkins_loop(x, f)


def test_unknown_units(tmp_path):
    t, x, f = synthetic_loop()
    p = write_json(tmp_path / "u.json", t, x, f, x_units="smoots_per_fortnight")
    with pytest.raises(UnitError) as err:
        read_hysteresis(p)
    assert "u.json" in str(err.value) and "displacement" in str(err.value)
    p = write_json(tmp_path / "v.json", t, x, f, f_units="m")
    with pytest.raises(UnitError, match="'N'"):
        read_hysteresis(p)
    p.write_text(json.dumps({"data": [[0, 0, 0]]}))
    with pytest.raises(UnitError, match="time units"):
        read_hysteresis(p)


@pytest.mark.parametrize("text, error, match, line", [
    ("time,displacement [m],force [N]\n0,0,0\n", UnitError, "has no unit", 1),
    ("time [s],force [N]\n0,0\n", SchemaError, "missing columns", 1),
    ("time [s],displacement [m],force [N]\n0,0,0\n1,x,0\n", SchemaError, "cannot read 'x' as a number", 3),
    ("time [s],displacement [m],force [N]\n0,0,0\n\n1,0\n", SchemaError, "the row has 2 field", 4),
    # a repeated column would silently replace the first one
    ("time [s],displacement [m],force [N],force [kN]\n0,0,0,0\n", SchemaError, "appears twice", 1),
    ("time [s],displacement [m],force [N],friction_force [N]\n0,0,0,0\n", SchemaError, "keep one", 1),
])
def test_csv_without_units_or_columns(tmp_path, text, error, match, line):
    p = tmp_path / "a.csv"
    p.write_text(text)
    with pytest.raises(error, match=match) as err:
        read_hysteresis(p)
    assert err.value.line == line


@pytest.mark.parametrize("name", ["a.csv", "a.json"])
def test_non_utf8_file_is_a_schema_error(tmp_path, name):
    p = tmp_path / name
    p.write_bytes(b"time [s],displacement [m],force [N]\n0,0,\xff\n")
    with pytest.raises(SchemaError, match="not UTF-8 text .byte 0xff at offset 40") as err:
        read_hysteresis(p)
    assert name in str(err.value)


def test_csv_is_read_with_the_rig_csv_machinery(tmp_path):
    """Issue 19: the hysteresis CSV is parsed as a rig CSV is (BOM, CRLF, blank and quoted fields, a bad value
    named by the file's own line counting blank lines), not split by hand."""
    t, x, f = synthetic_loop()
    rows = [f'{a:.6f},"{b * 1e3:.9f}",{c:.9f}' for a, b, c in zip(t, x, f)]
    rows.insert(5, "")
    p = tmp_path / "loop.csv"
    p.write_bytes(("\ufeff# source: bench\r\n" + '"time [s]","displacement [mm]",force [N]\r\n'
                   + "\r\n".join(rows) + "\r\n").encode("utf-8"))
    rec = read_hysteresis(p)
    # the written decimals, parsed back exactly (pyarrow and Python both round correctly)
    assert np.array_equal(rec.force, [float(f"{c:.9f}") for c in f])
    assert np.array_equal(rec.time, [float(f"{a:.6f}") for a in t])
    assert np.allclose(rec.displacement, x, rtol=0, atol=1e-12)  # 9 decimals of mm: 5e-13 m rounding
    assert rec.metadata["source"].startswith("loop.csv sha256:")
    rows[40] = "x" + rows[40]
    p.write_text("time [s],displacement [mm],force [N]\n" + "\n".join(rows) + "\n")
    with pytest.raises(SchemaError, match="cannot read") as err:
        read_hysteresis(p)
    assert err.value.line == 1 + 41 and err.value.column == "time"  # header, then rows[0..40] with one blank line
