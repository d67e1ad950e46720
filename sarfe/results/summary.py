"""``summary.json`` (numpy-safe, strict JSON) and the fixed-width console table of a run."""
from __future__ import annotations

import json
import math
import re
from dataclasses import asdict, is_dataclass
from pathlib import Path

import numpy as np

__all__ = ["to_jsonable", "write_summary_json", "console_table", "pruning_line", "NULL_NOTE",
           "SILENT_LEVEL_DB", "shown_level", "level_text", "headline_level", "headline_notes",
           "loudest_lines", "stability_line"]

# Levels below this are a motionless surface (round-off: a solve's 1e-19 m noise radiates
# −180 dB re 1 pW): the console, table.txt and the report show them as "-"; the files keep the value.
SILENT_LEVEL_DB = -100.0


def shown_level(value):
    """``value`` [dB] as a float for display, or None for no sound (None, NaN, −inf, or below
    :data:`SILENT_LEVEL_DB`)."""
    if value is None:
        return None
    value = float(value)
    return value if math.isfinite(value) and value >= SILENT_LEVEL_DB else None


def level_text(value, fmt: str = ".1f", unit: str = "") -> str:
    """'93.1 dB(A)' style text of a level, '-' for no sound (:func:`shown_level`)."""
    shown = shown_level(value)
    if shown is None:
        return "-"
    return format(shown, fmt) + (f" {unit}" if unit else "")

NULL_NOTE = ("null stands for a non-finite number (NaN, +inf or -inf), e.g. the dB level of zero "
             "power (-inf) or a quantity a contact does not have (NaN); see 'non_finite'")


def to_jsonable(value, path: str = "$", replaced: list | None = None):
    """Plain-Python copy of ``value``: numpy scalars/arrays → numbers/lists, dataclasses → dicts,
    Paths → str, sets/tuples → lists; NaN/±inf → None, appending ``(json path, repr)`` to ``replaced``.

    numpy arrays are converted whole (``tolist``; only non-finite entries are visited), and a
    value's JSON path is spelled out only when it is replaced: a run's summary (300 points of
    spectra and bands, ~4 MB) converts in a few tens of ms.
    """
    if replaced is None:
        replaced = []
    return _plain(value, path, replaced)


def _path_text(path) -> str:
    """'$.a.b[3]' of a lazy path: a str, or nested (parent, key) / (parent, index) tuples."""
    parts = []
    while isinstance(path, tuple):
        path, key = path
        parts.append(f"[{key}]" if isinstance(key, int) else f".{key}")
    return path + "".join(reversed(parts))


def _array(value: np.ndarray, path, replaced: list):
    """Nested lists of a numeric array; non-finite entries → None (recorded in ``replaced``)."""
    kind = value.dtype.kind
    if kind in "biu":
        return value.tolist()
    if kind == "f":
        finite = np.isfinite(value)
        if finite.all():
            return value.astype(float, copy=False).tolist()
        out = value.astype(object)
        for index in np.argwhere(~finite):
            where = path
            for i in index:
                where = (where, int(i))
            replaced.append((_path_text(where), repr(float(value[tuple(index)]))))
        out[~finite] = None
        return out.tolist()
    if kind == "c":
        raise TypeError(f"{_path_text(path)}: complex value {value.flat[0]!r} is not JSON; store "
                        "real and imaginary parts")
    return _plain(value.tolist(), path, replaced)


def _plain(value, path, replaced: list):
    kind = type(value)
    if kind is float:
        if value - value == 0.0:          # finite (NaN and ±inf give NaN)
            return value
        replaced.append((_path_text(path), repr(value)))
        return None
    if kind is str or kind is int or kind is bool or value is None:
        return value
    if kind is dict:
        return {str(k): _plain(v, (path, str(k)), replaced) for k, v in value.items()}
    if kind is list or kind is tuple or kind is set:
        return [_plain(v, (path, i), replaced) for i, v in enumerate(value)]
    if isinstance(value, np.ndarray):
        return _array(value, path, replaced)
    if is_dataclass(value) and not isinstance(value, type):
        return _plain(asdict(value), path, replaced)
    if isinstance(value, dict):
        return {str(k): _plain(v, (path, str(k)), replaced) for k, v in value.items()}
    if isinstance(value, (list, tuple, set)):
        return [_plain(v, (path, i), replaced) for i, v in enumerate(value)]
    if isinstance(value, (np.bool_, bool)):
        return bool(value)
    if isinstance(value, (np.integer, int)):
        return int(value)
    if isinstance(value, (np.floating, float)):
        return _plain(float(value), path, replaced)
    if isinstance(value, (np.str_, str)):
        return str(value)
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, (np.complexfloating, complex)):
        raise TypeError(f"{_path_text(path)}: complex value {value!r} is not JSON; store real and "
                        "imaginary parts")
    raise TypeError(f"{_path_text(path)}: cannot write {type(value).__name__} to JSON")


