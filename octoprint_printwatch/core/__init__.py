"""The host-independent core: G-code, geometry, rendering, vision, calibration, recordings.

Nothing in this package imports OctoPrint or the simulator; it takes plain data
(paths, arrays, dicts) in and gives dataclasses out. ``tests/test_architecture.py``
enforces the direction of imports.
"""
