"""The plan (recipe + run config) is validated whole, with file and key path, before any work."""

import textwrap

import pytest

from fivid.errors import ConfigError
from fivid.pipeline.config import load_recipe, load_run_config


def _write(path, text):
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path


@pytest.fixture
def folder(tmp_path):
    data = tmp_path / "data"
    data.mkdir()
    (data / "R1.csv").write_text("x\n")
    (tmp_path / "model.yaml").write_text("name: m\n")
    return tmp_path


def _config(folder, extra=""):
    return _write(folder / "run.yaml", f"""\
        fivid-run: 1
        inputs: {{folder: data}}
        model: model.yaml
        output: out
        analysis: {{band: [500 Hz, 20 kHz], nperseg: 1024}}
        simulate: {{duration: 0.1 s, sample_rate: 51.2 kHz, seeds: 3}}
        thresholds: {{lsd_db: {{max: 6}}, shape_correlation: {{min: 0.5}}}}
        """ + textwrap.dedent(extra))


def test_good_config_in_si_units_with_paths_relative_to_the_file(folder):
    cfg = load_run_config(_config(folder))
    assert cfg.band == (500.0, 20000.0)
    assert cfg.duration == pytest.approx(0.1) and cfg.sample_rate == pytest.approx(51200.0)
    assert cfg.seeds == (0, 1, 2)
    assert [f.name for f in cfg.input_files] == ["R1.csv"]
    assert cfg.output == folder / "out" and cfg.model == folder / "model.yaml"
    assert cfg.thresholds[0].passes(5.9) and not cfg.thresholds[0].passes(6.1)
    assert cfg.thresholds[1].passes(0.5) and not cfg.thresholds[1].passes(float("nan"))


@pytest.mark.parametrize("bad, key", [
    ("simulate: {duration: 0.1 m}\n", "simulate.duration"),
    ("simulate: {duration: -1 s}\n", "simulate.duration"),
    ("analysis: {band: [20 kHz, 500 Hz]}\n", "analysis.band"),
    ("analysis: {nperseg: 12}\n", "analysis.nperseg"),
    ("thresholds: {lsd_db: {min: 3}}\n", "thresholds.lsd_db"),
    ("thresholds: {lsd: {max: 3}}\n", "thresholds.lsd"),
    ("simulate: {seeds: [1, 1]}\n", "simulate.seeds"),
    ("simulat: {}\n", "simulat"),
    ("inputs: {folder: nowhere}\n", "inputs.folder"),
    ("inputs: {folder: data, pattern: '*.txt'}\n", "inputs.pattern"),
    ("model: missing.yaml\n", "model"),
])
def test_bad_values_name_file_and_key(folder, bad, key):
    base = _config(folder).read_text()
    top = bad.split(":")[0]
    lines = [ln for ln in base.splitlines() if not ln.startswith(top + ":")]
    path = _write(folder / "bad.yaml", "\n".join(lines) + "\n" + bad)
    with pytest.raises(ConfigError) as err:
        load_run_config(path)
    assert err.value.key == key, str(err.value)
    assert str(path) in str(err.value)


def test_every_problem_is_reported_at_once(folder):
    path = _write(folder / "bad.yaml", """\
        inputs: {folder: data}
        model: model.yaml
        output: out
        simulate: {duration: 2 kg, seeds: 0}
        """)
    with pytest.raises(ConfigError) as err:
        load_run_config(path)
    assert "simulate.seeds" in str(err.value) and err.value.key == "simulate.duration"


@pytest.mark.parametrize("stages, key, words", [
    ("[identify, ingest]", "stages[0]", "needs ingest"),
    ("[ingest, fit]", "stages[1]", "unknown stage"),
    ("[ingest, ingest]", "stages[1]", "twice"),
])
def test_recipe_order_and_names_are_checked(tmp_path, stages, key, words):
    path = _write(tmp_path / "p.yaml", f"fivid-pipeline: 1\nstages: {stages}\n")
    with pytest.raises(ConfigError) as err:
        load_recipe(path)
    assert err.value.key == key and words in str(err.value)


def test_shipped_recipe_is_valid(root):
    name, stages, _, _ = load_recipe(root / "pipelines" / "calibration.yaml")
    assert stages[0] == "ingest" and stages[-1] == "report" and name == "calibration"


def test_invalid_yaml_names_line(tmp_path):
    path = _write(tmp_path / "p.yaml", "stages: [ingest\nname: x\n")
    with pytest.raises(ConfigError) as err:
        load_recipe(path)
    assert err.value.line is not None
    # the CLI prints an error in one line: the parser's problem, not its multi-line excerpt of the file
    assert "\n" not in str(err.value) and "column" in str(err.value)


def test_output_that_is_a_file_is_a_config_error(folder, tmp_path):
    # the output must be a folder: a file there made the run fail in mkdir with a traceback
    (tmp_path / "taken").write_text("")
    with pytest.raises(ConfigError, match="is not a folder") as err:
        load_run_config(_config(folder), output=tmp_path / "taken")
    assert err.value.key == "output"


# --- issue 18: a band above the simulated Nyquist frequency, and the line of every offending key -----


def test_band_above_the_simulated_nyquist_frequency(folder):
    path = _config(folder, "simulate: {duration: 0.1 s, sample_rate: 25.6 kHz}\n")
    with pytest.raises(ConfigError) as info:
        load_run_config(path)
    err = info.value
    assert err.file == str(path) and err.key == "analysis.band" and err.line == 5
    assert "12800 Hz" in err.message and "simulate.sample_rate" in err.message


@pytest.mark.parametrize("extra, key, line", [
    ("thresholds:\n  lsd_db: {max: 4}\n  lsd: {max: 3}\n", "thresholds.lsd", 10),
    ("modal:\n  n_modes: 0\n", "modal.n_modes", 9),
    ("identify:\n  tolerance: 2\n", "identify.tolerance", 9),
    ("simulat: {}\n", "simulat", 8),
    ("identify:\n  band: [100 Hz, 2 kHz]\n  min_normal_force: 3 m\n", "identify.min_normal_force", 10),
])
def test_config_errors_carry_the_line(folder, extra, key, line):
    path = _config(folder)
    path.write_text(path.read_text() + extra)  # (_config dedents the whole text: multi-line extras would not parse)
    with pytest.raises(ConfigError) as info:
        load_run_config(path)
    assert info.value.key == key and info.value.line == line
    assert str(info.value).startswith(f"{path}:{line}: key {key!r}")


def test_recipe_errors_carry_the_line(tmp_path):
    path = _write(tmp_path / "recipe.yaml", "fivid-pipeline: 1\nname: x\nstages:\n  - ingest\n  - identfy\n")
    with pytest.raises(ConfigError) as info:
        load_recipe(path)
    assert info.value.key == "stages[1]" and info.value.line == 5