def write_summary_json(path, summary: dict) -> Path:
    """Write ``summary`` as strict, indented UTF-8 JSON to ``path`` and return the path.

    numpy types are converted; NaN/±inf become ``null`` and, if any were, two keys are added:
    ``"null_note"`` (:data:`NULL_NOTE`) and ``"non_finite"``, which says where the nulls are, with
    list indices collapsed to ``[*]``: {json path: {"values": ["-inf", …], "count": n}}, e.g.
    ``{"$.points[*].erp.harmonics.level_db[*]": {"values": ["-inf"], "count": 12}}``.
    """
    path = Path(path)
    replaced: list = []
    data = to_jsonable(dict(summary), "$", replaced)
    if replaced:
        grouped: dict = {}
        for where, what in replaced:
            entry = grouped.setdefault(re.sub(r"\[\d+\]", "[*]", where), {"values": [], "count": 0})
            if what not in entry["values"]:
                entry["values"].append(what)
            entry["count"] += 1
        data["null_note"] = NULL_NOTE
        data["non_finite"] = grouped
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data, indent=2, allow_nan=False, ensure_ascii=False) + "\n",
                    encoding="utf-8")
    return path


def _format(value, fmt: str | None) -> str:
    if value is None:
        return "-"
    if isinstance(value, (bool, np.bool_)):
        return "yes" if value else "no"
    if isinstance(value, (float, np.floating)):
        value = float(value)
        if math.isnan(value):
            return "-"
        if math.isinf(value):
            return "-inf" if value < 0 else "inf"
        if fmt:
            return format(value, fmt)
        if value == 0 or 1e-3 <= abs(value) < 1e5:
            return f"{value:.4g}"
        return f"{value:.3e}"
    if fmt and isinstance(value, (int, np.integer)):
        return format(int(value), fmt)
    return str(value)


def console_table(rows, columns=None, formats=None, headers=None, max_rows: int | None = None) -> str:
    """Fixed-width text table of ``rows`` (list of dicts) for the end of a run.

    columns : keys to show, in order (default: keys of the first row, then new keys of later rows).
    formats : {key: format spec}, e.g. ``{"level_total_db": ".1f"}``; floats default to 4
        significant digits (scientific outside 1e-3…1e5); NaN/None → "-", bools → yes/no.
    headers : {key: header text} (default: the key).
    max_rows : show at most this many rows, then a "… (n more)" line.
    Numbers are right-aligned, text left-aligned. Returns the table (no trailing newline);
    an empty ``rows`` gives "(no rows)".
    """
    rows = list(rows)
    if not rows:
        return "(no rows)"
    if columns is None:
        columns = []
        for row in rows:
            columns += [k for k in row if k not in columns]
    formats, headers = formats or {}, headers or {}
    shown = rows if max_rows is None else rows[:max_rows]
    cells = [[_format(row.get(c), formats.get(c)) for c in columns] for row in shown]
    numeric = [all(isinstance(row.get(c), (int, float, np.number)) and not isinstance(row.get(c), bool)
                   or row.get(c) is None for row in shown) for c in columns]
    head = [str(headers.get(c, c)) for c in columns]
    widths = [max([len(h)] + [len(r[j]) for r in cells]) for j, h in enumerate(head)]

    def line(parts):
        return "  ".join(p.rjust(w) if num else p.ljust(w)
                         for p, w, num in zip(parts, widths, numeric)).rstrip()

    out = [line(head), "  ".join("-" * w for w in widths)] + [line(r) for r in cells]
    if max_rows is not None and len(rows) > max_rows:
        out.append(f"... ({len(rows) - max_rows} more)")
    return "\n".join(out)


