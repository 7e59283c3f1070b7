"""``fivid identify`` end to end on SYNTHETIC runs written as netCDF files."""

import json

import numpy as np
import pytest
import yaml
from tests.helpers.synthetic_friction_runs import synthetic_run, true_law

from fivid.cli import main
from fivid.friction import load_law
from fivid.io import write_run


def _modes_psd(f):
    """SYNTHETIC acceleration PSD with two lightly damped modes (1.2 kHz, ζ 1 %; 3.1 kHz, ζ 0.8 %)."""
    out = np.full_like(f, 1e-8)
    for fn, z in ((1200.0, 0.01), (3100.0, 0.008)):
        out += 1e6 * (f / fn) ** 4 / ((fn**2 - f**2) ** 2 + (2 * z * fn * f) ** 2)
    return out


@pytest.fixture(scope="module")
def run_files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("runs")
    law = true_law()
    paths = []
    for i, (v, ra) in enumerate(((0.005, 0.4e-6), (0.02, 0.4e-6), (0.005, 1.6e-6), (0.02, 1.6e-6), (0.01, 1.6e-6))):
        ds = synthetic_run(law, velocity=v, roughness=ra, normal_load=5.0, seed=i, run_id=f"C{i}", duration=2.4,
                           acceleration_psd=_modes_psd)
        paths.append(str(write_run(ds, folder / f"C{i}.nc")))
    return paths


def test_identify_writes_a_law_and_json(run_files, tmp_path, capsys):
    out = tmp_path / "law.nc"
    damping = tmp_path / "damping.yaml"
    status = main(["identify", *run_files, "-o", str(out), "--band", "100", "5000", "--tare", "0", "0.5",
                   "--json", "--damping", str(damping), "--damping-band", "500", "5000", "--damping-peaks", "2"])
    assert status == 0
    report = json.loads(capsys.readouterr().out)
    assert report["mu0"] == pytest.approx(0.3, abs=1e-3)
    assert len(report["mu0_ci"]) == 2
    assert {"form", "coefficients", "stderr"} <= set(report["amplitude_model"])
    assert [r["run_id"] for r in report["runs"]] == [f"C{i}" for i in range(5)]
    assert all(r["used"] for r in report["runs"])
    law = load_law(out)
    assert law.sha256 == report["law_sha256"]
    frag = yaml.safe_load(damping.read_text())
    assert set(frag["damping"]) == {"alpha", "beta"}
    peaks = report["damping"]["peaks"]
    assert [round(p["frequency_fit"], -2) for p in peaks] == [1200.0, 3100.0]


def test_identify_bad_input_exits_2(run_files, tmp_path, capsys):
    out = tmp_path / "law.nc"
    assert main(["identify", *run_files, "-o", str(out), "--band", "100", "20000"]) == 2
    assert "Nyquist" in capsys.readouterr().err
    out.write_text("x")
    assert main(["identify", *run_files, "-o", str(out)]) == 2
    assert "exists" in capsys.readouterr().err
    assert main(["identify", str(tmp_path / "missing.nc"), "-o", str(tmp_path / "l.nc")]) == 2
    assert "no such file" in capsys.readouterr().err


def test_single_run_prints_the_per_run_result(run_files, tmp_path, capsys):
    out = tmp_path / "law1.nc"
    assert main(["identify", run_files[0], "-o", str(out), "--band", "100", "5000"]) == 0
    text = capsys.readouterr().out
    assert "no amplitude law across runs can be fitted" in text
    assert "run C0" in text and out.exists()


def test_inverse_with_an_unknown_run_is_bad_input(run_files, tmp_path, capsys, root):
    model = root / "configs" / "models" / "triboair_coarse.yaml"
    status = main(["identify", *run_files, "-o", str(tmp_path / "l.nc"), "--band", "100", "5000",
                   "--inverse", str(model), "--inverse-run", "NOPE"])
    assert status == 2
    assert "--inverse-run NOPE: no such run" in capsys.readouterr().err


@pytest.mark.slow
def test_law_file_drives_fivid_simulate(run_files, tmp_path, root):
    """Done-when of issue 6: 'fivid identify' writes a law file that 'fivid simulate --law' uses."""
    import xarray as xr

    law_path = tmp_path / "law.nc"
    assert main(["identify", *run_files, "-o", str(law_path), "--band", "100", "5000", "--tare", "0", "0.5"]) == 0
    sim = tmp_path / "sim.nc"
    model = root / "configs" / "models" / "triboair_coarse.yaml"
    status = main(["simulate", str(model), "--law", str(law_path), "--velocity", "10 mm/s", "--load", "5 N",
                   "--roughness", "0.4 um", "--duration", "0.02 s", "-o", str(sim)])
    assert status == 0
    with xr.open_dataset(sim) as ds:
        assert load_law(law_path).sha256 in str(ds.attrs)
