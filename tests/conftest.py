"""Shared test fixtures."""

import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared"


@pytest.fixture(autouse=True, scope="session")
def _basis_cache(tmp_path_factory):
    """One reduced-basis cache per test session (``$FIVID_CACHE_DIR``, inherited by CLI subprocesses and dask
    workers): the tests share the bases they build and never write to the user's cache folder."""
    os.environ["FIVID_CACHE_DIR"] = str(tmp_path_factory.mktemp("fivid-bases"))


@pytest.fixture
def root() -> Path:
    """The repository root."""
    return ROOT


@pytest.fixture
def real_data() -> Path:
    """``../shared/real_data`` (third-party measured data).

    Skipped when absent on a developer's machine; in CI (``CI`` set), where ``../shared`` is always beside the
    clone, a missing folder is a failure, so the real-data checks cannot silently stop running.
    """
    path = SHARED / "real_data"
    if not path.is_dir():
        (pytest.fail if os.environ.get("CI") else pytest.skip)(f"{path} is not beside the repository")
    return path
