"""The PNG figures of a run (``erp_sweep.png``, ``erp_spectrum.png``, ``third_octave.png``,
``contributions.png``, ``audibility.png``, ``contact_forces.png``, ``friction.png``) and the report's surface maps,
all "at the loudest point" drawn at the one point ``summary["worst"]["index"]``."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from sarfe import results
from sarfe.hbm.harmonics import time_samples
from sarfe.hbm.laws.curvature import friction_rows
from sarfe.results import render
from sarfe.results.vtk import period_samples


def _squeak_series(nl, solution):
    """(friction |λ_t| (N, n_sq) [N], state (N, n_sq) int, names) of the contacts with a friction (tangent) element: the
    pair forces summed per named contact, the state 'slip' if any pair slips, else 'stick' if any
    sticks, else 'open'."""
    cs = nl.contacts
    force = np.asarray(solution.contact_force_time, dtype=float)
    R = np.asarray(solution.contact_displacement, dtype=float)
    if R.shape[1]:                  # a curved partner's rows also carry −κ q λ_n: not friction
        force = friction_rows(cs, time_samples(R, force.shape[0]), force)
    state = np.asarray(solution.contact_state)
    friction, states, names = [], [], []
    for name, _, idx in nl.groups:
        tr = np.asarray(cs.tangent_rows)[idx]
        if not (tr >= 0).any():        # no friction (tangent) element
            continue
        lam = force[:, np.where(tr >= 0, tr, 0)] * (tr >= 0)                  # (N, p, 2)
        friction.append(np.sqrt((lam.sum(axis=1) ** 2).sum(axis=1)))
        st = state[:, idx]
        states.append(np.where((st == 2).any(axis=1), 2, np.where((st == 1).any(axis=1), 1, 0)))
        names.append(name)
    if not names:
        return None, None, []
    return np.stack(friction, axis=1), np.stack(states, axis=1), names


def point_figures(config, stage, nl, summary, solutions, erps, directory: Path, loudest) -> dict:
    """Draw the run's PNGs into ``directory``; returns {image key: path} (report keys).
    ``config``: the case's :class:`sarfe.case.config.CaseConfig` (name, output.target_dba)."""
    directory = Path(directory)
    points = summary["points"]
    target = config.output.target_dba
    images = {}
    frequencies = [p["frequency_hz"] for p in points]
    if len(solutions) > 1:
        images["erp_sweep"] = results.plot_erp_sweep(
            directory / "erp_sweep.png", frequencies, [p["erp"]["level_db"] for p in points],
            stable=[p["stable"] for p in points], level_a_db=[p["erp"]["level_dba"] for p in points],
            title=config.name, linear_level_db=[p["linear"]["erp_level_db"] for p in points],
            converged=[p["converged"] for p in points], target_dba=target, loudest_index=loudest)
    if loudest is None:
        return images
    j = int(loudest)
    at = f"{frequencies[j]:.1f} Hz"
    images["erp_spectrum"] = results.plot_erp_spectrum(
        directory / "erp_spectrum.png", erps[j].frequencies_hz, erps[j].level_db,
        erps[j].level_a_db, title=f"{config.name}: ERP per harmonic at {at} (loudest point)")
    bands = points[j].get("bands")
    if bands:
        images["third_octave"] = results.plot_third_octave(
            directory / "third_octave.png", bands["nonlinear"]["nominal_hz"],
            bands["nonlinear"]["level_dba"], linear_level_dba=bands["linear"]["level_dba"],
            linear_nominal_hz=bands["linear"]["nominal_hz"], target_dba=target,
            title=f"{config.name}: third-octave bands at {at}")
    contributions = points[j].get("contributions") or {}
    if contributions.get("available"):
        sources = sorted(contributions["sources"],
                         key=lambda s: -s["share_a"] if s["share_a"] is not None
                         and np.isfinite(s["share_a"]) else np.inf)[:20]
        images["contributions"] = results.plot_contributions(
            directory / "contributions.png", [s["name"] for s in sources],
            [s["level_dba"] for s in sources], [s["share_a"] for s in sources],
            title=f"share of the A-weighted ERP at {at}",
            part_level_dba=[s.get("part_level_dba") for s in sources])
    audibility = points[j].get("audibility") or {}
    if audibility.get("bands"):
        b = audibility["bands"]
        images["audibility"] = results.plot_audibility(
            directory / "audibility.png", b["band_hz"], b["spl_db"], b["background_db"],
            b["threshold_in_quiet_db"], b["masked_threshold_db"],
            title=f"{config.name}: at the occupant at {at} "
            f"(background {Path(config.audibility.background).stem})")
    if nl.contacts.count:
        force = np.asarray(solutions[j].contact_force_time)
        normal_rows = nl.contacts.normal_row
        totals = [force[:, normal_rows[idx][normal_rows[idx] >= 0]].sum(axis=1)
                  + nl.contacts.normal_load[idx].sum() for _, _, idx in nl.groups]
        images["contact_forces"] = results.plot_contact_forces(
            directory / "contact_forces.png", np.stack(totals, axis=1),
            names=[g[0] for g in nl.groups], omega=solutions[j].omega,
            title=f"normal contact forces at {at} (loudest point)")
        friction, state, names = _squeak_series(nl, solutions[j])
        if names:
            images["friction"] = results.plot_friction(
                directory / "friction.png", friction, state, names=names,
                omega=solutions[j].omega, title=f"friction and stick/slip at {at}")
    return images


