"""The print simulator: realistic webcam frames of prints, normal and failing.

Used by tests, benchmarks, the simulated webcams and the demo. It may import the
core (cameras, geometry); the core and the plugin's detection path never import it.
"""
