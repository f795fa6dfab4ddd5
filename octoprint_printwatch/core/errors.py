"""Errors a user can act on. Their message is one line naming what and where."""


class PrintWatchError(Exception):
    """Base class: bad input or a state the user can fix; shown without a traceback."""


class GcodeError(PrintWatchError):
    """A G-code file that cannot be analysed or injected."""


class GeometryError(PrintWatchError):
    """A mesh or toolpath solid that cannot be used."""


class RecordingError(PrintWatchError):
    """A recording folder that cannot be read."""


class CalibrationError(PrintWatchError):
    """Calibration images or files that give no trustworthy result."""
