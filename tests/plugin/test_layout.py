"""The plugin stays a thin adapter: only the class module and the HTTP views import OctoPrint or Flask."""
import ast
from pathlib import Path

PLUGIN = Path(__file__).resolve().parents[2] / "octoprint_printwatch" / "plugin"
HOST_MODULES = {"__init__.py", "api.py"}


def top_level_imports(path: Path) -> set[str]:
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and not node.level and node.module:
            names.add(node.module.split(".")[0])
    return names


def test_adapters_are_host_independent():
    offenders = {
        path.name: sorted(top_level_imports(path) & {"octoprint", "flask"})
        for path in PLUGIN.glob("*.py")
        if path.name not in HOST_MODULES and top_level_imports(path) & {"octoprint", "flask"}
    }
    assert offenders == {}

