"""Result files of a case (via :mod:`sarfe.io.outputs`), the console table, and the atomic move
of the finished result directory into place."""
from __future__ import annotations

import math
import os
import shutil
from pathlib import Path

import numpy as np


def write_outputs(case, stage, nl, summary, rows, solutions, erps, normal_w, directory: Path):
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
            attributes={"case": case.name, "linear_model_key": stage.key})
        written["response"] = "response.h5"
    frequencies = [float(s.omega) / (2 * np.pi) for s in solutions]
    if "plots" in files:
        if len(solutions) > 1:
            outputs.plot_erp_sweep(directory / "erp_sweep.png", frequencies,
                                   [e.level_total_db for e in erps],
                                   stable=[getattr(s, "stable", None) for s in solutions],
                                   level_a_db=[e.level_total_a_db for e in erps], title=case.name,
                                   linear_level_db=[p["linear"]["erp_level_db"]
                                                    for p in summary["points"]])
        j = int(np.argmax([e.power_total for e in erps]))
        outputs.plot_erp_spectrum(directory / "erp_spectrum.png", erps[j].frequencies_hz,
                                  erps[j].level_db, erps[j].level_a_db,
                                  title=f"{case.name} at {frequencies[j]:.1f} Hz")
        if nl.contacts.count:
            force = np.asarray(solutions[j].contact_force_time)
            normal_rows = nl.contacts.normal_row
            totals = [force[:, normal_rows[idx][normal_rows[idx] >= 0]].sum(axis=1)
                      + nl.contacts.normal_load[idx].sum() for _, _, idx in nl.groups]
            outputs.plot_contact_forces(directory / "contact_forces.png", np.stack(totals, axis=1),
                                        names=[g[0] for g in nl.groups],
                                        omega=solutions[j].omega,
                                        title=f"normal contact forces at {frequencies[j]:.1f} Hz")
        written["plots"] = "erp_sweep.png, erp_spectrum.png, contact_forces.png"
    if stage.kind == "fe" and ("erp_vtu" in files or "animation" in files):
        from sarfe.reduction.recovery import recover_displacement

        mesh = stage.mesh
        markers = outputs.contact_markers(mesh.n_nodes, [g.nodes_a for g in stage.contacts.values()])
        data = []
        for s, e, W in zip(solutions, erps, normal_w):
            # full-field recovery only because a VTU was asked for: translations (2H+1, n, 3) [m]
            u = recover_displacement(stage.reduced, np.asarray(s.displacement), all_dofs=True)
            translations = u.reshape(u.shape[0], mesh.n_nodes, 6)[:, :, :3]
            data.append(outputs.erp_point_data(mesh.n_nodes, e, W, float(s.omega),
                                               displacement=translations,
                                               radiating_nodes=stage.erp_nodes,
                                               contact_marker=markers))
        if "erp_vtu" in files:
            if len(solutions) == 1:
                outputs.write_erp_vtu(directory / "erp.vtu", mesh.points, mesh.triangles, data[0])
                written["erp_vtu"] = "erp.vtu"
            else:
                outputs.write_erp_sweep(directory / "erp", mesh.points, mesh.triangles, data,
                                        frequencies)
                written["erp_vtu"] = "erp/erp.pvd"
        if "animation" in files:
            j = int(np.argmax([e.power_total for e in erps]))
            u = recover_displacement(stage.reduced, np.asarray(solutions[j].displacement),
                                     all_dofs=True)
            U = u.reshape(u.shape[0], mesh.n_nodes, 6)[:, :, :3]
            outputs.write_deflection_animation(directory / "animation", mesh.points,
                                               mesh.triangles, U, omega=float(solutions[j].omega),
                                               point_data={"contact_marker": markers})
            written["animation"] = "animation/deflection.pvd"
    return written


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
    if any(math.isfinite(row.get("erp_error_db", float("nan"))) for row in rows):
        # the error estimate of the ERP level (summary.json points[].error_estimate.erp_db)
        columns.insert(columns.index("erp_dba") + 1, "erp_error_db")
        headers["erp_error_db"], formats["erp_error_db"] = "±dB", ".2f"
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
    shown = [dict(row) for row in rows]
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
