"""Result files of a case (via :mod:`sarfe.results`) and the console table. The caller writes them
into a temporary folder moved into place at the end (:func:`sarfe.results.folder.
write_result_folder`)."""
from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np

from sarfe import results
from sarfe.hbm.laws import table_column
from sarfe.pipeline.post.point_workers import point_workers
from sarfe.pipeline.post.records import point_erp
from sarfe.pipeline.post.result_data import (contact_margin_fields, contact_pair_fields,
                                             result_groups)
from sarfe.pipeline.write import figures
from sarfe.pipeline.write.sound_files import SOUND_FILES, write_point_sound
from sarfe.pipeline.write.map_points import map_indices
from sarfe.reduction.recovery import recover_displacement
from sarfe.results import render
from sarfe.results.summary import shown_level


def write_outputs(config, stage, nl, summary, rows, solutions, erps, fields, directory: Path):
    """Write the result files asked for in ``output.files`` into ``directory``; returns
    {file kind: file name}. ``config``: the case's :class:`sarfe.case.config.CaseConfig`;
    ``erps``, ``fields``: each point's ErpResult and map fields (:func:`sarfe.pipeline.
    postprocess.map_fields`).
    Everything "at the loudest point" (spectrum, contact plots, animation,
    report maps) uses ``summary["worst"]["index"]`` (:func:`sarfe.pipeline.post.records.loudest_point`).
    summary.json itself is written by the caller, last (it lists these files and the timings).
    The report's surface renders run in a child process from the moment the loudest point's
    arrays exist until the report is written, and a large sweep's ERP maps on the run's workers
    (:func:`map_workers`) while this process writes response.h5, the animation and the PNGs;
    both are stopped if a writer fails."""
    started = []        # ('render', run) | ('maps', writer) in progress in other processes
    try:
        return _write_outputs(config, stage, nl, summary, rows, solutions, erps, fields,
                              directory, started)
    except BaseException:
        for kind, run in started:
            if kind == "render":
                render.cancel_render(run)
            else:
                run.cancel()
        raise


