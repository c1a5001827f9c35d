"""The built wheel holds every package of ``ftcal`` and the robot models, and imports without the source tree.

The suite runs against an editable install, which finds any folder of ``ftcal/`` whether the build lists it or not;
a user's ``pip install ftcal`` gets only what the wheel holds. These tests build the wheel from a copy of the
project (the checkout is never written to) and look inside it.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    """A wheel built from a copy of pyproject.toml, README.md, ftcal/ and robots/."""
    src = tmp_path_factory.mktemp("src")
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, src / name)
    for name in ("ftcal", "robots"):
        shutil.copytree(ROOT / name, src / name, ignore=shutil.ignore_patterns("__pycache__"))
    out = tmp_path_factory.mktemp("wheel")
    subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w", str(out),
                    str(src)], check=True, capture_output=True, timeout=300)
    (found,) = out.glob("ftcal-*.whl")
    return found


def test_wheel_holds_every_package_folder(wheel):
    packages = {p.parent.relative_to(ROOT).as_posix() for p in (ROOT / "ftcal").rglob("__init__.py")}
    assert {"ftcal", "ftcal/workflow", "ftcal/cli"} <= packages
    with zipfile.ZipFile(wheel) as archive:
        names = set(archive.namelist())
    missing = sorted(p for p in packages if f"{p}/__init__.py" not in names)
    assert not missing, f"packages missing from the wheel (add them to pyproject.toml): {missing}"
    assert {"ftcal/robots/kuka_iiwa14_ft.urdf", "ftcal/reporting/certificate_page.html"} <= names


def test_unpacked_wheel_imports_every_subpackage(wheel, tmp_path):
    # Each subpackage must come from the unpacked wheel: the editable install's finder would serve a missing one
    # from the checkout.
    site = tmp_path / "site"
    with zipfile.ZipFile(wheel) as archive:
        archive.extractall(site)
    code = ("import importlib, ftcal\n"
            "assert ftcal.__file__.startswith(%r), ftcal.__file__\n"
            "for name in ftcal.SUBPACKAGES + ('cli',):\n"
            "    module = importlib.import_module('ftcal.' + name)\n"
            "    assert module.__file__.startswith(%r), module.__file__\n"
            "from ftcal.workflow import calibrate\n"
            "from ftcal.reporting._page import PAGE\n"  # its template is package data
            "assert '$summary' in PAGE.template\n"
            "print('ok')\n") % (str(site), str(site))
    done = subprocess.run([sys.executable, "-I", "-c", f"import sys; sys.path.insert(0, {str(site)!r})\n" + code],
                          cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "ok"
