"""The demos' JSON files are strict JSON: NaN and infinity become null (demos/_common.py)."""
import ast
import json
import math
import sys
from pathlib import Path

import numpy as np

DEMOS = Path(__file__).resolve().parents[2] / "demos"


def _common():
    if str(DEMOS) not in sys.path:
        sys.path.insert(0, str(DEMOS))
    import _common

    return _common


def _strict(text):
    def refuse(name):
        raise ValueError(f"not JSON: {name}")

    return json.loads(text, parse_constant=refuse)


def test_write_json_writes_nan_as_null(tmp_path):
    # the measured kink of a crack that did not grow far enough is nan (mode12_kink's kink.json)
    data = {"measured_history_deg": math.nan, "k": np.float64(0.215), "n": np.int64(3),
            "inf": -math.inf, "path": np.array([[0.5, 1.0], [np.nan, 0.9]]), "ok": np.bool_(True)}
    path = _common().write_json(tmp_path / "kink.json", data)
    assert "NaN" not in path.read_text() and "Infinity" not in path.read_text()
    assert _strict(path.read_text()) == {"measured_history_deg": None, "k": 0.215, "n": 3,
                                         "inf": None, "path": [[0.5, 1.0], [None, 0.9]], "ok": True}


def test_demos_write_json_only_through_write_json():
    for script in DEMOS.glob("*.py"):
        if script.name == "_common.py":
            continue
        calls = [node.func for node in ast.walk(ast.parse(script.read_text()))
                 if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)]
        direct = [f"json.{f.attr}" for f in calls
                  if isinstance(f.value, ast.Name) and f.value.id == "json"]
        assert not direct, f"{script.name} calls {direct}; use _common.write_json (strict JSON)"
