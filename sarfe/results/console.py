"""What ``sarfe solve`` prints at the end of a run: a summary that fits 80 columns and answers the
review (verdict, loudest point with its ±, target, contacts' share against the structure-borne
share, the contact ranking with onset and linear risk, the change that helps most), and the one
line of ``--quiet``. The full per-point table with every contact column goes to table.txt.

    summary_lines(summary, rows) -> [str]        the console summary (each ≤ WIDTH characters)
    quiet_line(summary) -> str                   one result line for --quiet
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from sarfe.erp.contributions import share_text
from sarfe.results.summary import console_table, headline_level, headline_notes, level_text

__all__ = ["WIDTH", "summary_lines", "quiet_line", "verdict_text", "points_table",
           "shown_points"]

WIDTH = 80
MAX_ROWS = 12       # points in the console table of a sweep (all of them in table.txt)
PARAMETER_LABELS = {"gap_m": "gap", "normal_stiffness_N_m": "normal stiffness",
                    "tangential_stiffness_N_m": "tangential stiffness",
                    "friction_coefficient": "friction coefficient", "preload_N": "preload"}


def _finite(value) -> bool:
    return value is not None and not isinstance(value, bool) and math.isfinite(value)


def _fit(line: str, width: int = WIDTH) -> str:
    return line if len(line) <= width else line[:width - 1] + "…"


def background_label(summary) -> str:
    """'ev_80kmh (61 dB(A))', or 'quiet (threshold in quiet only)' without a background."""
    hearing = summary.get("audibility_model") or {}
    name = hearing.get("background")
    if name in (None, "none"):
        return "quiet (threshold in quiet only)"
    total = hearing.get("background_dba")
    return f"{Path(name).stem}" + (f" ({total:.0f} dB(A))" if _finite(total) else "")


def verdict_text(summary) -> list:
    """['AUDIBLE over ev_80kmh (61 dB(A)): margin +38.1 dB in the 400 Hz band', '  at the
    occupant 96.5 dB(A), 180 sone'] of the loudest point; [] without an assessment."""
    audibility = (summary.get("worst") or {}).get("audibility") or {}
    if audibility.get("audible") is None:
        return []
    word = "AUDIBLE" if audibility["audible"] else "NOT AUDIBLE"
    margin = audibility.get("margin_db")
    band = audibility.get("loudest_band_hz")
    text = f"{word} over {background_label(summary)}"
    if _finite(margin):
        text += f": margin {margin:+.1f} dB" + (f" in the {band:g} Hz band" if _finite(band)
                                                else "")
    loudness = audibility.get("loudness_sone")
    capped = " (at least: bands beyond ISO 532-1's 120 dB)" if audibility.get("loudness_capped") \
        else ""
    return [text, f"  at the occupant {level_text(audibility.get('spl_dba'), unit='dB(A)')}"
            + (f", {loudness:.3g} sone{capped}" if _finite(loudness) else "")]


def target_text(summary) -> str:
    target = summary.get("target")
    if not target:
        return ""
    if target["exceeded"]:
        text = f"target {target['target_dba']:.1f} dB(A): EXCEEDED by " \
               f"{target['exceeded_by_db']:.1f} dB (exit code 4)"
    else:
        text = f"target {target['target_dba']:.1f} dB(A): met"
        if _finite(target.get("exceeded_by_db")):
            text += f" ({-target['exceeded_by_db']:.1f} dB below)"
    return text + (" — within the error bound" if target.get("within_error_bound") else "")


def contact_lines(summary, count: int = 5) -> list:
    """The first ``count`` contacts of the loudest point by A-weighted share: share = the level of
    its part of the total (alone: what it radiates by itself), onset factor, dynamic tolerance."""
    worst = summary.get("worst") or {}
    index = worst.get("index")
    points = summary.get("points") or []
    if index is None or not points:
        return []
    point = points[index]
    contributions = point.get("contributions") or {}
    if not contributions.get("available"):
        return []
    linear = {c["name"]: c for c in (point.get("linear") or {}).get("contacts", [])}
    contacts = {c["name"]: c for c in point.get("contacts", [])}
    sources = [s for s in contributions["sources"] if s["name"] in contacts]
    sources.sort(key=lambda s: -s["share_a"] if _finite(s["share_a"]) else math.inf)
    width = min(max((len(s["name"]) for s in sources), default=4), 14)
    lines = []
    for s in sources[:count]:
        share = share_text(s["share_a"])
        part = s.get("part_level_dba")
        part = f"= {part:5.1f}" if _finite(part) and share not in ("0 %", "- %") \
            and not share.startswith("-") else " " * 7
        alone = level_text(s.get("level_dba"))
        onset = (contacts[s["name"]].get("onset") or {}).get("factor")
        onset = f"{onset:.3g}" if _finite(onset) else ("never" if onset == math.inf else "-")
        tolerance = linear.get(s["name"], {}).get("dynamic_tolerance_m")
        tolerance = f"{1e3 * tolerance:+.3f} mm" if _finite(tolerance) else "-"
        lines.append(_fit(f"  {s['name'][:width]:<{width}} {share:>6} {part} (alone {alone:>5})"
                          f"  onset {onset:>5}  tol {tolerance:>9}"))
    if len(sources) > count:
        lines.append(f"  ({len(sources) - count} more: table.txt, report.html)")
    return lines


def best_change_text(summary) -> str:
    best = (summary.get("worst") or {}).get("best_change")
    if not best:
        return ""
    label = PARAMETER_LABELS.get(best["parameter"], best["parameter"])
    return _fit(f"change that helps most: {best['contact']} {label} {best['change']} → "
                f"{best['level_change_dba']:+.1f} dB(A) (linear estimate)")


def shown_points(rows, max_rows: int = MAX_ROWS) -> list:
    """Indices of the points the console shows: all when there are at most ``max_rows``, else the
    band's two ends and ``max_rows`` − 2 others — the level's peaks loudest first, then points
    spread over the sweep — in sweep order (every point is in table.txt)."""
    n = len(rows)
    if n <= max_rows:
        return list(range(n))
    levels = np.array([row.get("erp_dba") if _finite(row.get("erp_dba")) else -np.inf
                       for row in rows], dtype=float)
    peak = np.r_[False, (levels[1:-1] > levels[:-2]) & (levels[1:-1] >= levels[2:]), False]
    peaks = [int(i) for i in np.flatnonzero(peak)[np.argsort(-levels[peak], kind="stable")]]
    spread = [int(i) for i in np.linspace(0, n - 1, max_rows).round()]
    chosen = [0, n - 1]
    for i in peaks[:max_rows - 2] + spread:
        if len(chosen) < max_rows and i not in chosen:
            chosen.append(i)
    return sorted(chosen)


def points_table(rows, max_rows: int = MAX_ROWS) -> str:
    """The per-point table in ≤ 80 columns: frequency, converged, stable, ERP dB(A) with its ±,
    the linear baseline [dB(A)], the SPL at the occupant [dB(A)], heard, the audibility margin
    [dB]; a long sweep shows :func:`shown_points` and a line naming table.txt (every point)."""
    count = len(rows)
    rows = [rows[i] for i in shown_points(rows, max_rows)]
    columns = ["frequency_hz", "converged", "stable", "erp_dba", "erp_error_db",
               "linear_erp_dba", "occupant_spl_dba", "audible", "audibility_margin_db"]
    headers = {"frequency_hz": "f [Hz]", "converged": "conv", "erp_dba": "ERP [dB(A)]",
               "erp_error_db": "±dB", "linear_erp_dba": "linear", "occupant_spl_dba":
               "SPL [dB(A)]", "audible": "heard", "audibility_margin_db": "margin"}
    formats = {"frequency_hz": ".2f", "erp_dba": ".1f", "erp_error_db": ".2f",
               "linear_erp_dba": ".1f", "occupant_spl_dba": ".1f", "audibility_margin_db": "+.1f"}
    shown = []
    for row in rows:
        r = dict(row)
        for key in ("erp_dba", "linear_erp_dba", "occupant_spl_dba"):
            value = r.get(key)
            r[key] = value if _finite(value) and value >= -100 else None
        if not _finite(r.get("audibility_margin_db")):
            r["audibility_margin_db"] = None
        if not _finite(r.get("erp_error_db")):
            r["erp_error_db"] = None
        elif r.get("erp_error_interpolated"):
            r["erp_error_db"] = f"~{r['erp_error_db']:.2f}"
        shown.append(r)
    if not any(r.get("erp_error_db") is not None for r in shown):
        columns.remove("erp_error_db")
    table = console_table(shown, columns=columns, formats=formats, headers=headers)
    if len(shown) < count:
        table += f"\n({len(shown)} of {count} points: ends, peaks, spread; all in table.txt)"
    return table


def summary_lines(summary, rows) -> list:
    """The console summary of a run (module docstring), each line ≤ :data:`WIDTH`."""
    lines = points_table(rows).splitlines()
    worst = summary.get("worst") or {}
    lines += [_fit(line) for line in verdict_text(summary)]
    if worst.get("index") is None:
        lines.append(f"loudest point: none ({worst.get('note', 'no converged point')})")
        return lines
    notes = "".join(f" ({note})" for note in headline_notes(worst))
    lines.append(_fit(f"loudest point: {headline_level(worst)} ERP at "
                      f"{worst['frequency_hz']:.2f} Hz{notes}"))
    target = target_text(summary)
    if target:
        lines.append(_fit(f"  {target}"))
    if _finite(worst.get("contacts_share_a")):
        lines.append(_fit(f"who makes it: contacts {share_text(worst['contacts_share_a'])}, the "
                          f"panel's own structure-borne response "
                          f"{share_text(worst.get('structure_share_a'))}"))
        lines += contact_lines(summary)
    best = best_change_text(summary)
    if best:
        lines.append(best)
    return lines


def quiet_line(summary) -> str:
    """One line: case, loudest level with ± and frequency, audible or not with the margin, the
    target verdict, the exit code."""
    worst = summary.get("worst") or {}
    parts = [str(summary.get("case"))]
    if worst.get("index") is None:
        parts.append("no converged point")
    else:
        parts.append(f"{headline_level(worst)} at {worst['frequency_hz']:.2f} Hz")
        audibility = worst.get("audibility") or {}
        if audibility.get("audible") is not None:
            margin = audibility.get("margin_db")
            parts.append(("audible" if audibility["audible"] else "not audible")
                         + (f" ({margin:+.1f} dB)" if _finite(margin) else ""))
    target = summary.get("target")
    if target:
        parts.append(f"target {target['target_dba']:.1f} dB(A) "
                     + ("exceeded" if target["exceeded"] else "met"))
    parts.append(f"exit {summary.get('exit_code')}")
    return "; ".join(parts)
