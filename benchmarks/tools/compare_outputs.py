"""Compare two sarfe result folders number by number (issue 15: the output files of a faster tree
must hold main's numbers).

    python benchmarks/tools/compare_outputs.py REFERENCE NEW [--rtol 1e-12] [--json OUT.json] [--skip KEY]

Every file of REFERENCE must exist in NEW (and no file more), and:

- VTU (ERP maps, animation frames; read by VTK through pyvista, which reads the appended raw +
  LZ4 encoding the writer uses): the same points, cells and array names, dtypes and shapes; per
  point/field array the relative difference max|a − b| / max|a| (an array against its own largest
  magnitude; integer arrays must be equal);
- PVD, table.txt: the same text; report.html: reported (not counted) when its text differs
  once the creation time is dropped (its estimate table shows each estimate's seconds);
- response.h5 (h5py): the same datasets, dtypes, shapes and attributes (``created_utc`` and
  ``sarfe_version`` aside); floats by the same array-wise relative difference (NaN where NaN,
  ±inf where ±inf), everything else equal;
- summary.json: the same tree (``timings_s``, ``created_utc``, ``sarfe_version`` aside); each
  number by |a − b| / max(|a|, |b|), except numbers that are round-off by definition
  (``superposition_error``: ‖Σ parts − total‖ / ‖total‖, ~1e-16), compared absolutely;
- PNG plots: reported when their bytes differ (not counted: the pixels of a line plot of equal
  numbers are equal, but the check is informative only).

Prints one line per kind with the worst relative difference and where, and exits 1 when any
exceeds ``--rtol`` or a structural difference was found.
"""
from __future__ import annotations

import argparse
import json
import math
import pathlib
import re
import sys

import numpy as np

SKIP_KEYS = {"timings_s", "created_utc", "sarfe_version", "case_file",
             "seconds",       # (error_estimate.seconds: the estimate's own wall time)
             "workers"}       # how the run was scheduled (processes, points finished during
                              # the sweep): depends on the machine's load, not a result
ABSOLUTE_KEYS = {"superposition_error"}     # round-off quantities: |a − b| ≤ rtol
SKIP_ATTRS = {"created_utc", "sarfe_version"}


class Report:
    def __init__(self, rtol):
        self.rtol, self.worst, self.problems, self.notes = rtol, {}, [], []

    def number(self, kind, where, value):
        if not (value <= self.worst.get(kind, (-1.0, None))[0]):
            self.worst[kind] = (value, where)

    def problem(self, text):
        self.problems.append(text)

    def failed(self):
        return bool(self.problems) or any(not (v <= self.rtol) for v, _ in self.worst.values())


def array_difference(a, b) -> float:
    """max|a − b| / max|a| over the finite entries; inf when NaN/inf sit at different places."""
    a, b = np.asarray(a), np.asarray(b)
    if a.shape != b.shape:
        return math.inf
    if a.size == 0:
        return 0.0
    if a.dtype.kind not in "fc":
        return 0.0 if np.array_equal(a, b) else math.inf
    finite = np.isfinite(a)
    if not np.array_equal(finite, np.isfinite(b)) or not np.array_equal(a[~finite], b[~finite],
                                                                         equal_nan=True):
        return math.inf
    if not finite.any():
        return 0.0
    scale = np.abs(a[finite]).max()
    diff = np.abs(a[finite] - b[finite]).max()
    return float(diff / scale) if scale > 0 else float(diff)


def compare_vtu(a, b, name, report):
    import pyvista as pv

    x, y = pv.read(a), pv.read(b)
    if x.n_points != y.n_points or x.n_cells != y.n_cells:
        report.problem(f"{name}: {x.n_points}/{x.n_cells} vs {y.n_points}/{y.n_cells} points/cells")
        return
    report.number("vtu", f"{name}: points", array_difference(x.points, y.points))
    if not np.array_equal(np.asarray(x.cells), np.asarray(y.cells)):
        report.problem(f"{name}: cells differ")
    for label, first, second in (("point", x.point_data, y.point_data),
                                 ("field", x.field_data, y.field_data)):
        if set(first.keys()) != set(second.keys()):
            odd = sorted(set(first.keys()) ^ set(second.keys()))
            report.problem(f"{name}: {label} arrays {odd}")
            continue
        for key in first.keys():
            p, q = np.asarray(first[key]), np.asarray(second[key])
            if p.dtype != q.dtype or p.shape != q.shape:
                report.problem(f"{name}: {key} {p.dtype}{p.shape} vs {q.dtype}{q.shape}")
                continue
            report.number("vtu", f"{name}: {key}", array_difference(p, q))


