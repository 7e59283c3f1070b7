import os
import stat

import pytest

from fivid.errors import FividError, OutputExistsError
from fivid.storage import atomic_path, check_writable, write_text


def test_atomic_write_has_the_mode_open_would_give(tmp_path):
    mask = os.umask(0o022)
    try:
        path = write_text(tmp_path / "a.txt", "x")
    finally:
        os.umask(mask)
    assert stat.S_IMODE(path.stat().st_mode) == 0o644


def test_failed_write_leaves_nothing(tmp_path):
    with pytest.raises(RuntimeError):
        with atomic_path(tmp_path / "b.nc") as tmp:
            tmp.write_text("partial")
            raise RuntimeError("killed")
    assert list(tmp_path.iterdir()) == []


def test_no_overwrite_refuses_a_file_that_appeared(tmp_path):
    target = tmp_path / "c.txt"
    with pytest.raises(OutputExistsError):
        with atomic_path(target, overwrite=False) as tmp:
            tmp.write_text("new")
            target.write_text("someone else's")
    assert target.read_text() == "someone else's"
    assert [p.name for p in tmp_path.iterdir()] == ["c.txt"]


def test_check_writable_refuses_a_folder_even_with_overwrite(tmp_path):
    """`-o somedir --overwrite` must be a bad-input error, not an IsADirectoryError at the rename."""
    (tmp_path / "out").mkdir()
    for overwrite in (False, True):
        with pytest.raises(FividError, match="is a folder"):
            check_writable(tmp_path / "out", overwrite=overwrite)
    assert check_writable(tmp_path / "new.nc") == tmp_path / "new.nc"


@pytest.mark.skipif(not os.path.isdir("/proc/self"), reason="needs Linux /proc")
def test_check_writable_writes_instead_of_trusting_os_access():
    """/proc refuses new files to everyone, root included, although os.access says yes to root."""
    with pytest.raises(FividError, match="'/proc' is not writable"):
        check_writable("/proc/x.nc")
