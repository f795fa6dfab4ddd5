"""One module per ``printwatch`` subcommand; see :mod:`octoprint_printwatch.cli`."""
