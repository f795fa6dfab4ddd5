"""Shared fixtures. Area-specific fixtures live in each test folder's own conftest.py."""
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent
DATA = TESTS / "data"


@pytest.fixture(scope="session")
def data_dir() -> Path:
    """Test data copied into the project (see tests/data/SOURCES.md)."""
    return DATA


@pytest.fixture(scope="session")
def gcode_dir() -> Path:
    return DATA / "gcode"
