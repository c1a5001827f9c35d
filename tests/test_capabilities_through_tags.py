"""Capabilities are read from the calibrators' tags (``calibration_tags``), never guessed from a class, a fitted
attribute or an instance's ``__dict__``: a scan of the whole package, with a check that the scan finds each kind."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import ftcal

PACKAGE = Path(ftcal.__file__).parent
#: Type checks that are not capability checks: the base class (is it a calibrator at all, for validation and the
#: model files' nesting) and the stock baseline's class (which row of auto's table a candidate is).
NOT_CAPABILITIES = {"BaseCalibrator", "StockCalibrator"}
#: Fitted attributes a check may ask for that are no capability: scikit-learn's own (column names of a DataFrame).
SKLEARN_OWN = {"feature_names_in_"}


def _guesses(source: str) -> list[str]:
    """``isinstance(x, SomeCalibrator)``, ``hasattr(x, "fitted_")`` and ``"fitted_" in x.__dict__`` of ``source``
    (a class asking about its own state, ``self``, guesses nothing: its tags are computed from it)."""
    found = []
    tree = ast.parse(source)
    own = {id(n) for call in ast.walk(tree) for n in ast.walk(call) if isinstance(call, ast.Call) and call.args
           and isinstance(call.args[0], ast.Name) and call.args[0].id == "self"}
    for node in ast.walk(tree):
        if id(node) in own:
            continue
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and len(node.args) == 2:
            kind, what = node.func.id, node.args[1]
            if kind == "isinstance":
                names = [e for e in (what.elts if isinstance(what, ast.Tuple) else [what])]
                for n in names:
                    name = n.id if isinstance(n, ast.Name) else n.attr if isinstance(n, ast.Attribute) else ""
                    if name.endswith("Calibrator") and name not in NOT_CAPABILITIES:
                        found.append(f"{node.lineno}: isinstance(..., {name})")
            elif kind == "hasattr" and isinstance(what, ast.Constant) and isinstance(what.value, str) \
                    and what.value.endswith("_") and not what.value.startswith("_") and what.value not in SKLEARN_OWN:
                found.append(f"{node.lineno}: hasattr(..., {what.value!r})")
        if isinstance(node, ast.Compare) and len(node.ops) == 1 and isinstance(node.ops[0], (ast.In, ast.NotIn)) \
                and isinstance(node.left, ast.Constant) and str(node.left.value).endswith("_") \
                and isinstance(node.comparators[0], ast.Attribute) and node.comparators[0].attr == "__dict__" \
                and not (isinstance(node.comparators[0].value, ast.Name) and node.comparators[0].value.id == "self"):
            found.append(f"{node.lineno}: {node.left.value!r} in ...__dict__")
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "get" \
                and isinstance(node.func.value, ast.Attribute) and node.func.value.attr == "__dict__" and node.args \
                and not (isinstance(node.func.value.value, ast.Name) and node.func.value.value.id == "self") \
                and isinstance(node.args[0], ast.Constant) and node.args[0].value in ("comparison_", "best_estimator_"):
            found.append(f"{node.lineno}: __dict__.get({node.args[0].value!r})")
    return found


def test_the_scan_finds_each_kind_of_guess():
    source = ('isinstance(m, NetworkCalibrator)\nhasattr(m, "gain_per_deg_")\n"comparison_" in m.__dict__\n'
              'm.__dict__.get("comparison_")\nisinstance(m, (BaseCalibrator, ft.AutoCalibrator))\n')
    assert [g.split(":")[0] for g in _guesses(source)] == ["1", "2", "3", "4", "5"]
    assert _guesses('isinstance(m, BaseCalibrator)\nhasattr(m, "feature_names_in_")\nhasattr(m, "_x")\n') == []


MODULES = sorted(p for p in PACKAGE.rglob("*.py"))


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(PACKAGE)))
def test_no_module_guesses_a_capability(path):
    assert _guesses(path.read_text(encoding="utf-8")) == []


def test_fit_stacked_refuses_by_the_tags(tmp_path):
    from ftcal import LinearCalibrator
    from ftcal.networks import fit_stacked
    from ftcal.core._exceptions import CalibrationInputError

    with pytest.raises(CalibrationInputError, match="estimator 0 is LinearCalibrator"):
        fit_stacked([LinearCalibrator()], [[0.0] * 6] * 8, [[0.0] * 6] * 8)
