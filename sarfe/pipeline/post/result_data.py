"""Arrays of the per-point post-processing for the result files: the response.h5 groups of the
contributions, contact dynamics and third-octave bands, and the contact fields of the VTU."""
from __future__ import annotations

import numpy as np

from sarfe.erp.bands import band_frequencies, nominal_frequency
from sarfe.hbm.harmonics import time_samples
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