def compare_h5(a, b, report):
    import h5py

    with h5py.File(a) as fa, h5py.File(b) as fb:
        names_a, names_b = [], []
        fa.visit(names_a.append)
        fb.visit(names_b.append)
        if sorted(names_a) != sorted(names_b):
            report.problem(f"response.h5: objects {sorted(set(names_a) ^ set(names_b))}")
        for name in ["/"] + names_a:
            if name not in fb:
                continue
            p, q = fa[name], fb[name]
            keys = set(p.attrs) - SKIP_ATTRS
            if keys != set(q.attrs) - SKIP_ATTRS:
                report.problem(f"response.h5 {name}: attributes differ")
            for key in keys & set(q.attrs):
                u, v = np.asarray(p.attrs[key]), np.asarray(q.attrs[key])
                if u.dtype.kind in "fc":
                    report.number("h5", f"{name}@{key}", array_difference(u, v))
                elif not np.array_equal(u, v):
                    report.problem(f"response.h5 {name}@{key}: {u!r} vs {v!r}")
            if isinstance(p, h5py.Dataset):
                u, v = p[()], q[()]
                if np.asarray(u).dtype != np.asarray(v).dtype or np.shape(u) != np.shape(v):
                    report.problem(f"response.h5 {name}: dtype/shape differ")
                    continue
                report.number("h5", name, array_difference(u, v))


def compare_json(x, y, path, report):
    if isinstance(x, dict) and isinstance(y, dict):
        keys = set(x) - SKIP_KEYS
        if keys != set(y) - SKIP_KEYS:
            report.problem(f"summary.json {path}: keys {sorted(keys ^ (set(y) - SKIP_KEYS))}")
        for key in sorted(keys & set(y)):
            compare_json(x[key], y[key], f"{path}.{key}", report)
    elif isinstance(x, list) and isinstance(y, list):
        if len(x) != len(y):
            report.problem(f"summary.json {path}: {len(x)} vs {len(y)} entries")
            return
        for i, (p, q) in enumerate(zip(x, y)):
            compare_json(p, q, f"{path}[{i}]", report)
    elif (isinstance(x, (int, float)) and isinstance(y, (int, float))
          and not isinstance(x, bool) and not isinstance(y, bool)):
        leaf = path.rsplit(".", 1)[-1]
        if leaf in ABSOLUTE_KEYS:
            report.number("json (absolute)", path, abs(x - y))
            return
        scale = max(abs(x), abs(y))
        report.number("json", path, abs(x - y) / scale if scale > 0 else 0.0)
    elif x != y:
        report.problem(f"summary.json {path}: {x!r} vs {y!r}")


TIMESTAMP = re.compile(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d[^ ]*")


def compare_text(a, b, name, report, informative=False):
    p, q = (TIMESTAMP.sub("", path.read_text(encoding="utf-8")) for path in (a, b))
    if p != q:
        lines = sum(u != v for u, v in zip(p.splitlines(), q.splitlines()))
        if informative:
            report.notes.append(f"{name}: {lines} lines differ")
        else:
            report.problem(f"{name}: text differs ({lines} lines)")


def compare_folders(ref: pathlib.Path, new: pathlib.Path, rtol=1e-12) -> Report:
    report = Report(rtol)
    files_a = {p.relative_to(ref) for p in ref.rglob("*") if p.is_file()}
    files_b = {p.relative_to(new) for p in new.rglob("*") if p.is_file()}
    for extra in sorted(files_a ^ files_b):
        if extra.name.startswith("."):      # e.g. the result-folder marker
            continue
        report.problem(f"only in {'reference' if extra in files_a else 'new'}: {extra}")
    for name in sorted(files_a & files_b):
        a, b = ref / name, new / name
        if name.suffix == ".vtu":
            compare_vtu(a, b, str(name), report)
        elif name.suffix == ".h5":
            compare_h5(a, b, report)
        elif name.name == "summary.json":
            compare_json(json.loads(a.read_text()), json.loads(b.read_text()), "", report)
        elif name.suffix in (".pvd", ".txt"):
            compare_text(a, b, str(name), report)
        elif name.suffix == ".html":
            compare_text(a, b, str(name), report, informative=True)
        elif name.suffix == ".png":
            if a.read_bytes() != b.read_bytes():
                report.notes.append(f"{name}: PNG bytes differ")
    report.files = len(files_a & files_b)
    return report


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("reference", type=pathlib.Path)
    parser.add_argument("new", type=pathlib.Path)
    parser.add_argument("--rtol", type=float, default=1e-12)
    parser.add_argument("--json", type=pathlib.Path, help="write the worst differences here")
    parser.add_argument("--skip", action="append", default=[],
                        help="a summary.json key to leave out as well (e.g. workers, when the "
                             "two runs used different solver.workers)")
    args = parser.parse_args(argv)
    SKIP_KEYS.update(args.skip)
    report = compare_folders(args.reference, args.new, args.rtol)
    print(f"{args.new}: {report.files} files compared with {args.reference}")
    for kind, (value, where) in sorted(report.worst.items()):
        print(f"  {kind}: worst relative difference {value:.3g} ({where})")
    for line in report.problems:
        print(f"  PROBLEM {line}")
    for line in report.notes:
        print(f"  note: {line}")
    print("  verdict:", "DIFFERENT" if report.failed() else f"same within {args.rtol:g}")
    if args.json:
        args.json.write_text(json.dumps({"files": report.files, "worst": report.worst,
                                         "problems": report.problems, "notes": report.notes,
                                         "same": not report.failed()}, indent=1))
    return 1 if report.failed() else 0


if __name__ == "__main__":
    sys.exit(main())
