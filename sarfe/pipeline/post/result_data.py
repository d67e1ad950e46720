"""Arrays of the per-point post-processing for the result files: the response.h5 groups of the
contributions, contact dynamics, third-octave bands, audibility and margins (onset, linear risk,
sensitivities), and the contact fields of the VTU."""
from __future__ import annotations

import numpy as np

from sarfe.erp.bands import band_frequencies, nominal_frequency
from sarfe.hbm.harmonics import time_samples
from sarfe.pipeline.post.margin_records import CASE_PARAMETERS
from sarfe.results.vtk import contact_point_values


def contact_pair_fields(stage, nl, solution, n_points):
    """(peak force magnitude [N], relative displacement amplitude [m]) of every contact pair at
    both of its nodes, as (n_points,) arrays for the VTU (:func:`sarfe.results.vtk.
    contact_point_values`); (None, None) without contacts."""
    cs = nl.contacts
    if not cs.count or not stage.contacts:
        return None, None
    force = np.asarray(solution.contact_force_time, dtype=float)
    R = np.asarray(solution.contact_displacement, dtype=float)
    r = time_samples(R, force.shape[0]) - R[0]
    rows = np.column_stack([cs.normal_row, cs.tangent_rows])                  # (n_c, 3)
    valid = rows >= 0
    take = np.where(valid, rows, 0)
    lam = force[:, take] * valid                                             # (N, n_c, 3)
    lam[:, :, 0] += np.where(valid[:, 0], cs.normal_load, 0.0)
    peak = np.sqrt((lam ** 2).sum(axis=2)).max(axis=0)                       # (n_c,)
    motion = np.sqrt(((r[:, take] * valid) ** 2).sum(axis=2)).max(axis=0)    # (n_c,)
    force_field, motion_field = np.zeros(n_points), np.zeros(n_points)
    for (name, _, idx) in nl.groups:
        geometry = stage.contacts.get(name)
        if geometry is None or len(geometry.nodes_a) != len(idx):
            continue
        force_field = np.maximum(force_field, contact_point_values(
            n_points, geometry.nodes_a, geometry.nodes_b, peak[idx]))
        motion_field = np.maximum(motion_field, contact_point_values(
            n_points, geometry.nodes_a, geometry.nodes_b, motion[idx]))
    return force_field, motion_field


def result_groups(points, nl) -> dict:
    """response.h5 groups of the per-point post-processing: /contributions (partial ERP and shares
    per source, NaN where not computed), /contact_dynamics and /bands (third-octave, on the union
    of the points' bands; −inf where a band is empty)."""
    n_f = len(points)
    names = ["excitation"] + [name for name, _, _ in nl.groups]
    S = len(names)
    share, share_a = np.full((n_f, S), np.nan), np.full((n_f, S), np.nan)
    level_db, level_dba = np.full((n_f, S), np.nan), np.full((n_f, S), np.nan)
    power = np.full((n_f, S), np.nan)
    error = np.full(n_f, np.nan)
    ranking = []
    for i, p in enumerate(points):
        c = p.get("contributions") or {}
        ranking.append((c.get("ranking") or [""])[0])
        if not c.get("available"):
            continue
        error[i] = c["superposition_error"]
        for s, source in enumerate(c["sources"][:S]):
            share[i, s], share_a[i, s] = source["share"], source["share_a"]
            level_db[i, s], level_dba[i, s] = source["level_db"], source["level_dba"]
            power[i, s] = source["power_W"]
    groups = {"contributions": {
        "source_names": np.array(names, dtype=object), "power_W": (power, "W"),
        "level_db": (level_db, "dB re 1e-12 W"), "level_dba": (level_dba, "dB(A) re 1e-12 W"),
        "share": (share, "1"), "share_a": (share_a, "1"),
        "superposition_error": (error, "1"), "ranking_first": np.array(ranking, dtype=object)}}
    keys = ("impacts_per_period", "peak_force_N", "slip_distance_m", "dissipated_energy_J")
    dynamics = {k: np.full((n_f, len(nl.groups)), np.nan) for k in keys}
    for i, p in enumerate(points):
        for g, c in enumerate(p.get("contacts", [])[:len(nl.groups)]):
            for k in keys:
                dynamics[k][i, g] = c.get(k, np.nan)
    if nl.groups:
        units = {"impacts_per_period": "1/period", "peak_force_N": "N", "slip_distance_m": "m",
                 "dissipated_energy_J": "J"}
        groups["contact_dynamics"] = {"contact_names": np.array([g[0] for g in nl.groups],
                                                                dtype=object),
                                      **{k: (v, units[k]) for k, v in dynamics.items()}}
    groups.update(audibility_group(points, nl))
    groups.update(margin_group(points, nl))
    bands = [p.get("bands") for p in points if p.get("bands")]
    if bands:
        all_bands = [b for p in bands for part in ("nonlinear", "linear") for b in p[part]["band"]]
        first, last = min(all_bands), max(all_bands)
        numbers = np.arange(first, last + 1)
        table = {}
        for part in ("nonlinear", "linear"):
            for key in ("power_W", "power_a_W", "level_db", "level_dba"):
                fill = -np.inf if key.startswith("level") else 0.0
                arr = np.full((n_f, numbers.size), fill)
                for i, p in enumerate(points):
                    b = (p.get("bands") or {}).get(part)
                    if b and b["band"]:
                        slot = np.asarray(b["band"]) - first
                        arr[i, slot] = np.asarray(b[key], dtype=float)
                table[f"{part}_{key}"] = arr
        mid, lo, hi = band_frequencies(numbers)
        groups["bands"] = {"band": numbers, "nominal_hz": (np.array([nominal_frequency(b)
                                                                     for b in numbers]), "Hz"),
                           "center_hz": (mid, "Hz"), "lower_hz": (lo, "Hz"), "upper_hz": (hi, "Hz"),
                           **{k: (v, _band_units(k)) for k, v in table.items()}}
    return groups


