"""Plugin tests: helpers (OctoPrint harness, simulated webcams) live beside the tests."""
import sys
from pathlib import Path

# Import mode is importlib: make the helper modules in this folder importable by name.
sys.path.insert(0, str(Path(__file__).resolve().parent))
