"""Running the CLI in-process in the bad-input tests."""

from __future__ import annotations

from fivid.cli import main


def fails(capsys, argv) -> str:
    """Run the CLI, check exit 2 without a traceback, return stderr."""
    status = main(argv)
    err = capsys.readouterr().err
    assert "Traceback" not in err, err
    assert status == 2, err
    return err
