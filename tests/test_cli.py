import subprocess
import sys

from fivid import __version__
from fivid.cli import main


def test_version(capsys):
    try:
        main(["--version"])
    except SystemExit as e:
        assert e.code == 0
    assert __version__ in capsys.readouterr().out


def test_help_lists_commands():
    out = subprocess.run([sys.executable, "-m", "fivid", "--help"], capture_output=True, text=True)
    assert out.returncode == 0
    assert "exit status" in out.stdout


def test_no_command_is_bad_input():
    assert main([]) == 2


def test_main_restores_the_fivid_logger(tmp_path):
    import logging

    log = logging.getLogger("fivid")
    before = (list(log.handlers), log.level, log.propagate)
    status = main(["-vv", "ingest", str(tmp_path / "missing.csv"), "-o", str(tmp_path)])
    assert status == 2
    assert (list(log.handlers), log.level, log.propagate) == before
