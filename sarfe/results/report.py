"""``report.html``: one self-contained page a design review reads top to bottom.

    write_report_html(path, summary: dict, images: {key: PNG path}, notes: dict | None,
                      sounds: {WAV name: path} | None) -> Path

Built from the jinja2 template ``templates/report.html.j2`` (package data) with autoescaping;
every image is embedded as a base64 PNG data URI, each sound (sound.wav, sound_with_background.wav)
as a base64 WAV data URI in an <audio controls> player, and the CSS is inline, so the page needs
no network and no other file (≈ 0.35 MB per 3 s of sound). The first screen answers the review
(section ``verdict``): audible or not at the occupant over the case's background (margin, SPL,
loudness), the loudest point (converged, not found unstable, highest dB(A): ``summary["worst"]``)
with its ERP error bound and notes, the target, the contacts' share against the panel's own
structure-borne share, the top contact, the change that helps most, and the two players. Then:
case and model, what would fix it (per contact: share, level alone, audible alone, onset factor,
dynamic tolerance, level change for +10 % of each parameter), audibility per band, accuracy estimate, ERP vs frequency with the linear baseline and ``output.target_dba``, the contact
ranking, third-octave spectrum, contact forces and stick/slip, ERP map (dB) and deflection at the
loudest point, and the table of all points. Levels of a motionless surface read "-".

Image keys the template knows: ``erp_sweep``, ``contributions``, ``audibility``, ``third_octave``,
``erp_spectrum``, ``contact_forces``, ``friction``, ``erp_map``, ``deflection``, ``contact_map``.
"""
from __future__ import annotations

import base64
import math
from pathlib import Path

from sarfe.erp.contributions import share_text
from sarfe.results.summary import (headline_level, headline_notes, level_text, shown_level,
                                   to_jsonable)

__all__ = ["write_report_html", "render_report_html", "data_uri", "environment"]

PARAMETER_SHORT = {"gap_m": "gap", "normal_stiffness_N_m": "kₙ", "tangential_stiffness_N_m": "kₜ",
                   "friction_coefficient": "μ", "preload_N": "preload"}
PARAMETER_LABELS = {"gap_m": "gap", "normal_stiffness_N_m": "normal stiffness",
                    "tangential_stiffness_N_m": "tangential stiffness",
                    "friction_coefficient": "friction coefficient", "preload_N": "preload"}


def data_uri(path, mime: str = "image/png") -> str:
    """data:<mime>;base64,… of a file (a PNG by default; 'audio/wav' for the sound files)."""
    return f"data:{mime};base64," + base64.b64encode(Path(path).read_bytes()).decode("ascii")


def _number(value, fmt=".3g", scale=1.0):
    if value is None or isinstance(value, bool):
        return "-" if value is None else ("yes" if value else "no")
    try:
        value = float(value)
    except (TypeError, ValueError):
        return str(value)
    if not math.isfinite(value):
        return "-"
    return format(value * scale, fmt)


def _percent(value):
    return _number(value, ".0f", 100.0) + (" %" if _number(value) != "-" else "")


def environment():
    """The jinja2 Environment of the report templates (autoescape on, the report's filters)."""
    import jinja2

    env = jinja2.Environment(loader=jinja2.PackageLoader("sarfe.results", "templates"),
                             autoescape=jinja2.select_autoescape(["html", "j2"]),
                             undefined=jinja2.ChainableUndefined, trim_blocks=True,
                             lstrip_blocks=True)
    env.filters["level"] = level_text
    env.filters["num"] = _number
    env.filters["percent"] = _percent
    env.filters["mm"] = lambda v: _number(v, ".3f", 1e3)
    env.filters["yesno"] = lambda v: "-" if v is None else ("yes" if v else "no")
    env.filters["share"] = share_text
    env.filters["signed"] = lambda v, fmt=".1f": (   # None/Undefined/NaN → "-"
        format(v, "+" + fmt) if isinstance(v, (int, float)) and math.isfinite(v) else "-")
    return env


def _ten_percent(sensitivities) -> dict:
    """{case key: ΔL_A [dB(A)] for +10 % of the parameter} of a contact's sensitivities."""
    relative = (sensitivities or {}).get("per_relative_change_dba") or {}
    return {k: 0.1 * v for k, v in relative.items() if v is not None and math.isfinite(v)}


