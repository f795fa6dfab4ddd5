"""The direction of imports is the architecture: the core is pure, the simulator is apart."""
import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "octoprint_printwatch"


def imported_modules(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:  # relative import: resolve against the package path
                parts = path.relative_to(PACKAGE.parent).with_suffix("").parts[: -node.level]
                base = ".".join(parts)
                names.add(f"{base}.{node.module}" if node.module else base)
            elif node.module:
                names.add(node.module)
    return names


def test_core_never_imports_octoprint_the_plugin_or_the_simulator():
    offenders = []
    for path in sorted((PACKAGE / "core").rglob("*.py")):
        for name in imported_modules(path):
            top = name.split(".")[0]
            if top in {"octoprint", "flask"} or name.startswith(
                ("octoprint_printwatch.simulator", "octoprint_printwatch.plugin")
            ):
                offenders.append(f"{path.relative_to(PACKAGE)} imports {name}")
    assert offenders == []


def test_simulator_never_imports_octoprint():
    offenders = [
        f"{path.relative_to(PACKAGE)} imports {name}"
        for path in sorted((PACKAGE / "simulator").rglob("*.py"))
        for name in imported_modules(path)
        if name.split(".")[0] == "octoprint"
    ]
    assert offenders == []


def test_importing_the_package_does_not_import_octoprint():
    import subprocess
    import sys

    code = "import octoprint_printwatch.cli, sys; print('octoprint' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
