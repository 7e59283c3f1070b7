"""ingest_files and ``fivid ingest``: partial success, exit codes, one stderr line per rejection,
duplicate run_id, existing outputs, unwritable output folders, nothing left by rejected or killed runs."""

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest
from tests.helpers.ingest import GOOD_META, STANDARD_GRAVITY, data_line, rig_rows, with_field, write_rig

from fivid.cli import main
from fivid.errors import FividError
from fivid.io import ingest_files, read_run

ROOT = Path(__file__).resolve().parents[2]


def _good(folder: Path, run_id: str, name: str | None = None) -> Path:
    return write_rig(folder / (name or f"{run_id}.csv"), meta=dict(GOOD_META, run_id=run_id))


def _bad(folder: Path, name: str = "bad.csv") -> Path:
    rows = rig_rows()
    rows[5] = with_field(rows[5], 2, "oops")
    return write_rig(folder / name, meta=dict(GOOD_META, run_id="BAD"), rows=rows)


def _nc_and_tmp(outdir: Path):
    return sorted(p.name for p in outdir.iterdir())


def test_valid_files_are_written_when_others_are_bad(tmp_path):
    a, bad, b = _good(tmp_path, "A1"), _bad(tmp_path), _good(tmp_path, "B2")
    out = tmp_path / "out" / "runs"  # created
    result = ingest_files([a, bad, b], out)
    assert result.written == [out / "A1.nc", out / "B2.nc"]
    assert [r.path for r in result.rejected] == [bad] and not result.ok
    assert _nc_and_tmp(out) == ["A1.nc", "B2.nc"]  # nothing for the rejected file, no temporary files
    assert result.rejected[0].error.line == data_line(5)
    ds = read_run(out / "A1.nc")
    assert ds.attrs["run_id"] == "A1" and ds.attrs["source"].startswith("A1.csv sha256:")


def test_cli_exit_status_and_one_line_per_rejection(tmp_path, capsys):
    a, bad = _good(tmp_path, "A1"), _bad(tmp_path)
    missing = tmp_path / "missing.csv"
    status = main(["ingest", str(a), str(bad), str(missing), "-o", str(tmp_path / "out")])
    captured = capsys.readouterr()
    assert status == 2
    lines = captured.err.strip().splitlines()
    assert len(lines) == 3  # two rejections + a summary
    assert lines[0] == (f"fivid ingest: rejected: {bad}:{data_line(5)}: column 'friction_force': "
                        "cannot read 'oops' as a number (expected a number with a decimal point, or nan/inf)")
    assert lines[1].startswith(f"fivid ingest: rejected: {missing}: no such file")
    assert lines[2] == "fivid ingest: 1 file(s) written, 2 rejected"
    assert f"{a} -> {tmp_path / 'out' / 'A1.nc'}" in captured.out
    assert main(["ingest", str(_good(tmp_path, "C3")), "-o", str(tmp_path / "out")]) == 0


def test_duplicate_run_id_rejects_all_its_files(tmp_path):
    first, second = _good(tmp_path, "R7", "first.csv"), _good(tmp_path, "R7", "second.csv")
    other = _good(tmp_path, "R8")
    result = ingest_files([first, other, second], tmp_path / "out")
    assert result.written == [tmp_path / "out" / "R8.nc"]
    assert [r.path for r in result.rejected] == [first, second]
    for r in result.rejected:
        assert r.error.key == "run_id" and "also the run_id of" in r.error.message
    assert "second.csv" in str(result.rejected[0]) and "first.csv" in str(result.rejected[1])


def test_same_file_twice_is_read_once(tmp_path):
    a = _good(tmp_path, "A1")
    result = ingest_files([a, tmp_path / "." / "A1.csv"], tmp_path / "out")
    assert result.ok and result.written == [tmp_path / "out" / "A1.nc"]


