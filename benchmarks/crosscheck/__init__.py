"""A second, independent print simulator (written from docs/recording-format.md only) to measure how the
detector generalises. ``render`` and ``scenes`` must never import ``octoprint_printwatch``."""