def _band_units(name: str) -> str:
    """``units`` attribute of a /bands dataset: '*_level_dba' A-weighted levels, '*_level_db'
    levels, '*_power_W' / '*_power_a_W' powers."""
    if name.endswith("_level_dba"):
        return "dB(A) re 1e-12 W"
    return "dB re 1e-12 W" if "level" in name else "W"


def _number(value) -> float:
    return float("nan") if value is None else float(value)


def audibility_group(points, nl) -> dict:
    """response.h5 /audibility: per point the occupant verdict (spl_dba, loudness_sone, audible,
    margin_db), its 28 third-octave bands (SPL and margin, (n_f, 28)), the background and the
    thresholds (28,), the occupant SPL and pressure phase per harmonic (n_f, H), and per contact
    the verdict of its sound alone (n_f, n_g). Empty without audibility records."""
    records = [p.get("audibility") for p in points]
    if not any(records):
        return {}
    first = next(r for r in records if r)
    n_f, n_g = len(points), len(nl.groups)
    bands = first["bands"]
    H = len(first["harmonics"]["frequency_hz"])
    table = {k: np.full(n_f, np.nan) for k in ("spl_dba", "loudness_sone", "margin_db")}
    audible = np.full(n_f, -1, dtype=np.int8)
    band_spl, band_margin = np.full((n_f, len(bands["band_hz"])), np.nan), \
        np.full((n_f, len(bands["band_hz"])), np.nan)
    spl_h, phase_h = np.full((n_f, H), np.nan), np.full((n_f, H), np.nan)
    alone = {k: np.full((n_f, n_g), np.nan) for k in ("spl_dba", "loudness_sone", "margin_db")}
    alone_audible = np.full((n_f, n_g), -1, dtype=np.int8)
    names = [g[0] for g in nl.groups]
    for i, r in enumerate(records):
        if not r:
            continue
        for k in table:
            table[k][i] = _number(r[k])
        audible[i] = int(bool(r["audible"]))
        band_spl[i] = [_number(v) for v in r["bands"]["spl_db"]]
        band_margin[i] = [_number(v) for v in r["bands"]["margin_db"]]
        spl_h[i, :len(r["harmonics"]["spl_db"])] = [_number(v) for v in r["harmonics"]["spl_db"]]
        phase_h[i, :len(r["harmonics"]["phase_rad"])] = r["harmonics"]["phase_rad"]
        for source in r.get("sources", []):
            if source["name"] in names:
                g = names.index(source["name"])
                for k in alone:
                    alone[k][i, g] = _number(source[k])
                alone_audible[i, g] = int(bool(source["audible"]))
    return {"audibility": {
        "spl_dba": (table["spl_dba"], "dB(A) re 20e-6 Pa"),
        "loudness_sone": (table["loudness_sone"], "sone"),
        "audible": audible, "margin_db": (table["margin_db"], "dB"),
        "band_hz": (np.asarray(bands["band_hz"], dtype=float), "Hz"),
        "band_spl_db": (band_spl, "dB re 20e-6 Pa"), "band_margin_db": (band_margin, "dB"),
        "background_db": (np.array([_number(v) for v in bands["background_db"]]),
                          "dB re 20e-6 Pa"),
        "threshold_in_quiet_db": (np.array([_number(v) for v in
                                            bands["threshold_in_quiet_db"]]), "dB re 20e-6 Pa"),
        "masked_threshold_db": (np.array([_number(v) for v in bands["masked_threshold_db"]]),
                                "dB re 20e-6 Pa"),
        "harmonic_spl_db": (spl_h, "dB re 20e-6 Pa"), "harmonic_phase_rad": (phase_h, "rad"),
        "contact_names": np.array(names, dtype=object),
        "contact_spl_dba": (alone["spl_dba"], "dB(A) re 20e-6 Pa"),
        "contact_loudness_sone": (alone["loudness_sone"], "sone"),
        "contact_margin_db": (alone["margin_db"], "dB"), "contact_audible": alone_audible}}


