"""Plugin tests: helpers (the test stack, the browser session) live beside the tests.

The OctoPrint harness and the simulated webcams are in ``octoprint_printwatch/demo/``
(the demo uses them too).
"""
import sys
from pathlib import Path

# Import mode is importlib: make the helper modules in this folder importable by name.
sys.path.insert(0, str(Path(__file__).resolve().parent))
