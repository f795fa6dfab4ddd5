"""The one-command demo: a real OctoPrint with PrintWatch, its virtual printer and simulated webcams.

- ``octoprint_server.py``: starts ``octoprint serve`` in a throwaway base folder (virtual printer,
  users with API keys, network plugins off). Also used by the integration tests and benchmarks.
- ``webcam_server.py``: simulated webcams that render the print's *actual* progress with the print
  simulator, following the job through OctoPrint's API.
- ``run.py``: the orchestration behind ``printwatch demo`` (configure, upload, print, watch, summarise).

Nothing here is imported by the plugin or the core; it needs OctoPrint installed
(``pip install 'octoprint-printwatch[octoprint]'``).
"""