def finish_surface_maps(run) -> dict:
    """{key: PNG path, 'renderer': text} of the renders :func:`start_surface_maps` started."""
    rendered = render.finish_render(run)
    maps = {key: path for key, (path, _) in zip(("erp_map", "deflection", "contact_map"),
                                                rendered)}
    maps["renderer"] = rendered[0][1]
    return maps


def start_surface_maps(config, mesh, point_data, translations, point, directory: Path,
                       contact_nodes=None):
    """Start the report renders at the loudest point in their child process and return at once
    (:func:`sarfe.results.render.start_render`): the run's other files are written meanwhile.
    The renders: the ERP map [dB re 1 pW/m²], the deflection at the phase of largest displacement
    (exaggerated warp, colour |u| [mm]) and, when contacts move, their relative displacement [mm],
    named at ``contact_nodes`` {name: mesh node}; :func:`finish_surface_maps` collects them."""
    directory = Path(directory)
    at = f"{point['frequency_hz']:.1f} Hz"
    level = point_data["erp_level_db_m2"]
    jobs = [dict(path=directory / "erp_map.png", points=mesh.points, triangles=mesh.triangles,
                 values=level, label="ERP density [dB re 1 pW/m2]",
                 title=f"{config.name}: ERP at {at}",
                 clim=[float(np.nanmin(level)), float(np.nanmax(level))])]   # NaN: off the surface
    frames = period_samples(translations, 24)                              # (24, n, 3)
    frame = frames[int(np.argmax(np.linalg.norm(frames, axis=2).max(axis=1)))]
    magnitude = np.linalg.norm(frame, axis=1)
    extent = float(np.ptp(mesh.points, axis=0).max())
    scale = 0.05 * extent / magnitude.max() if magnitude.max() > 0 else 0.0
    jobs.append(dict(path=directory / "deflection.png", points=mesh.points,
                     triangles=mesh.triangles, values=1e3 * magnitude, label="|u| [mm]",
                     title=f"deflection at {at} (x{scale:.3g})", warp=scale * frame,
                     cmap="viridis"))
    motion = point_data.get("contact_relative_displacement_m")
    if motion is not None and np.any(motion > 0):
        jobs.append(dict(path=directory / "contact_map.png", points=mesh.points,
                         triangles=mesh.triangles, values=1e3 * motion,
                         label="relative motion [mm]",
                         title=f"contact motion at {at}", cmap="plasma", spots=True,
                         labels=[(mesh.points[node], name)
                                 for name, node in (contact_nodes or {}).items()]))
    return render.start_render(jobs)
