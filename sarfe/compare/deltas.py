"""Level differences of result variants against the first one (``sarfe compare``).

For variant b against the reference a (the first result named), at every frequency point both
hold (frequencies equal within 1e-9 relative):

    delta_dba(f)          = L_A,b(f) − L_A,a(f)                         total ERP level [dB(A)]
    delta_dba(f, contact) = L_A,b,c(f) − L_A,a,c(f)                     contact contribution [dB(A)]
    delta_dba(f, band)    = L_A,b,k(f) − L_A,a,k(f)                     third-octave band k [dB(A)]

and for the loudest point of each (``worst``): the difference of the two headline levels (which
may sit at different frequencies). A level of zero power is −inf dB; the difference of two −inf
levels is 0 (nothing radiated in either), of one −inf and a finite level ±inf, written as null
in JSON. Contacts or bands only one variant has are listed with their level and delta null.
"""
from __future__ import annotations

import math

import numpy as np

from sarfe.compare.result_reader import Result, level

FREQUENCY_RTOL = 1e-9


def delta(b: float, a: float) -> float:
    """b − a in dB, with −inf − (−inf) = 0 (equal silence)."""
    if a == b:
        return 0.0
    return b - a


def headline(result: Result) -> dict:
    """The result's loudest point: level [dB(A)], its error bound [dB], frequency [Hz], ranking."""
    worst = result.worst
    ranking = worst.get("ranking") or []
    return {"case": result.case, "path": str(result.path),
            "level_dba": level(worst.get("erp_level_dba")),
            "error_db": worst.get("erp_error_db"),
            "frequency_hz": worst.get("frequency_hz"),
            "top_contact": ranking[0] if ranking else None,
            "all_converged": bool(result.summary.get("all_converged", True)),
            "points": len(result.points)}


def matched_points(a: Result, b: Result) -> list[tuple]:
    """Pairs (point of a, point of b) at the same frequency (within FREQUENCY_RTOL)."""
    fb = np.array([p.frequency_hz for p in b.points])
    pairs = []
    for pa in a.points:
        hit = np.flatnonzero(np.abs(fb - pa.frequency_hz) <= FREQUENCY_RTOL * abs(pa.frequency_hz))
        if hit.size:
            pairs.append((pa, b.points[int(hit[0])]))
    return pairs


def _keyed(da: dict, db: dict) -> list[dict]:
    """Rows {key, a, b, delta_dba} over the union of the keys (delta None if one side lacks it)."""
    rows = []
    for key in list(da) + [k for k in db if k not in da]:
        va, vb = da.get(key), db.get(key)
        rows.append({"key": key, "a_dba": va, "b_dba": vb,
                     "delta_dba": None if va is None or vb is None else delta(vb, va)})
    return rows


def compare_pair(a: Result, b: Result) -> dict:
    """Every delta of ``b`` against ``a`` (see the module docstring) as a JSON-ready dict."""
    pairs = matched_points(a, b)
    points = []
    for pa, pb in pairs:
        points.append({
            "frequency_hz": pa.frequency_hz, "a_dba": pa.level_dba, "b_dba": pb.level_dba,
            "delta_dba": delta(pb.level_dba, pa.level_dba),
            "contacts": [dict(contact=r.pop("key"), **r) for r in _keyed(pa.contacts, pb.contacts)],
            "bands": [dict(nominal_hz=r.pop("key"), **r) for r in _keyed(pa.bands, pb.bands)],
            "sources": [dict(source=r.pop("key"), **r) for r in _keyed(pa.sources, pb.sources)]})
    ha, hb = headline(a), headline(b)
    matched_a = {pa.index for pa, _ in pairs}
    return {
        "reference": a.label, "variant": b.label,
        "worst_delta_dba": delta(hb["level_dba"], ha["level_dba"]),
        "points": points,
        "unmatched_frequencies_hz": [p.frequency_hz for p in a.points if p.index not in matched_a]
        + [p.frequency_hz for p in b.points
           if all(abs(p.frequency_hz - q.frequency_hz) > FREQUENCY_RTOL * abs(p.frequency_hz)
                  for q in a.points)],
        "max_abs_delta_dba": max_abs(points),
    }


def all_deltas(point_rows: list[dict]) -> list[float]:
    """Every finite-or-inf delta of a pair's points (total, contacts, bands, sources) — for tests
    and the headline "largest change"."""
    out = []
    for p in point_rows:
        out.append(p["delta_dba"])
        for group in ("contacts", "bands", "sources"):
            out += [r["delta_dba"] for r in p[group] if r["delta_dba"] is not None]
    return out


def max_abs(point_rows: list[dict]) -> float | None:
    """Largest |delta_dba| of the point totals (None with no common point)."""
    values = [abs(p["delta_dba"]) for p in point_rows if not math.isnan(p["delta_dba"])]
    return max(values) if values else None


def compare_all(results: list[Result]) -> dict:
    """compare.json's content: headlines of all variants and each variant's deltas vs the first."""
    reference = results[0]
    return {"reference": reference.label,
            "headlines": [headline(r) for r in results],
            "comparisons": [compare_pair(reference, r) for r in results[1:]]}