def pruning_line(report: dict | None) -> str | None:
    """One console line for summary.json's ``contact_pruning`` (None when there is nothing to say),
    e.g. "contacts: 3 of 5 solved linearly (front_1, front_2 open; clip closed)"."""
    if not report or not report.get("enabled") or not report.get("contacts"):
        return None
    linear = [c for c in report["contacts"] if c["decision"] != "nonlinear"]
    if report.get("fallback"):
        first = report["violations"][0] if report.get("violations") else {}
        return (f"contacts: screening would solve {len(linear)} of {len(report['contacts'])} "
                f"linearly, but {first.get('contact')} {first.get('what', 'violated its decision')} "
                f"at {first.get('frequency_hz', float('nan')):.2f} Hz: solved with all contacts")
    if not report.get("applied"):
        return f"contacts: all {len(report['contacts'])} nonlinear (none screened open or closed)"
    groups = {}
    for c in linear:
        groups.setdefault(c["decision"], []).append(c["name"])
    what = "; ".join(f"{', '.join(names)} {decision}" for decision, names in groups.items())
    return f"contacts: {len(linear)} of {len(report['contacts'])} solved linearly ({what})"


def headline_level(worst: dict) -> str:
    """The headline level of summary.json's ``worst`` with its error bound: '97.0 ± 0.24 dB(A)'
    (``erp_error_db``, the point's ERP error estimate [dB]); '97.0 dB(A)' without an estimate;
    '-' for no sound."""
    text = level_text(worst.get("erp_level_dba"))
    error = worst.get("erp_error_db")
    if text == "-":
        return text
    if error is not None and math.isfinite(error):
        text += f" ± {error:.2f}"
    return f"{text} dB(A)"


def headline_notes(worst: dict) -> list[str]:
    """What the headline level of summary.json's ``worst`` does not carry: 'stability not
    assessed' (``stable`` None: the loudest point is the loudest one not found unstable),
    'error interpolated' (its error bound is the larger of two estimated neighbours'),
    'error unknown' (its estimate's re-solve failed), ``error_note`` when given (no bound: a
    contact's impact the harmonics do not resolve), 'error not estimated' (none asked or no
    contacts). Keys absent (older summaries): no note."""
    notes = []
    if "stable" in worst and worst["stable"] is None:
        notes.append("stability not assessed")
    if worst.get("error_interpolated"):
        notes.append("error interpolated")
    if worst.get("error_note"):        # no bound, and why (an impact H does not resolve)
        notes.append(worst["error_note"])
    elif "erp_error_db" in worst and worst["erp_error_db"] is None:
        notes.append("error unknown" if worst.get("error_estimated") else "error not estimated")
    return notes


def loudest_lines(worst: dict | None, count: int = 5) -> list[str]:
    """Console lines of summary.json's ``worst``: the headline at the loudest (converged, not
    unstable) point and the first ``count`` lines of its contact ranking."""
    if not worst:
        return []
    if worst.get("index") is None:
        return [f"loudest point: none ({worst.get('note', 'no converged, not unstable point')})"]
    notes = "".join(f" ({note})" for note in headline_notes(worst))
    lines = [f"loudest point: {headline_level(worst)} "
             f"({level_text(worst.get('erp_level_db'), unit='dB re 1 pW')}) at "
             f"{worst['frequency_hz']:.2f} Hz{notes}"]
    lines += [f"  {line}" for line in (worst.get("ranking") or [])[:count]]
    excitation = worst.get("excitation")
    if excitation and worst.get("ranking"):
        share = excitation.get("share_a")
        share = "-" if share is None or not math.isfinite(share) else f"{round(100 * share)} %"
        lines.append(f"  (the excitation through the structure without contact forces: "
                     f"{level_text(excitation.get('level_dba'), unit='dB(A)')}, {share})")
    return lines


def stability_line(points) -> str | None:
    """One console line when converged points of summary.json have no stability verdict
    (``stable`` None with a ``stability_note``: '-' in the table), naming how many, the first
    frequency and its note; None when every converged point has a verdict or none was asked."""
    unresolved = [p for p in points if p.get("converged") and p.get("stable") is None
                  and p.get("stability_note")]
    if not unresolved:
        return None
    first = unresolved[0]
    converged = sum(bool(p.get("converged")) for p in points)
    return (f"stability: not resolved at {len(unresolved)} of {converged} converged points "
            f"('-' in the stable column; stability_note in summary.json), e.g. "
            f"{first['frequency_hz']:.2f} Hz: {first['stability_note']}; raise solver.harmonics "
            "or check a frequency with `sarfe verify`")
