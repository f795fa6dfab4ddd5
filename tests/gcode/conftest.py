"""Fixtures for the G-code tests: the corpus of real slicer files (tests/data/gcode)."""
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
GCODE_DIR = HERE.parent / "data" / "gcode"
CORPUS = sorted(GCODE_DIR.glob("*.gcode")) + sorted((GCODE_DIR / "third_party").glob("*.gcode"))

# The test-side simulator (gcode_machine.py) is imported by name.
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))


@pytest.fixture(params=CORPUS, ids=[path.name for path in CORPUS])
def corpus_file(request) -> Path:
    return request.param
