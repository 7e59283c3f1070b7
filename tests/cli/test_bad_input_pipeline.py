"""Bad inputs of issue 18 (A4-A6, A8) refused before any work: memory of a simulation, a dask scheduler
address, a band above the Nyquist frequency of the configured sample rate, and config errors with the
line of the offending key."""

import socket
from pathlib import Path

import pytest

from fivid.cli import main

ROOT = Path(__file__).resolve().parents[2]
COARSE = ROOT / "configs" / "models" / "triboair_coarse.yaml"
RECIPE = ROOT / "pipelines" / "calibration.yaml"


from tests.helpers.cli import fails as _fails  # noqa: E402  (run the CLI, expect exit 2 and no traceback)


# --- A4: memory of a simulation --------------------------------------------------------------------


def test_simulate_one_year_is_refused_before_work(tmp_path, capsys):
    out = tmp_path / "sim.nc"
    err = _fails(capsys, ["simulate", str(COARSE), "--mu", "0.3", "--duration", "1 year", "-o", str(out), "--dry-run"])
    assert "--duration" in err and "GiB" in err and "available" in err and "steps" in err
    assert not out.exists()


def test_simulate_refused_when_the_estimate_exceeds_available_memory(tmp_path, capsys, monkeypatch):
    from fivid.execution import resources

    monkeypatch.setattr(resources, "available_memory", lambda: (1 << 20, "test"))  # 1 MiB
    out = tmp_path / "sim.nc"
    err = _fails(capsys, ["simulate", str(COARSE), "--mu", "0.3", "--duration", "0.05 s", "-o", str(out)])
    assert "1 MiB available" in err
    assert not out.exists()


def test_simulate_dry_run_prints_the_estimate(tmp_path, capsys):
    out = tmp_path / "sim.nc"
    assert main(["simulate", str(COARSE), "--mu", "0.3", "--duration", "0.05 s", "-o", str(out), "--dry-run"]) == 0
    text = capsys.readouterr().out
    assert "steps" in text and "memory" in text
    assert not out.exists()


def test_memory_estimate_counts_the_records():
    from fivid.fe import load_model
    from fivid.execution.resources import simulation_memory

    model = load_model(COARSE)
    small = simulation_memory(model, duration=0.1, sample_rate=51200.0)
    large = simulation_memory(model, duration=1.1, sample_rate=51200.0)
    # records grow with the number of output samples: 1 s more at 51.2 kHz, oversampled 4 times, of at
    # least the kernel's 10 record columns (8 bytes each)
    assert large.bytes - small.bytes >= 51200 * 4 * 10 * 8
    assert large.output_samples - small.output_samples == pytest.approx(51200, abs=2)


def test_huge_mesh_is_exit_2(tmp_path, capsys):
    text = COARSE.read_text().replace("divisions: [50, 5]", "divisions: [5000000, 500000]")
    model = tmp_path / "huge.yaml"
    model.write_text(text)
    err = _fails(capsys, ["simulate", str(model), "--mu", "0.3", "-o", str(tmp_path / "sim.nc")])
    assert str(model) in err and "memory" in err and "divisions" in err


# --- A5: dask scheduler address --------------------------------------------------------------------


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.parametrize("address, words", [
    ("notaurl", ["'notaurl'", "tcp://HOST:PORT"]),
    ("tcp://localhost", ["port"]),
    ("http://127.0.0.1:8786", ["'http'", "tcp"]),
])
def test_scheduler_address_form(tmp_path, capsys, address, words):
    err = _fails(capsys, ["run", str(RECIPE), "-c", str(ROOT / "configs/runs/sample.yaml"), "-o", str(tmp_path / "o"),
                          "--scheduler", address, "--no-progress"])
    assert "--scheduler" in err
    for w in words:
        assert w in err
    assert not (tmp_path / "o").exists()


def test_scheduler_not_reachable(tmp_path, capsys):
    address = f"tcp://127.0.0.1:{_free_port()}"
    err = _fails(capsys, ["run", str(RECIPE), "-c", str(ROOT / "configs/runs/sample.yaml"), "-o", str(tmp_path / "o"),
                          "--scheduler", address, "--no-progress"])
    assert address in err and "dask scheduler" in err
    assert not (tmp_path / "o").exists()


def test_scheduler_check_accepts_a_listening_port():
    from fivid.execution.cluster import check_scheduler_address

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        address = f"tcp://127.0.0.1:{s.getsockname()[1]}"
        assert check_scheduler_address(address) == address


# --- A6: a band above the Nyquist frequency of the input files (config-only cases: test_pipeline_config.py)


@pytest.mark.parametrize("key, band", [("analysis.band", "band: [800 Hz, 8 kHz]"),
                                       ("identify.band", "band: [100 Hz, 8 kHz]")])
def test_band_above_the_nyquist_frequency_of_the_input_files(tmp_path, capsys, key, band):
    """The sample runs are at 51.2 kHz: a 30 kHz band is refused by the plan, before ingest or simulation."""
    text = (ROOT / "configs/runs/sample.yaml").read_text()
    assert band in text
    text = text.replace(band, band.split(",")[0] + ", 30 kHz]")
    text = text.replace("sample_rate: 51.2 kHz", "sample_rate: 102.4 kHz")
    text = text.replace("../../sample_data/twin", str(ROOT / "sample_data/twin"))
    text = text.replace("model: ../models/triboair.yaml", f"model: {COARSE}")  # refused before any simulation
    text = text.replace("../models/triboair.yaml", str(ROOT / "configs/models/triboair.yaml"))
    config = tmp_path / "run.yaml"
    config.write_text(text)
    err = _fails(capsys, ["run", str(RECIPE), "-c", str(config), "-o", str(tmp_path / "o"), "--no-progress"])
    assert f"{config}:" in err and key in err and "25600 Hz" in err and "T01_" in err
    assert not (tmp_path / "o").exists()
