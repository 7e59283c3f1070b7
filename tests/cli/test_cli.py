import pkgutil
import subprocess
import sys

import pytest

from fivid import __version__
from fivid.cli import commands, main


def test_version(capsys):
    with pytest.raises(SystemExit) as info:  # argparse's version action exits
        main(["--version"])
    assert info.value.code == 0
    assert capsys.readouterr().out.strip() == f"fivid {__version__}"


def test_help_lists_commands():
    out = subprocess.run([sys.executable, "-m", "fivid", "--help"], capture_output=True, text=True)
    assert out.returncode == 0
    assert "exit status" in out.stdout
    names = [m.name for m in pkgutil.iter_modules(commands.__path__) if not m.name.startswith("_")]
    assert "ingest" in names
    listed = {line.split()[0] for line in out.stdout.splitlines() if line.startswith("    ") and line.split()}
    assert set(names) <= listed, f"commands missing from --help: {set(names) - listed}"


def test_no_command_is_bad_input():
    assert main([]) == 2


def test_main_restores_the_fivid_logger(tmp_path):
    import logging

    log = logging.getLogger("fivid")
    before = (list(log.handlers), log.level, log.propagate)
    status = main(["-vv", "ingest", str(tmp_path / "missing.csv"), "-o", str(tmp_path)])
    assert status == 2
    assert (list(log.handlers), log.level, log.propagate) == before


def test_a_missing_optional_package_gets_an_install_hint(monkeypatch, capsys):
    import argparse

    import fivid.cli as cli

    def needs_dask(args):
        raise ModuleNotFoundError("No module named 'distributed'", name="distributed")

    parser = argparse.ArgumentParser()
    parser.add_argument("-v", "--verbose", action="count", default=0)
    parser.set_defaults(command="run", func=needs_dask)
    monkeypatch.setattr(cli, "build_parser", lambda: parser)
    assert cli.main([]) == 1
    err = capsys.readouterr().err
    assert "'distributed'" in err and "fivid[sweep]" in err and "Traceback" not in err


def test_reader_closing_the_pipe_is_no_traceback():
    """`fivid schema model | head -c 10`: the reader closes stdout before fivid writes; fivid exits 141
    (128 + SIGPIPE, as a shell reports a tool ended by SIGPIPE) without a traceback or 'unexpected failure'."""
    p = subprocess.Popen([sys.executable, "-m", "fivid", "schema", "model"], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE)
    p.stdout.close()  # before the child has written anything
    err = p.stderr.read().decode()
    assert p.wait(timeout=120) == 141, err
    assert "Traceback" not in err and "unexpected failure" not in err