def margin_group(points, nl) -> dict:
    """response.h5 /margins (n_f, n_g) per point and named contact: the onset factor (its level
    20 lg s* [dB], mechanism, the steady factor), the linear risk (dynamic tolerance [m], rattle
    risk) and the sensitivities p dL_A/dp [dB(A)] and dL_A/dp of each case parameter (NaN where
    not computed or not used). Empty without contacts."""
    if not nl.groups:
        return {}
    n_f, n_g = len(points), len(nl.groups)
    grid = (lambda: np.full((n_f, n_g), np.nan))            # noqa: E731
    onset, onset_db, steady, tolerance = grid(), grid(), grid(), grid()
    risk = np.full((n_f, n_g), -1, dtype=np.int8)
    mechanism = np.full((n_f, n_g), "", dtype=object)
    relative = {k: grid() for k in CASE_PARAMETERS}
    slope = {k: grid() for k in CASE_PARAMETERS}
    for i, p in enumerate(points):
        for g, c in enumerate(p.get("contacts", [])[:n_g]):
            o = c.get("onset") or {}
            onset[i, g], onset_db[i, g] = _number(o.get("factor")), _number(o.get("level_db"))
            steady[i, g] = _number(o.get("steady_factor"))
            mechanism[i, g] = o.get("mechanism", "")
            sens = c.get("sensitivities") or {}
            for k, v in (sens.get("per_relative_change_dba") or {}).items():
                relative[k][i, g] = _number(v)
            for k, v in (sens.get("dL_dp") or {}).items():
                slope[k][i, g] = _number(v)
        for g, c in enumerate((p.get("linear") or {}).get("contacts", [])[:n_g]):
            tolerance[i, g] = _number(c.get("dynamic_tolerance_m"))
            risk[i, g] = int(bool(c.get("rattle_risk")))
    group = {"contact_names": np.array([g[0] for g in nl.groups], dtype=object),
             "onset_factor": (onset, "1"), "onset_level_db": (onset_db, "dB"),
             "steady_onset_factor": (steady, "1"), "onset_mechanism": mechanism,
             "dynamic_tolerance_m": (tolerance, "m"), "linear_rattle_risk": risk}
    units = {"gap_m": "dB(A)/m", "normal_stiffness_N_m": "dB(A)/(N/m)",
             "tangential_stiffness_N_m": "dB(A)/(N/m)", "friction_coefficient": "dB(A)",
             "preload_N": "dB(A)/N"}
    for key in CASE_PARAMETERS:
        group[f"relative_sensitivity_{key}_dba"] = (relative[key], "dB(A)")
        group[f"dL_dp_{key}"] = (slope[key], units[key])
    return {"margins": group}


ONSET_CAP = 1000.0     # VTU onset factor of a contact that never switches (s* = ∞): 60 dB


def contact_margin_fields(stage, nl, point, n_points) -> dict:
    """VTU arrays at the contact-pair nodes (both nodes of each pair) from a point record:
    ``contact_onset_factor`` (the named contact's s*: < 1 active; capped at ONSET_CAP for
    'never'), ``contact_dynamic_tolerance_m`` (linear risk d = g − t − |ŵ1|, < 0 rattle risk) and
    ``contact_sensitivity_dba_10pct`` (|ΔL_A| for 10 % of the contact's most effective
    parameter). Where contacts share a node the smallest (most critical) factor and tolerance,
    the largest sensitivity win. The other points (no contact; the VTU holds no NaN) get the
    harmless end of each scale: ONSET_CAP, the frame's largest tolerance, 0 dB(A) — threshold
    ``contact_marker`` > 0 to see the contacts alone. Empty without FE contacts."""
    if not nl.contacts.count or not stage.contacts:
        return {}
    linear = {c["name"]: c for c in (point.get("linear") or {}).get("contacts", [])}
    fields = {key: np.full(int(n_points), np.nan) for key in (
        "contact_onset_factor", "contact_dynamic_tolerance_m", "contact_sensitivity_dba_10pct")}
    for c in point.get("contacts", []):
        geometry = stage.contacts.get(c["name"])
        if geometry is None:
            continue
        nodes = np.concatenate([np.asarray(geometry.nodes_a, int), np.asarray(geometry.nodes_b,
                                                                               int)])
        nodes = nodes[nodes >= 0]
        relative = ((c.get("sensitivities") or {}).get("per_relative_change_dba") or {}).values()
        finite = [abs(0.1 * v) for v in relative if v is not None and np.isfinite(v)]
        values = {"contact_onset_factor": min(_number((c.get("onset") or {}).get("factor")),
                                              ONSET_CAP),
                  "contact_dynamic_tolerance_m": _number(linear.get(c["name"], {}).get(
                      "dynamic_tolerance_m")),
                  "contact_sensitivity_dba_10pct": max(finite) if finite else float("nan")}
        for key, value in values.items():
            reduce = np.fmax if key == "contact_sensitivity_dba_10pct" else np.fmin
            reduce.at(fields[key], nodes, value)
    tolerance = fields["contact_dynamic_tolerance_m"]
    fills = {"contact_onset_factor": ONSET_CAP, "contact_sensitivity_dba_10pct": 0.0,
             "contact_dynamic_tolerance_m": float(np.nanmax(tolerance))
             if np.isfinite(tolerance).any() else 0.0}
    return {key: np.where(np.isfinite(v), v, fills[key]) for key, v in fields.items()}
