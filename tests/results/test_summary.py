"""summary.json (strict JSON, non-finite → null with a note) and the console table."""
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from sarfe.erp import equivalent_radiated_power
from sarfe.results import console_table, write_summary_json


@dataclass(frozen=True)
class Point:
    x: float
    tag: str


def test_summary_json_is_strict_and_numpy_safe(tmp_path):
    erp = equivalent_radiated_power(np.zeros((3, 2)), 10.0, np.ones(2))   # zero power → −inf dB
    summary = {
        "case": "demo", "path": Path("/tmp/x"), "count": np.int64(3), "flag": np.bool_(True),
        "levels": np.array([1.5, np.nan, np.inf]), "erp": erp.summary(), "point": Point(1.0, "a"),
        "nested": {"t": (np.float32(0.5), None)},
    }
    path = write_summary_json(tmp_path / "out" / "summary.json", summary)
    text = path.read_text()

    def reject(constant):
        raise AssertionError(f"non-strict JSON constant {constant}")

    data = json.loads(text, parse_constant=reject)
    assert data["count"] == 3 and data["flag"] is True and data["path"] == "/tmp/x"
    assert data["levels"] == [1.5, None, None]
    assert data["erp"]["level_total_db"] is None
    assert data["point"] == {"x": 1.0, "tag": "a"} and data["nested"]["t"] == [0.5, None]
    assert "null" in data["null_note"]
    assert data["non_finite"]["$.levels[*]"] == {"values": ["nan", "inf"], "count": 2}
    assert data["non_finite"]["$.erp.level_total_db"] == {"values": ["-inf"], "count": 1}
    assert data["non_finite"]["$.erp.level_db[*]"] == {"values": ["-inf"], "count": 1}


def test_summary_json_without_non_finite_has_no_note(tmp_path):
    data = json.loads(write_summary_json(tmp_path / "s.json", {"a": 1.0}).read_text())
    assert data == {"a": 1.0}
    with pytest.raises(TypeError, match="complex"):
        write_summary_json(tmp_path / "c.json", {"z": 1j})


def test_console_table_layout():
    rows = [
        {"contact": "clip_1", "amplitude_m": 1.234e-4, "rattle": True, "level_db": 61.234},
        {"contact": "felt_pad_long", "amplitude_m": float("nan"), "rattle": False,
         "level_db": -np.inf},
    ]
    table = console_table(rows, formats={"level_db": ".1f"}, headers={"level_db": "L [dB]"})
    lines = table.splitlines()
    assert len(lines) == 4
    assert lines[0].split() == ["contact", "amplitude_m", "rattle", "L", "[dB]"]
    assert set(lines[1].replace(" ", "")) == {"-"}
    assert "clip_1" in lines[2] and "1.234e-04" in lines[2] and "yes" in lines[2] and "61.2" in lines[2]
    assert "felt_pad_long" in lines[3] and "-inf" in lines[3]
    # fixed width: numeric columns right-aligned to the same end column
    assert lines[2].index("61.2") + 4 == lines[3].index("-inf") + 4
    assert console_table([]) == "(no rows)"
    many = console_table([{"i": i} for i in range(10)], max_rows=3)
    assert many.splitlines()[-1] == "... (7 more)"