def _ranking_rows(point) -> list:
    """Source rows of a point's contributions (ranked by A-weighted share) joined with the point's
    contact dynamics, the audibility of each source alone, its onset factor, linear risk and
    level sensitivities (what would fix it)."""
    contributions = (point or {}).get("contributions") or {}
    if not contributions.get("available"):
        return []
    contacts = {c["name"]: c for c in point.get("contacts", [])}
    linear = {c["name"]: c for c in (point.get("linear") or {}).get("contacts", [])}
    alone = {s["name"]: s for s in (point.get("audibility") or {}).get("sources", [])}
    sources = sorted(contributions["sources"],
                     key=lambda s: -(s["share_a"] if s["share_a"] is not None
                                     and math.isfinite(s["share_a"]) else -math.inf))
    rows = []
    for s in sources:
        c = contacts.get(s["name"], {})
        rows.append({"name": s["name"], "level_db": s["level_db"], "level_dba": s["level_dba"],
                     "share": s["share"], "share_a": s["share_a"],
                     "part_level_dba": s.get("part_level_dba"),
                     "type": c.get("type", "structure-borne" if s["name"] == "excitation"
                                   else ""),
                     "audible_alone": (alone.get(s["name"]) or {}).get("audible"),
                     "impacts": c.get("impacts_per_period"),
                     "peak_force_N": c.get("peak_force_N"),
                     "slip_distance_m": c.get("slip_distance_m"),
                     "dissipated_energy_J": c.get("dissipated_energy_J"),
                     "onset": c.get("onset") or {},
                     "dynamic_tolerance_m": linear.get(s["name"], {}).get("dynamic_tolerance_m"),
                     "ten_percent": _ten_percent(c.get("sensitivities"))})
    return rows


def _band_rows(point) -> list:
    bands = (point or {}).get("bands") or {}
    nl, lin = bands.get("nonlinear") or {}, bands.get("linear") or {}
    linear = dict(zip(lin.get("nominal_hz", []), zip(lin.get("level_db", []),
                                                     lin.get("level_dba", []))))
    rows = []
    for f, lo, hi, db, dba in zip(nl.get("nominal_hz", []), nl.get("lower_hz", []),
                                  nl.get("upper_hz", []), nl.get("level_db", []),
                                  nl.get("level_dba", [])):
        if shown_level(db) is None and f not in linear:
            continue
        rows.append({"nominal_hz": f, "lower_hz": lo, "upper_hz": hi, "level_db": db,
                     "level_dba": dba, "linear_dba": linear.get(f, (None, None))[1]})
    return rows


def render_report_html(summary: dict, images: dict | None = None, notes: dict | None = None,
                       sounds: dict | None = None) -> str:
    """The report page (module docstring) as a string. ``sounds``: {WAV file name: path} embedded
    as data URIs in <audio> players (the page stays one offline file)."""
    summary = to_jsonable(dict(summary))       # plain lists and numbers; NaN/±inf → None ("-")
    images = {k: data_uri(v) for k, v in (images or {}).items() if v and Path(v).exists()}
    audio = {Path(k).stem: data_uri(v, "audio/wav") for k, v in (sounds or {}).items()
             if v and Path(v).exists()}
    points = summary.get("points") or []
    worst = summary.get("worst") or {}
    index = worst.get("index")
    loudest = points[index] if index is not None and 0 <= index < len(points) else None
    case_data = summary.get("case_data") or {}
    output = case_data.get("output") or {}
    estimates = [p for p in points if isinstance(p.get("error_estimate"), dict)
                 and "failed" not in p["error_estimate"]]
    ranking = _ranking_rows(loudest)
    hearing = summary.get("audibility_model") or {}
    background = hearing.get("background")
    background_label = "no background (the threshold in quiet only)" \
        if background in (None, "none") else \
        f"the {Path(background).stem} background ({_number(hearing.get('background_dba'), '.0f')} dB(A))"
    parameters = [k for k in PARAMETER_LABELS if any(k in r["ten_percent"] for r in ranking)]
    template = environment().get_template("report.html.j2")
    return template.render(
        audio=audio, parameters=parameters, background_label=background_label,
        parameter_short=PARAMETER_SHORT, parameter_labels=PARAMETER_LABELS,
        audibility=worst.get("audibility") or {}, model_of_hearing=summary.get(
            "audibility_model") or {}, target=summary.get("target"),
        s=summary, points=points, worst=worst, loudest=loudest, images=images,
        notes=notes or {}, target_dba=output.get("target_dba"),
        headline_level=headline_level(worst), headline_notes=headline_notes(worst),
        ranking=ranking, bands=_band_rows(loudest), estimates=estimates,
        excitation=case_data.get("excitation") or {}, contacts=summary.get("contacts") or [],
        model=summary.get("model") or {}, solver=summary.get("solver") or {})


def write_report_html(path, summary: dict, images: dict | None = None,
                      notes: dict | None = None, sounds: dict | None = None) -> Path:
    """Write :func:`render_report_html` to ``path`` (UTF-8) and return the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(render_report_html(summary, images, notes, sounds), encoding="utf-8")
    return path