def test_output_exists_unless_overwrite(tmp_path, capsys):
    a = _good(tmp_path, "A1")
    out = tmp_path / "out"
    assert main(["ingest", str(a), "-o", str(out)]) == 0
    before = (out / "A1.nc").stat().st_mtime_ns
    capsys.readouterr()
    assert main(["ingest", str(a), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"{a}: output '{out / 'A1.nc'}' exists; pass --overwrite to replace it" in err
    assert (out / "A1.nc").stat().st_mtime_ns == before
    write_rig(a, meta=dict(GOOD_META, run_id="A1", normal_load="7 N"))
    assert main(["ingest", str(a), "-o", str(out), "--overwrite"]) == 0
    assert read_run(out / "A1.nc").attrs["normal_load"] == 7.0
    assert _nc_and_tmp(out) == ["A1.nc"]


def test_output_folder_not_creatable(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(FividError, match="cannot create the output folder"):
        ingest_files([_good(tmp_path, "A1")], blocker / "out")
    assert main(["ingest", str(tmp_path / "A1.csv"), "-o", str(blocker / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "cannot create the output folder" in err[0] and "Traceback" not in err[0]


@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="needs Linux /proc")
def test_output_folder_not_writable_even_for_root(tmp_path):
    """/proc refuses new files to everyone: the check writes a file instead of trusting os.access."""
    with pytest.raises(FividError, match="'/proc' is not writable"):
        ingest_files([_good(tmp_path, "A1")], "/proc")


@pytest.mark.skipif(hasattr(os, "geteuid") and os.geteuid() == 0, reason="root may write anywhere")
def test_output_folder_without_write_permission(tmp_path):
    out = tmp_path / "ro"
    out.mkdir()
    out.chmod(0o500)
    try:
        with pytest.raises(FividError, match="is not writable"):
            ingest_files([_good(tmp_path, "A1")], out)
    finally:
        out.chmod(0o700)


def test_folder_input_and_rig_option(tmp_path, capsys):
    folder = tmp_path / "exports"
    folder.mkdir()
    _good(folder, "A1")
    _good(folder, "A2")
    (folder / "notes.txt").write_text("not data")
    assert main(["ingest", str(folder), "-o", str(tmp_path / "out"), "--rig", "triboair"]) == 0
    assert _nc_and_tmp(tmp_path / "out") == ["A1.nc", "A2.nc"]
    assert main(["ingest", str(folder), "-o", str(tmp_path / "o2"), "--rig", "nope"]) == 2
    assert "no rig profile named 'nope'" in capsys.readouterr().err


def test_folder_without_csv_is_rejected_not_a_silent_success(tmp_path, capsys):
    empty = tmp_path / "exports"
    empty.mkdir()
    (empty / "notes.txt").write_text("not data")
    a = _good(tmp_path, "A1")
    result = ingest_files([empty, a], tmp_path / "out")
    assert [p.name for p in result.written] == ["A1.nc"]
    assert [r.path for r in result.rejected] == [empty]
    assert main(["ingest", str(empty), "-o", str(tmp_path / "o2")]) == 2
    err = capsys.readouterr().err
    assert f"{empty}: the folder holds no *.csv file" in err
    assert "0 file(s) written, 1 rejected" in err


def test_readme_main_command_gives_si_values(tmp_path):
    """What a new user runs (README): the sample file in g, mm/s, µm becomes SI in OUTDIR/R001.nc."""
    out = tmp_path / "out"
    proc = subprocess.run([sys.executable, "-m", "fivid", "ingest", "sample_data/R001_v10_ra08.csv", "-o", str(out)],
                          cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    ds = read_run(out / "R001.nc")
    first = (ROOT / "sample_data" / "R001_v10_ra08.csv").read_text(encoding="utf-8").splitlines()[9].split(",")
    assert ds["acceleration"].values[0] == pytest.approx(float(first[1]) * STANDARD_GRAVITY, rel=4e-16)
    assert ds["velocity"].values[0] == pytest.approx(float(first[5]) * 1e-3, rel=4e-16)
    assert ds.attrs["sliding_velocity"] == pytest.approx(0.01, rel=4e-16)
    assert ds.attrs["roughness_ra"] == pytest.approx(8e-7, rel=4e-16)
    assert ds["acceleration"].attrs["units"] == "m s-2" and ds["velocity"].attrs["units"] == "m s-1"


def test_bad_input_gives_no_traceback(tmp_path):
    bad = tmp_path / "x.csv"
    bad.write_bytes(b"\x00\x01binary")
    proc = subprocess.run([sys.executable, "-m", "fivid", "ingest", str(bad), "-o", str(tmp_path / "o")],
                          cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr and f"{bad}: not a CSV text file" in proc.stderr


_KILL_AT_RENAME = textwrap.dedent("""
    import os, signal, sys
    def die(*args, **kwargs):
        os.kill(os.getpid(), signal.SIGKILL)   # killed after the data were written, before the rename
    os.replace = die
    os.link = die
    from fivid.cli import main
    sys.exit(main(["ingest", sys.argv[1], "-o", sys.argv[2]]))
""")


def test_killed_before_rename_leaves_no_nc(tmp_path):
    src = _good(tmp_path, "K1")
    out = tmp_path / "out"
    proc = subprocess.run([sys.executable, "-c", _KILL_AT_RENAME, str(src), str(out)], cwd=ROOT,
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == -signal.SIGKILL
    names = _nc_and_tmp(out)
    assert not any(n.endswith(".nc") for n in names)
    assert len(names) == 1 and names[0].startswith(".K1.nc.") and names[0].endswith(".tmp")  # the complete temp file


@pytest.mark.slow
def test_killed_while_writing_leaves_no_nc(tmp_path):
    """SIGKILL from outside while the temporary file grows: no K2.nc, partial data only in the .tmp."""
    rows = [f"{i / 51200.0:.9f},0.01,1.5,5.0,0.0" for i in range(400_000)]
    src = write_rig(tmp_path / "K2.csv", meta=dict(GOOD_META, run_id="K2"), rows=rows)
    out = tmp_path / "out"
    out.mkdir()
    proc = subprocess.Popen([sys.executable, "-m", "fivid", "ingest", str(src), "-o", str(out)], cwd=ROOT,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 60
    try:
        while time.monotonic() < deadline and proc.poll() is None:
            if any(n.endswith(".tmp") and n.startswith(".K2") for n in os.listdir(out)):
                proc.send_signal(signal.SIGKILL)
                break
            time.sleep(0.001)
    finally:
        killed = proc.poll() is None or proc.returncode == -signal.SIGKILL
        proc.kill()
        proc.wait()
    if not killed:
        pytest.skip("the ingest finished before it could be killed (machine too fast for this file)")
    assert not (out / "K2.nc").exists()


def test_ingest_help():
    proc = subprocess.run([sys.executable, "-m", "fivid", "ingest", "--help"], cwd=ROOT, capture_output=True,
                          text=True, timeout=60)
    assert proc.returncode == 0 and "--rig PROFILE" in proc.stdout and "--overwrite" in proc.stdout


def test_written_values_equal_read_values(tmp_path):
    a = _good(tmp_path, "A1")
    ingest_files([a], tmp_path / "out")
    from fivid.io import read_rig_csv

    ds, back = read_rig_csv(a), read_run(tmp_path / "out" / "A1.nc")
    for name in ds.variables:
        np.testing.assert_array_equal(back[name].values, ds[name].values)


def test_docs_commands_run(tmp_path, monkeypatch, capsys):
    """Every `fivid ingest` command in docs/ingest.md's first code block works as documented."""
    import re
    import shlex

    text = (ROOT / "docs" / "ingest.md").read_text(encoding="utf-8")
    block = re.search(r"```bash\n(.*?)```", text, re.S).group(1)
    commands = [line.split("#")[0].strip() for line in block.splitlines() if line.startswith("fivid ingest")]
    assert len(commands) == 2
    monkeypatch.chdir(ROOT)
    out = tmp_path / "out"
    for command in commands:
        argv = shlex.split(command)[1:]
        argv[argv.index("-o") + 1] = str(out)
        assert main(argv) == 0, capsys.readouterr().err
    ds = read_run(out / "R002.nc")
    assert ds.attrs["sliding_velocity"] == pytest.approx(0.02, rel=4e-16)
    assert ds["acceleration"].attrs["sensitivity"] == "100 mV/g"