def _write_outputs(config, stage, nl, summary, rows, solutions, erps, fields, directory,
                   started):
    files = config.output.files
    written = {}
    written["summary"] = "summary.json"
    if "table" in files:
        types = {name: kind for name, kind, _ in nl.groups}
        mesh = (summary.get("mesh_error") or {}).get("line")    # the ± mesh term's line
        (directory / "table.txt").write_text(results_table(rows, types, max_contacts=100) + "\n"
                                             + (f"{mesh}\n" if mesh else ""), encoding="utf-8")
        written["table"] = "table.txt"
    if not solutions:
        return written
    loudest = (summary.get("worst") or {}).get("index")
    maps, renders, series = {}, None, None
    frequencies = [float(s.omega) / (2 * np.pi) for s in solutions]
    selected = map_indices(config.output.maps, frequencies, [bool(s.converged) for s in solutions],
                           loudest)       # the points with an ERP map (output.maps)
    if stage.kind == "fe" and ("erp_vtu" in files or "animation" in files or "report" in files):
        mesh = stage.mesh
        markers = results.contact_markers(mesh.n_nodes, [g.nodes_a for g in stage.contacts.values()])
        parts = results.part_ids(mesh.n_triangles, mesh.element_groups)
        translations = {}
        every_point = full_field_every_point(stage, solutions) or (
            len(selected) < len(solutions)
            and full_field_every_point(stage, [solutions[j] for j in selected]))

        def nodal_translations(j):
            # full-field recovery only because a VTU or a map was asked for: (2H+1, n, 3) [m];
            # kept for the loudest point only (200 points of a 5 mm door trim would hold 5 GB)
            if j in translations:
                return translations[j]
            if j != loudest and not (every_point and j in selected):
                return None
            u = recover_displacement(stage.reduced, np.asarray(solutions[j].displacement),
                                     all_dofs=True)
            u = u.reshape(u.shape[0], mesh.n_nodes, 6)[:, :, :3]
            if j == loudest:
                translations[j] = u
            return u

        loudest_data = {}

        def point_data(j):
            if j in loudest_data:     # the loudest point's arrays serve its map and the report's
                return loudest_data[j]
            force, motion = contact_pair_fields(stage, nl, solutions[j], mesh.n_nodes)
            erp, W = erps[j], None
            if fields[j] is None:     # a chosen map (output.maps): its ERP density made now
                erp, W = point_erp(config.erp, stage, np.asarray(solutions[j].displacement),
                                   float(solutions[j].omega))
            data = results.erp_point_data(mesh.n_nodes, erp, W,
                                          float(solutions[j].omega), fields=fields[j],
                                          displacement=nodal_translations(j),
                                          radiating_nodes=stage.erp_nodes,
                                          contact_marker=markers, contact_force=force,
                                          contact_displacement=motion,
                                          node_ids=getattr(stage, "node_ids", None))
            # onset factor, dynamic tolerance, sensitivity at the contact nodes (what would fix it)
            data.update(contact_margin_fields(stage, nl, summary["points"][j], mesh.n_nodes))
            if j == loudest:
                loudest_data[j] = data
            return data

        if loudest is not None and ("erp_vtu" in files or "report" in files):
            point_data(loudest)       # before the VTU workers fork: they inherit it
        if "report" in files and loudest is not None:
            # the report's renders run in their child process while the other files are written
            renders = figures.start_surface_maps(config, mesh, point_data(loudest),
                                         nodal_translations(loudest), summary["points"][loudest],
                                         directory / ".report-figures",
                                         contact_nodes={name: int(g.nodes_a[0])
                                                        for name, g in stage.contacts.items()
                                                        if len(g.nodes_a)})
            started.append(("render", renders))
        if "erp_vtu" in files:
            if len(selected) == 1:      # one map (the loudest, or the only point): erp.vtu
                j = selected[0]
                results.write_erp_vtu(directory / "erp.vtu", mesh.points, mesh.triangles,
                                      point_data(j), field_data={"frequency_hz": frequencies[j],
                                                                 "point_index": j}, parts=parts)
                written["erp_vtu"] = "erp.vtu"
            else:       # on the workers while this process writes the files below
                series = results.start_erp_sweep(directory / "erp", mesh.points, mesh.triangles,
                                                 lambda i: point_data(selected[i]),
                                                 [frequencies[j] for j in selected],
                                                 workers=map_workers(config, mesh, len(selected)),
                                                 indices=selected, parts=parts)
                started.append(("maps", series))
                written["erp_vtu"] = "erp/erp.pvd"
        if "animation" in files and loudest is not None:
            results.write_deflection_animation(directory / "animation", mesh.points,
                                               mesh.triangles, nodal_translations(loudest),
                                               omega=float(solutions[loudest].omega),
                                               point_data={"contact_marker": markers} | (
                                                   {"node_id": stage.node_ids}
                                                   if getattr(stage, "node_ids", None) is not None
                                                   else {}))
            written["animation"] = "animation/deflection.pvd"
    if "response" in files:
        reduced = getattr(stage, "reduced", None)
        results.write_response_h5(
            directory / "response.h5", solutions, contacts=nl.contacts, excitation=nl.excitation,
            # a base excitation loads every coordinate of a reduced model: its "excitation DOFs"
            # would be the whole reduced response (∝ modes); the contact rows and the ERP are
            # the record (∝ points × contacts × H)
            excitation_dofs=np.zeros(0, dtype=int) if reduced is not None
            and config.excitation.base_acceleration is not None else None,
            density_points=selected if stage.kind == "fe" else None,
            base_samples_per_period=config.solver.samples_per_period,   # N before raised
            boundary_dofs=getattr(stage.reduced, "boundary_dofs", None),
            mode_frequencies_hz=stage.mode_frequencies_hz, erp=erps,
            radiating_nodes=stage.erp_nodes if stage.erp_map.shape[0] else None,
            extra_groups=result_groups(summary["points"], nl),   # contributions, bands, …
            attributes={"case": config.name, "linear_model_key": stage.key})
        written["response"] = "response.h5"
    images = {}
    if "plots" in files or "report" in files:
        plot_dir = directory if "plots" in files else directory / ".report-figures"
        images = figures.point_figures(config, stage, nl, summary, solutions, erps, plot_dir, loudest)
        if "plots" in files:
            written["plots"] = ", ".join(sorted(Path(v).name for v in images.values()))
    sounds = {}
    if ("sound" in files or "report" in files) and loudest is not None:
        sound_dir = directory if "sound" in files else directory / ".report-figures"
        summary["sound"] = write_point_sound(config, summary["points"][loudest], sound_dir)
        sounds = {name: sound_dir / name for name in (summary["sound"] or {}).get("files", {})}
        if "sound" in files and sounds:
            written["sound"] = ", ".join(name for name in SOUND_FILES if name in sounds)
    if series is not None:
        series.finish()
    if renders is not None:
        maps = figures.finish_surface_maps(renders)
    if "report" in files:
        notes = {"renderer": maps.pop("renderer", None)}
        results.write_report_html(directory / "report.html", summary, {**images, **maps}, notes,
                                  sounds=sounds)
        written["report"] = "report.html"
    shutil.rmtree(directory / ".report-figures", ignore_errors=True)
    return written


# the ERP maps of a sweep are written on the run's worker processes (solver.workers) when the
# series holds at least this many point values (points × mesh nodes; ≈ 20 ms per 35k-node map,
# forking the workers costs ≈ 0.1 s: below this the maps are written in the solving process)
PARALLEL_MAP_VALUES = 2e6


