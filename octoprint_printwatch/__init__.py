"""PrintWatch: an OctoPrint plugin that watches prints with webcams and pauses failed ones.

This module is what OctoPrint loads. It only declares the plugin; the plugin
class and its hooks are imported in ``__plugin_load__`` so that the offline
``printwatch`` command and the pure core (``octoprint_printwatch.core``) never
import OctoPrint.
"""

__plugin_name__ = "PrintWatch"
__plugin_identifier__ = "printwatch"
__plugin_pythoncompat__ = ">=3.9,<4"
__plugin_description__ = (
    "Compares webcam views of the print with the expected part at each check height "
    "and pauses the print when it went wrong."
)
__plugin_license__ = "AGPLv3"


def __plugin_load__():
    # Deferred import: OctoPrint is only needed when running inside OctoPrint.
    from .plugin import plugin_hooks, PrintWatchPlugin

    global __plugin_implementation__, __plugin_hooks__
    __plugin_implementation__ = PrintWatchPlugin()
    __plugin_hooks__ = plugin_hooks(__plugin_implementation__)
