"""Result files of a case (via :mod:`sarfe.io.outputs`), the console table, and the atomic move
of the finished result directory into place."""
from __future__ import annotations

import math
import os
import shutil
from pathlib import Path

import numpy as np


def write_outputs(case, stage, nl, summary, rows, solutions, erps, normal_w, directory: Path):
    """Write the result files asked for in ``output.files`` into ``directory``; returns
    {file kind: file name}. Everything "at the loudest point" (spectrum, contact plots, animation,
    report maps) uses ``summary["worst"]["index"]`` (:func:`sarfe.pipeline.postprocess.loudest_point`)."""
    from sarfe.io import outputs

    files = case.data["output"]["files"]
    written = {}
    outputs.write_summary_json(directory / "summary.json", summary)
    written["summary"] = "summary.json"
    if "table" in files:
        types = {name: kind for name, kind, _ in nl.groups}
        (directory / "table.txt").write_text(results_table(rows, types, max_contacts=100) + "\n",
                                             encoding="utf-8")
        written["table"] = "table.txt"
    if not solutions:
        return written
    if "response" in files:
        outputs.write_response_h5(
            directory / "response.h5", solutions, contacts=nl.contacts, excitation=nl.excitation,
            boundary_dofs=getattr(stage.reduced, "boundary_dofs", None),
            mode_frequencies_hz=stage.mode_frequencies_hz, erp=erps,
            radiating_nodes=stage.erp_nodes if stage.erp_map.shape[0] else None,
            extra_groups=result_groups(summary["points"], nl),
            attributes={"case": case.name, "linear_model_key": stage.key})
        written["response"] = "response.h5"
    loudest = (summary.get("worst") or {}).get("index")
    images = {}
    if "plots" in files or "report" in files:
        from sarfe.pipeline.figures import point_figures

        plot_dir = directory if "plots" in files else directory / ".report-figures"
        images = point_figures(case, stage, nl, summary, solutions, erps, plot_dir, loudest)
        if "plots" in files:
            written["plots"] = ", ".join(sorted(Path(v).name for v in images.values()))
    maps = {}
    if stage.kind == "fe" and ("erp_vtu" in files or "animation" in files or "report" in files):
        from sarfe.reduction.recovery import recover_displacement

        mesh = stage.mesh
        markers = outputs.contact_markers(mesh.n_nodes, [g.nodes_a for g in stage.contacts.values()])
        translations = {}

        def nodal_translations(j):
            # full-field recovery only because a VTU or a map was asked for: (2H+1, n, 3) [m]
            if j not in translations:
                u = recover_displacement(stage.reduced, np.asarray(solutions[j].displacement),
                                         all_dofs=True)
                translations[j] = u.reshape(u.shape[0], mesh.n_nodes, 6)[:, :, :3]
            return translations[j]

        def point_data(j):
            force, motion = contact_pair_fields(stage, nl, solutions[j], mesh.n_nodes)
            return outputs.erp_point_data(mesh.n_nodes, erps[j], normal_w[j],
                                          float(solutions[j].omega),
                                          displacement=nodal_translations(j),
                                          radiating_nodes=stage.erp_nodes,
                                          contact_marker=markers, contact_force=force,
                                          contact_displacement=motion)

        if "erp_vtu" in files:
            frequencies = [float(s.omega) / (2 * np.pi) for s in solutions]
            if len(solutions) == 1:
                outputs.write_erp_vtu(directory / "erp.vtu", mesh.points, mesh.triangles,
                                      point_data(0))
                written["erp_vtu"] = "erp.vtu"
            else:
                outputs.write_erp_sweep(directory / "erp", mesh.points, mesh.triangles,
                                        (point_data(j) for j in range(len(solutions))),
                                        frequencies)
                written["erp_vtu"] = "erp/erp.pvd"
        if "animation" in files and loudest is not None:
            outputs.write_deflection_animation(directory / "animation", mesh.points,
                                               mesh.triangles, nodal_translations(loudest),
                                               omega=float(solutions[loudest].omega),
                                               point_data={"contact_marker": markers})
            written["animation"] = "animation/deflection.pvd"
        if "report" in files and loudest is not None:
            from sarfe.pipeline.figures import surface_maps

            maps = surface_maps(case, mesh, point_data(loudest), nodal_translations(loudest),
                                summary["points"][loudest], directory / ".report-figures")
    if "report" in files:
        notes = {"renderer": maps.pop("renderer", None)}
        outputs.write_report_html(directory / "report.html", summary, {**images, **maps}, notes)
        written["report"] = "report.html"
    import shutil

    shutil.rmtree(directory / ".report-figures", ignore_errors=True)
    return written


