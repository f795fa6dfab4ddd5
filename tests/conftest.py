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


def load_benchmark_script(name: str):
    """``benchmarks/<name>.py`` imported as a module under a private name (the scripts are no package), registered
    in ``sys.modules`` while the caller holds it (dataclasses and pickling look their module up there); a
    generator: yields the module, unregisters it afterwards."""
    import importlib.util
    import sys
    spec = importlib.util.spec_from_file_location(f"_{name}_under_test", TESTS.parent / "benchmarks" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    try:
        spec.loader.exec_module(module)
        yield module
    finally:
        sys.modules.pop(spec.name, None)


@pytest.fixture(scope="session")
def load_benchmark():
    """:func:`load_benchmark_script`, for a test module's own fixture: ``yield from load_benchmark("bench_x")``."""
    return load_benchmark_script
