"""Fixtures for the simulator tests."""
import pytest

from octoprint_printwatch.core.camera import Camera


@pytest.fixture
def side_camera() -> Camera:
    """Looks horizontally along +Y at the bed centre from 400 mm: image columns map to X."""
    return Camera.look_at("side", [100.0, -300.0, 12.0], [100.0, 100.0, 12.0], width=400, height=300,
                          focal_px=1600.0)
