"""Fixtures shared by the vision tests."""
from __future__ import annotations

import pytest

from octoprint_printwatch.core import pipeline


@pytest.fixture
def brims_not_looked_for(monkeypatch):
    """Looks lay the outline as they did before a look found a part in a brim by its brim (thirty-eighth session,
    core.alignment.align_with_brim): for recordings whose first looks laid the outline off the part, along a brim,
    where what is tested handles such an outline whatever laid it (a miscalibrated camera does the same)."""
    monkeypatch.setattr(pipeline, "BRIM_WIDTHS_MM", ())