def contact_pair_fields(stage, nl, solution, n_points):
    """(peak force magnitude [N], relative displacement amplitude [m]) of every contact pair at
    both of its nodes, as (n_points,) arrays for the VTU (:func:`sarfe.io.outputs.vtk.
    contact_point_values`); (None, None) without contacts."""
    from sarfe.hbm.harmonics import time_samples
    from sarfe.io.outputs.vtk import contact_point_values

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
        from sarfe.erp.bands import band_frequencies, nominal_frequency

        mid, lo, hi = band_frequencies(numbers)
        groups["bands"] = {"band": numbers, "nominal_hz": (np.array([nominal_frequency(b)
                                                                     for b in numbers]), "Hz"),
                           "center_hz": (mid, "Hz"), "lower_hz": (lo, "Hz"), "upper_hz": (hi, "Hz"),
                           **{k: (v, "dB re 1e-12 W" if "level" in k else "W")
                              for k, v in table.items()}}
    return groups


def results_table(rows, contact_types=None, max_contacts=6) -> str:
    """Console table of the frequency points: convergence, ERP and, per contact (at most
    ``max_contacts``), the max penetration of a rattle contact or the slip fraction of a squeak
    contact. ``contact_types``: {name: 'rattle' | 'squeak'} (default: all rattle)."""
    from sarfe.io.outputs import console_table

    columns = ["frequency_hz", "converged", "stable", "iterations", "erp_db", "erp_dba",
               "linear_erp_db"]
    headers = {"frequency_hz": "f [Hz]", "erp_db": "ERP [dB]", "erp_dba": "ERP [dB(A)]",
               "linear_erp_db": "linear [dB]", "iterations": "iter"}
    formats = {"frequency_hz": ".2f", "erp_db": ".1f", "erp_dba": ".1f", "linear_erp_db": ".1f"}
    names = [k[: -len(".max_penetration_m")] for k in (rows[0] if rows else {})
             if k.endswith(".max_penetration_m")]
    for name in names[:max_contacts]:
        if (contact_types or {}).get(name) == "squeak":
            key, header, fmt = f"{name}.slip_fraction", f"{name} slip", ".2f"
        else:
            key, header, fmt = f"{name}.max_penetration_m", f"{name} pen [mm]", ".3f"
        columns.append(key)
        headers[key] = header
        formats[key] = fmt
    from sarfe.io.outputs.summary import shown_level

    shown = [dict(row) for row in rows]
    for row in shown:  # a motionless surface's level reads "-"
        for key in ("erp_db", "erp_dba", "linear_erp_db"):
            if key in row:
                row[key] = shown_level(row[key])
    for row in shown:  # penetration in mm for reading
        for name in names:
            key = f"{name}.max_penetration_m"
            if isinstance(row.get(key), float) and math.isfinite(row[key]):
                row[key] = 1e3 * row[key]
    table = console_table(shown, columns=columns, formats=formats, headers=headers)
    if len(names) > max_contacts:
        table += f"\n({len(names) - max_contacts} more contacts in summary.json)"
    return table


def replace_directory(temporary: Path, target: Path):
    """Move a finished temporary directory onto ``target`` (replacing an older result)."""
    backup = None
    if target.exists():
        backup = target.with_name(f".{target.name}.old-{os.getpid()}")
        os.replace(target, backup)
    os.replace(temporary, target)
    if backup is not None:
        shutil.rmtree(backup, ignore_errors=True)
