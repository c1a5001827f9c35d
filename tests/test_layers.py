"""The package layout is the architecture: a package imports only the layers below it.

The allowed imports are the table of ``docs/architecture.md``; every ``from .x import`` and
``import ftcal.x`` in every module is checked, including imports inside functions.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import ftcal

PACKAGE = Path(ftcal.__file__).parent
ALLOWED = {
    "core": set(),
    "model_selection": {"core"},
    "io": {"core"},
    "calibrators": {"core", "model_selection"},
    "robot": {"core"},
    "networks": {"core", "model_selection", "calibrators"},
    "simulation": {"core", "io"},
    "compose": {"core", "model_selection", "calibrators", "networks"},
    "persistence": {"core", "calibrators", "networks", "compose"},
    "experiment": {"core", "model_selection", "io", "robot", "simulation"},
    "reporting": {"core", "io", "model_selection", "calibrators", "compose", "persistence"},
    "benchmark": {"core", "io", "model_selection", "calibrators", "robot", "networks", "simulation", "compose",
                  "persistence", "experiment", "reporting"},
    "cli": {"core", "io", "model_selection", "calibrators", "robot", "networks", "simulation", "compose",
            "persistence", "experiment", "reporting", "benchmark"},
    # deprecated alias packages: names only, resolved lazily from the new homes (core's lazy namespace only)
    "models": {"core"},
    "neural_network": {"core"},
    "evaluation": {"core"},
}


def _imported_packages(path: Path, package: str) -> set[str]:
    """The ftcal packages (first component under ``ftcal``) that the module at ``path`` imports."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level == 0:
                parts = (node.module or "").split(".")
                if parts[0] == "ftcal":
                    found.add(parts[1] if len(parts) > 1 else "ftcal")
                continue
            # a relative import from ftcal/<package>/<module>.py: level 1 is <package>, level 2 is ftcal
            if node.level == 1:
                found.add(package)
            else:
                target = (node.module or "").split(".")[0]
                found.add(target or "ftcal")
        elif isinstance(node, ast.Import):
            for alias in node.names:
                parts = alias.name.split(".")
                if parts[0] == "ftcal":
                    found.add(parts[1] if len(parts) > 1 else "ftcal")
    return found


@pytest.mark.parametrize("package", sorted(ALLOWED))
def test_a_package_imports_only_the_layers_below_it(package):
    modules = sorted((PACKAGE / package).glob("*.py"))
    assert modules, f"ftcal/{package} is empty"
    for path in modules:
        imported = _imported_packages(path, package) - {package}
        imported.discard("ftcal")  # ``from .. import __version__`` only
        assert imported <= ALLOWED[package], (
            f"ftcal/{package}/{path.name} imports {sorted(imported - ALLOWED[package])}, above its layer"
        )


def test_every_module_lives_in_a_layer_package():
    top_level = {p.name for p in PACKAGE.glob("*.py")}
    assert top_level == {"__init__.py", "__main__.py"}
    packages = {p.name for p in PACKAGE.iterdir() if (p / "__init__.py").exists()}
    assert packages == set(ALLOWED)
    for name in packages:  # each says what it holds and what it may import
        doc = ast.get_docstring(ast.parse((PACKAGE / name / "__init__.py").read_text()))
        assert doc and "import" in doc.lower(), f"ftcal/{name}/__init__.py needs a docstring naming its imports"


def test_the_public_names_resolve():
    for name in ftcal.__all__:
        assert getattr(ftcal, name) is not None


def test_benchmark_scripts_use_only_public_names():
    """The scripts in benchmarks/ are thin callers of the library: no ``ftcal._x`` module, no ``_private`` name."""
    scripts = sorted((PACKAGE.parent / "benchmarks").glob("*.py"))
    assert scripts
    for path in scripts:
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("ftcal"):
                private = [p for p in node.module.split(".") if p.startswith("_")]
                private += [a.name for a in node.names if a.name.startswith("_")]
                assert not private, f"{path.name}:{node.lineno} imports private {private} from {node.module}"
            elif isinstance(node, ast.Attribute) and node.attr.startswith("_") and not node.attr.startswith("__"):
                raise AssertionError(f"{path.name}:{node.lineno} uses the private attribute .{node.attr}")
