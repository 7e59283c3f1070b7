"""Bad inputs of issue 32 ("Bad inputs that still get through"): each ends in one line naming the file, line,
key or value and what is allowed, exit 2, no traceback, nothing half-written."""

import pytest
from cli_helpers import fails
from ingest_helpers import GOOD_META, write_rig

from fivid.cli import main





# --- ingest -----------------------------------------------------------------------------------------


@pytest.mark.parametrize("rate", ["0 Hz", "1e-320 Hz"])
def test_zero_sample_rate_does_not_stop_the_batch(tmp_path, capsys, rate):
    """A file with sample_rate 0 Hz (a ZeroDivisionError before) is reported; the good file is written."""
    bad = write_rig(tmp_path / "bad.csv", meta={**GOOD_META, "run_id": "R009"}, extra_meta=[f"# sample_rate: {rate}"])
    good = write_rig(tmp_path / "good.csv")
    out = tmp_path / "out"
    err = fails(capsys, ["ingest", str(bad), str(good), "-o", str(out)])
    assert f"{bad}:7: key 'sample_rate'" in err and "1 file(s) written, 1 rejected" in err
    assert sorted(p.name for p in out.iterdir()) == ["R001.nc"]


def test_allow_implausible_is_recorded_in_the_file(tmp_path, capsys):
    from fivid.io import read_run

    path = write_rig(tmp_path / "kn.csv", meta={**GOOD_META, "normal_load": "5 kN"})
    out = tmp_path / "out"
    err = fails(capsys, ["ingest", str(path), "-o", str(out)])
    assert "normal_force" in err and "--allow-implausible" in err and not out.joinpath("R001.nc").exists()
    assert main(["ingest", str(path), "-o", str(out), "--allow-implausible"]) == 0
    ds = read_run(out / "R001.nc")
    assert ds.attrs["allow_implausible"] == "yes"
    assert "allowed (--allow-implausible): normal_force: " in ds.attrs["quality_report"]
