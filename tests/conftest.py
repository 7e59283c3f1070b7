"""Shared test fixtures."""

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared"


@pytest.fixture
def root() -> Path:
    """The repository root."""
    return ROOT


@pytest.fixture
def real_data() -> Path:
    """``../shared/real_data`` (third-party measured data; skip when absent)."""
    path = SHARED / "real_data"
    if not path.is_dir():
        pytest.skip("../shared/real_data is not beside the repository")
    return path