def map_workers(config, mesh, n_maps) -> int:
    """Processes that write a sweep's ERP maps: the run's point workers for a large series."""
    return point_workers(config.solver) if n_maps * mesh.n_nodes >= PARALLEL_MAP_VALUES else 1


# full-field recovery u = T q of every sweep point for the VTU maps up to this many multiply-adds
# (Σ_points (2H+1) · n_free · n_r: ~1 s); beyond it only the loudest point's map carries the
# nodal displacement (docs/outputs.md, displacement_amplitude_m)
FULL_FIELD_BUDGET = 5e9


def full_field_every_point(stage, solutions) -> bool:
    """True when every point's VTU map gets the recovered nodal displacement (FULL_FIELD_BUDGET)."""
    reduced = stage.reduced
    if reduced is None or not solutions:
        return False
    cost = sum(np.asarray(s.displacement).shape[0] for s in solutions) \
        * reduced.full_dof_count * reduced.reduced_dof_count
    return cost <= FULL_FIELD_BUDGET


def results_table(rows, contact_types=None, max_contacts=6) -> str:
    """Console table of the frequency points: convergence, ERP and, per contact (at most
    ``max_contacts``), the indicator its law declares (max penetration, or the slip fraction of a
    friction law: the share of the period in slip, 0…1). The ±dB column is the ERP error bound,
    "~" marking a bound interpolated between estimated points. ``contact_types``: {name: law
    name} (default: max penetration). Every point and contact: table.txt (the console shows a
    few points, :func:`sarfe.results.console.points_table`)."""
    columns = ["frequency_hz", "converged", "stable", "iterations", "erp_db", "erp_dba",
               "linear_erp_db"]
    headers = {"frequency_hz": "f [Hz]", "erp_db": "ERP [dB]", "erp_dba": "ERP [dB(A)]",
               "linear_erp_db": "linear [dB]", "iterations": "iter"}
    formats = {"frequency_hz": ".2f", "erp_db": ".1f", "erp_dba": ".1f", "linear_erp_db": ".1f"}
    if any(math.isfinite(row.get("erp_error_db", float("nan"))) for row in rows):
        # the error estimate of the ERP level (summary.json points[].error_estimate.erp_db)
        columns.insert(columns.index("erp_dba") + 1, "erp_error_db")
        headers["erp_error_db"], formats["erp_error_db"] = "±dB", ".2f"
    if rows and "occupant_spl_dba" in rows[0]:     # heard at the occupant (audibility)
        columns += ["occupant_spl_dba", "audible", "audibility_margin_db"]
        headers.update(occupant_spl_dba="SPL [dB(A)]", audible="heard",
                       audibility_margin_db="margin [dB]")
        formats.update(occupant_spl_dba=".1f", audibility_margin_db="+.1f")
    names = [k[: -len(".max_penetration_m")] for k in (rows[0] if rows else {})
             if k.endswith(".max_penetration_m")]
    for name in names[:max_contacts]:
        law = (contact_types or {}).get(name)
        if law is not None and table_column(law) == "slip_fraction":
            key, header, fmt = f"{name}.slip_fraction", f"{name} slip fraction", ".2f"
        else:
            key, header, fmt = f"{name}.max_penetration_m", f"{name} pen [mm]", ".3f"
        columns.append(key)
        headers[key] = header
        formats[key] = fmt
        if f"{name}.onset_factor" in rows[0]:   # onset factor s* of the excitation (< 1: active)
            columns.append(f"{name}.onset_factor")
            headers[f"{name}.onset_factor"] = f"{name} onset"
            formats[f"{name}.onset_factor"] = ".3g"
    shown = [dict(row) for row in rows]
    for row in shown:  # a motionless surface's level reads "-"
        for key in ("erp_db", "erp_dba", "linear_erp_db", "occupant_spl_dba"):
            if key in row:
                row[key] = shown_level(row[key])
    if "erp_error_db" in columns:  # "~": interpolated between estimated points (not estimated)
        cells = [_error_cell(row) for row in rows]
        width = max(len(c) for c in cells)
        for row, cell in zip(shown, cells):
            row["erp_error_db"] = cell.rjust(width)
    for row in shown:  # penetration in mm for reading
        for name in names:
            key = f"{name}.max_penetration_m"
            if isinstance(row.get(key), float) and math.isfinite(row[key]):
                row[key] = 1e3 * row[key]
    table = results.console_table(shown, columns=columns, formats=formats, headers=headers)
    if len(names) > max_contacts:
        table += f"\n({len(names) - max_contacts} more contacts in summary.json)"
    return table


def _error_cell(row) -> str:
    """Table text of a row's ERP error bound [dB]: '0.24', '~3.06' when the point's estimate is
    interpolated between estimated points, '-' when there is none."""
    value = row.get("erp_error_db", float("nan"))
    if value is None or not math.isfinite(value):
        return "-"
    return ("~" if row.get("erp_error_interpolated") else "") + f"{value:.2f}"
