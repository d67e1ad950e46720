"""The headline's ± where the harmonics cannot give one: the loudest point, when its estimate has
no bound because a contact's impact is far shorter than H' resolves
(:mod:`sarfe.accuracy.contact_resolution`), is integrated in time from its own state and its
error measured (:func:`sarfe.accuracy.time_check.time_integration_error`); that measured error
becomes the point's ± (``error_estimate.time_check``, a note), so the headline reads a level with
its real error instead of none. Other points without a bound keep none (the check costs
≈ 40–90 CPU s a point: lumped_rattle, k_n = 10¹⁰ N/m, N = 2048 with Richardson, 40 periods).
Never run on cases whose impacts the harmonics resolve (every shipped case)."""
from __future__ import annotations

import math

import numpy as np

from sarfe.accuracy.time_check import time_integration_error
from sarfe.pipeline.post.records import loudest_point


def impact_check_point(points) -> int | None:
    """Index (into ``points``) of the loudest point (:func:`sarfe.pipeline.post.records.
    loudest_point`) when its estimate has no bound for an unresolved impact, else None."""
    j = loudest_point(points)
    if j is None:
        return None
    estimate = points[j].get("error_estimate")
    if not isinstance(estimate, dict) or math.isfinite(estimate.get("amplitude_rel", 0.0)) \
            or (estimate.get("contact_resolution") or {}).get("resolved") is not False:
        return None
    return j


def impact_time_check(stage, nl, points, rows, solutions, j) -> dict:
    """Measure the error of ``points[j]`` (:func:`impact_check_point`) by time integration
    (module docstring); the point's estimate (``amplitude_rel``, ``erp_db``, ``time_check``,
    ``notes``) and its row's ±dB are updated in place → the check's dict with ``index`` and
    ``frequency_hz``."""
    point = points[j]
    estimate = point["error_estimate"]
    index = point["index"]
    try:        # a check must not break a solve: a failure is said, the point keeps no bound
        check = time_integration_error(solutions[index], nl.model, nl.contacts, nl.excitation,
                                       stage.erp_map, stage.erp_areas)
    except (ValueError, ArithmeticError, np.linalg.LinAlgError) as error:
        estimate["notes"] = list(estimate.get("notes") or []) + [
            f"time-integration check failed: {type(error).__name__}: {error}"]
        return {"index": index, "frequency_hz": point["frequency_hz"],
                "failed": f"{type(error).__name__}: {error}"}
    estimate = dict(estimate, amplitude_rel=check["amplitude_rel"],
                    erp_db=check["erp_db"] + float(estimate.get("mesh_db", 0.0) or 0.0),
                    time_check=check, interpolated=False,
                    notes=list(estimate.get("notes") or []) + [
                        f"± measured against the time integration from this point "
                        f"(N = {check['steps_per_period']} and {2 * check['steps_per_period']} "
                        f"steps a period, Richardson; {check['periods']} periods in all): "
                        f"first harmonic {100 * check['amplitude_rel']:.3g} %, ERP "
                        f"{check['erp_db']:.3g} dB" + (f"; {check['note']}" if check['note']
                                                       else "")])
    point["error_estimate"] = estimate
    rows[j]["erp_error_db"] = estimate["erp_db"]
    rows[j]["erp_error_interpolated"] = False
    return dict(check, index=index, frequency_hz=point["frequency_hz"])


__all__ = ["impact_check_point", "impact_time_check"]
