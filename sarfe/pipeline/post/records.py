r"""Per-point results: ERP of the HBM solution, contact indicators, linear risk baseline,
third-octave bands, the contribution of each contact, and the loudest point of a run.

ERP: w_s = N ũ (radiating-node normal displacement harmonics) → :func:`sarfe.erp.
equivalent_radiated_power`. Linear baseline: (K + Gᵀ diag(k) G − ω² M + iω D) Û = F̂ with the
contacts at their static state (preloaded pairs as springs, open ones removed: the rest state
of :func:`sarfe.hbm.onset.rest_rows`, the same as the onset factor's) →
:func:`sarfe.erp.risk.linear_risk_from_contacts` and its ERP. Bands: :func:`sarfe.erp.bands.
third_octave_levels` of the harmonic powers (the linear baseline radiates at ω only).
Contributions: :mod:`sarfe.pipeline.post.contribution_records`; per-period contact dynamics:
:mod:`sarfe.pipeline.post.contact_dynamics`. The loudest point (:func:`loudest_point`) is the converged,
not unstable point of highest A-weighted ERP; every artefact "at the loudest point" uses it.
"""
from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np
import scipy.sparse as sp

from sarfe.case.config import CaseConfig, ErpConfig, SolverConfig
from sarfe.erp import equivalent_radiated_power
from sarfe.erp.bands import third_octave_levels
from sarfe.erp.risk import linear_risk_from_contacts
from sarfe.hbm.onset import rest_rows
from sarfe.hbm.harmonics import time_samples
from sarfe.hbm.laws.curvature import friction_rows
from sarfe.pipeline.model.nonlinear_model import NonlinearModel
from sarfe.pipeline.post.audibility_records import point_audibility
from sarfe.pipeline.post.contact_dynamics import contact_dynamics
from sarfe.pipeline.post.contribution_records import contributions_record, point_condensation
from sarfe.pipeline.post.margin_records import point_margins
from sarfe.pipeline.post.review import loudest_review
from sarfe.pipeline.solve.case_accuracy import stage_error_estimate
from sarfe.results.vtk import radiating_fields
from sarfe.util.workers import map_points


def radiating_displacement(stage, displacement) -> np.ndarray:
    """W = U Nᵀ (rows, n_s) [m]: the radiating-node normal displacements of reduced displacement
    rows U (rows, n) [m], N = ``stage.erp_map`` (n_s, n). One matrix product over every row
    given: a point's harmonics and its linear baseline's share one pass over N (:func:`point_
    records`), the largest per-point product of the records on a fine mesh (N: 24,100 × 613 at
    5 mm)."""
    return np.asarray(displacement) @ stage.erp_map.T


def point_erp(erp: ErpConfig, stage, displacement, omega, normal_displacement=None):
    """(ErpResult, W) of displacement harmonics (2H+1, n) at ω (zero power without radiating
    nodes); ``normal_displacement``: W = :func:`radiating_displacement` of them when already
    computed. ``erp``: the case's :class:`ErpConfig` (a Case is also taken, for
    sarfe.pipeline.verify)."""
    if not isinstance(erp, ErpConfig):
        erp = erp.config.erp
    W = radiating_displacement(stage, displacement) if normal_displacement is None \
        else np.asarray(normal_displacement)
    if W.shape[1] == 0:  # no radiating surface: a zero-area node keeps the shapes valid
        W, areas = np.zeros((W.shape[0], 1)), np.zeros(1)
    else:
        areas = stage.erp_areas
    result = equivalent_radiated_power(W, omega, areas, density=erp.rho_kg_m3,
                                       sound_speed=erp.c_m_s,
                                       radiation_loss_factor=erp.radiation_loss_factor,
                                       reference_power=erp.reference_power_W)
    return result, W


def _erp_dict(result):
    return {"power_W": float(result.power_total), "level_db": float(result.level_total_db),
            "level_dba": float(result.level_total_a_db),
            "harmonics": {"frequency_hz": result.frequencies_hz, "power_W": result.power,
                          "level_db": result.level_db, "level_dba": result.level_a_db}}


def contact_indicators(solution, nl: NonlinearModel) -> list[dict]:
    """Per named contact: max penetration, peak normal/friction force, open/stick/slip fractions."""
    cs = nl.contacts
    R = np.asarray(solution.contact_displacement)
    force = np.asarray(solution.contact_force_time)
    N = force.shape[0]
    r = time_samples(R, N) if R.shape[1] else np.zeros((N, 0))
    state = np.asarray(solution.contact_state)
    tangential = friction_rows(cs, r, force) if R.shape[1] else force   # curved: less −κ q λ_n
    out = []
    for name, kind, idx in nl.groups:
        nr = cs.normal_row[idx]
        has = nr >= 0
        penetration = (r[:, nr[has]] - cs.gap[idx][has]).max(initial=-np.inf) if has.any() else np.nan
        normal = force[:, nr[has]].sum(axis=1) if has.any() else np.zeros(N)
        normal = normal + cs.normal_load[idx].sum()
        tr = cs.tangent_rows[idx]
        friction = np.zeros(N)
        has_tangent = bool(np.any(tr >= 0))        # a law with a tangent (friction) element
        if has_tangent:
            t = np.where(tr >= 0, tr, 0)
            ft = tangential[:, t] * (tr >= 0)
            friction = np.sqrt((ft ** 2).sum(axis=2)).sum(axis=1)
        st = state[:, idx]
        amplitude_1 = np.hypot(R[1, nr[has]], R[2, nr[has]]).max(initial=0.0) if has.any() else np.nan
        out.append({
            "name": name, "type": kind, "pairs": int(len(idx)),
            "max_penetration_m": float(max(penetration, 0.0)) if has.any() else float("nan"),
            "peak_normal_force_N": float(normal.max()),
            "peak_friction_force_N": float(friction.max()) if has_tangent else float("nan"),
            "normal_amplitude_m": float(amplitude_1),
            "open_fraction": float(np.mean(st == 0)),
            "closed_or_stick_fraction": float(np.mean(st == 1)),
            "slip_fraction": float(np.mean(st == 2)),
        })
    return out


_BASELINE = {}     # the matrices of the last model: every point of a run shares them


def baseline_matrices(nl: NonlinearModel):
    """Dense (K + Gᵀ diag(k) G, M, D + Gᵀ diag(c) G) of the linear baseline (the rest state,
    :func:`sarfe.hbm.onset.rest_rows`), built once per model (not per frequency point)."""
    hit = _BASELINE.get(id(nl))
    if hit is not None and hit[0] is nl:
        return hit[1]
    dense = (lambda A: A.toarray() if sp.issparse(A) else np.asarray(A, dtype=float))
    K, M, D = dense(nl.model.stiffness), dense(nl.model.mass), dense(nl.model.damping)
    if nl.contacts.count:
        G = sp.csr_matrix(nl.contacts.gap_map)
        k, c, _ = rest_rows(nl.contacts)
        K = K + (G.T @ sp.diags(k) @ G).toarray()
        D = D + (G.T @ sp.diags(c) @ G).toarray()
    _BASELINE.clear()
    _BASELINE[id(nl)] = (nl, (K, M, D))
    return K, M, D


def baseline_response(nl: NonlinearModel, omega, condensation=None) -> np.ndarray:
    """Û (n,) complex [m] of (K + Gᵀ diag(k) G − ω² M + iω (D + Gᵀ diag(c) G)) Û = F̂
    (:func:`sarfe.hbm.onset.rest_rows`).

    With the point's condensation (:func:`sarfe.pipeline.post.contribution_records.point_condensation`, order
    1 kept) no matrix of model size is factorized: with y = Z₁⁻¹F̂, Y = Z₁⁻¹Gᵀ, C = G Z₁⁻¹ Gᵀ and
    s = k + iωc on the rows a that carry a spring or dashpot (Woodbury),

        (I + C_aa diag(s_a)) r_a = (G y)_a,      Û = y − Y_a (s_a ⊙ r_a).

    Otherwise (or when that system is singular) one dense LU of the matrix (least squares only for
    a singular one: an undamped free-floating part)."""
    if condensation is not None and nl.contacts.count and 1 in np.asarray(condensation.orders):
        springs, dashpots, _ = rest_rows(nl.contacts)
        s = springs + 1j * omega * dashpots
        active = np.flatnonzero(s != 0)
        order = int(np.flatnonzero(np.asarray(condensation.orders) == 1)[0])
        y = np.asarray(condensation.forced)[order]
        if not active.size:
            return y
        n_rows = nl.contacts.row_count
        first = 2 * order                          # (cos, sin) rows of order 1 (no mean kept)
        if 0 in np.asarray(condensation.orders):
            first -= 1
        C = np.asarray(condensation.compliance)
        block = slice(first * n_rows, (first + 1) * n_rows)
        other = slice((first + 1) * n_rows, (first + 2) * n_rows)
        C1 = C[block, block] + 1j * C[block, other]                      # G Z₁⁻¹ Gᵀ (n_rows²)
        r_lin = nl.contacts.gap_map @ y
        A = np.eye(active.size) + C1[np.ix_(active, active)] * s[active][None, :]
        try:
            r = np.linalg.solve(A, r_lin[active])
        except np.linalg.LinAlgError:
            r = None
        if r is not None and np.all(np.isfinite(r)):
            loads = np.zeros((len(condensation.orders), n_rows), dtype=complex)
            loads[order, active] = s[active] * r
            return y - condensation.apply_admittance(loads)[order]
    K, M, D = baseline_matrices(nl)
    S = K - omega ** 2 * M + 1j * omega * D
    try:        # one LU; least squares only for a singular S (an undamped free-floating part)
        U1 = np.linalg.solve(S, nl.excitation_amplitude)
        if not np.all(np.isfinite(U1)):
            raise np.linalg.LinAlgError("non-finite")
    except np.linalg.LinAlgError:
        U1 = np.linalg.lstsq(S, nl.excitation_amplitude, rcond=None)[0]
    return U1


def baseline_harmonics(U1) -> np.ndarray:
    """(3, n) [m] harmonic coefficients [0, Re Û, −Im Û] of the linear baseline's complex
    amplitude Û (n,) (sarfe convention; it moves at ω only)."""
    U1 = np.asarray(U1)
    return np.stack([np.zeros(U1.shape, dtype=float), U1.real, -U1.imag])


def linear_baseline(erp: ErpConfig, stage, nl: NonlinearModel, omega, condensation=None,
                    response=None, normal_displacement=None):
    """Linear response at ω of the structure with its contacts at their static state: preloaded
    (closed) pairs as their linearized spring k_n (and dashpot c_n), stuck friction pairs as k_t,
    open pairs removed (:func:`sarfe.hbm.onset.rest_rows`):

        (K + Gᵀ diag(k) G − ω² M + iω (D + Gᵀ diag(c) G)) Û = F̂   [m],

    (:func:`baseline_response`; ``condensation``: the point's, when computed), its ERP and the
    linear risk per named contact. ``response``: Û when computed beforehand; ``normal_
    displacement``: the radiating rows (2, n_s) of its [Re Û, −Im Û] (:func:`radiating_
    displacement`, shared with the point's own harmonics by :func:`point_record`)."""
    U1 = baseline_response(nl, omega, condensation) if response is None else response
    H = (nl.excitation.shape[0] - 1) // 2
    U = np.zeros((2 * H + 1, stage.dof_count))
    U[:3] = baseline_harmonics(U1)
    W = None                                    # it radiates at ω only: W = [0, W_1c, W_1s]
    if normal_displacement is not None:
        W = np.concatenate([np.zeros((1, np.shape(normal_displacement)[1])),
                            normal_displacement])
    erp, _ = point_erp(erp, stage, U[:3], omega, W)
    contacts = []
    if nl.contacts.count:
        R = (nl.contacts.gap_map @ U.T).T
        risks = linear_risk_from_contacts(nl.contacts, R, nl.tolerance, omega / (2 * np.pi))
        for name, kind, idx in nl.groups:
            sub = [risks[i] for i in idx]
            d = np.array([x.dynamic_tolerance_m for x in sub])
            a = np.array([x.normal_amplitude_m for x in sub])
            s = np.array([x.tangential_peak_to_peak_m for x in sub])
            contacts.append({
                "name": name,
                "normal_amplitude_m": float(np.nanmax(a)) if np.isfinite(a).any() else float("nan"),
                "dynamic_tolerance_m": float(np.nanmin(d)) if np.isfinite(d).any() else float("nan"),
                "rattle_risk": bool(np.any([x.rattle_risk for x in sub])),
                "tangential_peak_to_peak_m": float(np.nanmax(s)) if np.isfinite(s).any()
                else float("nan"),
            })
    return {"erp_power_W": float(erp.power_total), "erp_level_db": float(erp.level_total_db),
            "erp_level_dba": float(erp.level_total_a_db), "contacts": contacts}


ESTIMATE_STRIDE = 8     # a sweep's estimate is computed at every 8th converged point (+ ends, peak)


def _error_estimate(solver: SolverConfig, stage, nl, solution):
    """A-posteriori error estimate of a converged point (:mod:`sarfe.accuracy.estimate`): harmonic
    truncation (H → H' and N → N' solved by condensed Newton from the point, usually 1–4
    iterations), AFT aliasing (N → 2N, likewise), modal truncation (the same on the cached coarser
    Craig–Bampton model), spectral tails. None when switched off, not converged or without
    contacts; a failure of the estimate is reported, never raised."""
    if not solver.error_estimate or not solution.converged \
            or not nl.contacts.count:
        return None
    try:
        return stage_error_estimate(solution, stage, nl).as_dict()
    except Exception as error:  # an estimate must not break a solve
        return {"failed": f"{type(error).__name__}: {error}"}


def _estimates_in_order(estimate, solutions, first, workers):
    """[estimate(s) for s in solutions], the ``first`` (a list of at most one index) in this
    process before the others go to ``workers`` processes: the caches an estimate builds (the
    coarser Craig–Bampton model; its modal basis, made at a model's second condensation after a
    factorized first one, sarfe.hbm.dynamic_stiffness) are then the same for every later estimate — in the
    workers as in the serial loop — and so are the round-off of the results."""
    out = [None] * len(solutions)
    for i in first:
        out[i] = estimate(solutions[i])
    rest = [i for i in range(len(solutions)) if i not in first]
    for i, value in zip(rest, map_points(estimate, [solutions[i] for i in rest], workers)):
        out[i] = value
    return out


def estimated_points(config: CaseConfig, nl, solutions, stride=ESTIMATE_STRIDE) -> list:
    """Indices of the points whose error estimate is computed (:func:`error_estimates`), in the
    order they are computed (the first in the solving process: it builds the caches the others
    share); empty when estimates are off."""
    if not config.solver.error_estimate or not nl.contacts.count:
        return []
    eligible = [i for i, s in enumerate(solutions) if s.converged]
    if config.excitation.sweep is None or len(eligible) <= 2 * stride:
        return eligible
    G = nl.contacts.gap_map

    def amplitude(i):
        U = np.asarray(solutions[i].displacement)
        return float(np.max(np.hypot(G @ U[1], G @ U[2]), initial=0.0))

    return sorted(set(eligible[::stride]) | {eligible[0], eligible[-1],
                                             max(eligible, key=amplitude)})


def point_estimate(config: CaseConfig, stage, nl, solution):
    """The error estimate dict of one point (or None): :func:`_error_estimate`."""
    return _error_estimate(config.solver, stage, nl, solution)


def error_estimates(config: CaseConfig, stage, nl, solutions, stride=ESTIMATE_STRIDE,
                    workers=1, computed=None) -> list:
    """Per point: the error estimate dict, or None (see :func:`_error_estimate`); the estimates
    are computed on ``workers`` processes (:func:`sarfe.util.workers.map_points`), or taken from
    ``computed`` ({point index: estimate} of the points :func:`estimated_points` lists).

    A sweep's points are estimated on a subset and the others take the larger estimate of their
    two estimated neighbours in continuation order (``interpolated: true``, ``from_points``): every
    ``stride``-th converged point, the first and last, and the point with the largest first-harmonic
    contact amplitude (the resonance, where the error peaks). The error of a harmonic-balance
    solution varies smoothly along a branch between those points, so the subset costs 1/stride of
    the per-point estimates; benchmarks/results/accuracy.md measures cost and bracketing. A
    neighbour whose impact the harmonics do not resolve (no bound,
    :mod:`sarfe.accuracy.contact_resolution`) leaves the point without one (inf, its notes)."""
    n = len(solutions)
    solver = config.solver
    if not solver.error_estimate or not nl.contacts.count:
        return [None] * n
    chosen = estimated_points(config, nl, solutions, stride)
    if computed is None:
        estimate = functools.partial(_error_estimate, solver, stage, nl)
        computed = dict(zip(chosen, _estimates_in_order(estimate, [solutions[i] for i in chosen],
                                                        chosen[:1] and [0], workers)))
    if len(chosen) == sum(s.converged for s in solutions):      # every converged point
        return [computed.get(i) if s.converged else None for i, s in enumerate(solutions)]
    # a point whose impact the harmonics do not resolve (no bound, contact_resolution) counts
    # too — a property of the branch there: a neighbour between it and a bounded point takes the
    # larger, no bound, not one from bounded points further along; a point whose re-solve alone
    # did not converge (inf) is that point's alone (as before: its neighbours keep theirs)
    usable = [i for i in sorted(computed) if computed[i] is not None and "failed" not in computed[i]
              and (np.isfinite(computed[i]["amplitude_rel"])
                   or "contact_resolution" in computed[i])]
    out = []
    for i, s in enumerate(solutions):
        if i in computed or not s.converged or not usable:
            out.append(computed.get(i) if s.converged else None)
            continue
        below = [j for j in usable if j < i]
        above = [j for j in usable if j > i]
        near = ([below[-1]] if below else []) + ([above[0]] if above else [])
        merged = {"interpolated": True, "from_points": near, "notes": []}
        for key, value in computed[near[0]].items():
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                values = [computed[j][key] for j in near if not np.isnan(computed[j][key])]
                merged[key] = max(values) if values else float("nan")
        for j in near:      # why a neighbour has no bound: said at this point too
            if not np.isfinite(computed[j]["amplitude_rel"]):
                merged["notes"] = list(computed[j].get("notes") or [])
                if "contact_resolution" in computed[j]:
                    merged["contact_resolution"] = computed[j]["contact_resolution"]
                break
        merged["seconds"] = 0.0
        out.append(merged)
    return out


def harmonic_set_record(solver: SolverConfig, solution):
    """Which harmonic orders a point was solved with (solver.harmonic_set) and the estimate η of
    what the dropped orders carry (for a full-set point: the orders outside the odd set)."""
    H = int(solution.harmonics)
    orders = solution.harmonic_orders
    return {"requested": solver.harmonic_set,
            "used": solution.harmonic_set,
            "orders": list(range(H + 1)) if orders is None else [int(k) for k in orders],
            "dropped_content": float(solution.dropped_content)}


def band_record(erp, linear, omega) -> dict:
    """Third-octave bands of the point's ERP harmonics and of the linear baseline (at ω only)."""
    f = omega / (2 * np.pi)
    linear_power = linear.get("erp_power_W", float("nan"))
    linear_power = linear_power if math.isfinite(linear_power) else 0.0
    return {"nonlinear": third_octave_levels(erp.frequencies_hz, erp.power).as_dict(),
            "linear": third_octave_levels([f], [linear_power]).as_dict()}


def writes_maps(config: CaseConfig, stage) -> bool:
    """True when the run writes an ERP map of every point (``erp_vtu`` in ``output.files`` of an
    FE model and ``output.maps: {every: 1}``: :mod:`sarfe.pipeline.write.result_files`):
    :func:`point_record` then returns the map fields of each point. The few maps of the other
    selections (:mod:`sarfe.pipeline.write.map_points`) are made when written."""
    files = config.output.files
    maps = config.output.maps
    return (getattr(stage, "kind", None) == "fe" and "erp_vtu" in files
            and not isinstance(maps, (str, tuple)) and int(maps["every"]) == 1)


def map_fields(config: CaseConfig, stage, erp, W, omega):
    """(ErpResult without its per-harmonic density, (H + 2, n_s) map fields or None): the
    fields of :func:`sarfe.results.vtk.radiating_fields` (the density per harmonic, the normal
    velocity amplitude and excursion of each radiating node) when the run writes maps
    (:func:`writes_maps`). The nodal arrays of a point then travel from a record worker once,
    as the fields (17 rows at H = 15), instead of as W (2H+1 rows) and the density (H rows): at
    P1 (24,100 radiating nodes, 204 points) 0.7 GB instead of 1.9 GB pickled back and held until
    the maps are written. The ErpResult keeps its powers, levels and ``density_total``."""
    fields = radiating_fields(erp, W, omega) if writes_maps(config, stage) else None
    return dataclasses.replace(erp, density=None), fields


RECORD_CHUNK = 8    # points per product with the ERP map in :func:`point_records`


def record_chunks(count: int, size: int = RECORD_CHUNK) -> list:
    """The point indices 0 … count−1 in runs of ``size`` (the last shorter): the items of the
    record workers (:mod:`sarfe.pipeline.post.point_workers`)."""
    return [list(range(start, min(start + size, count))) for start in range(0, count, size)]


def point_record(config: CaseConfig, stage, nl, index, solution, error_estimate=False):
    """(point dict of summary.json, flat table row, ErpResult without its per-harmonic density,
    map fields or None: :func:`map_fields`). ``error_estimate``: the point's estimate when
    computed beforehand (:func:`error_estimates`), False to compute it here."""
    return point_records(config, stage, nl, [(index, solution, error_estimate)])[0]


def point_records(config: CaseConfig, stage, nl, points) -> list:
    """[:func:`point_record`] of ``points`` = [(index, solution, error_estimate)], with the
    radiating-node displacements of all of them — each point's 2H+1 harmonics and its linear
    baseline's two rows — from one product with the ERP map N (:func:`radiating_displacement`):
    N (24,100 × 757 at P1) is read once per chunk instead of once per point, and the product of
    RECORD_CHUNK points' 8 × 33 rows runs at the machine's multiply rate where one point's 33
    rows wait on memory (≈ 12 instead of ≈ 20 ms a point at P1). The same numbers as one point at
    a time (each row of a product is computed alone)."""
    prepared = []
    for _, solution, _ in points:
        try:    # shared by the contributions and the linear baseline (None: their own paths)
            condensation = point_condensation(nl, solution) if nl.contacts.count else None
        except (ValueError, np.linalg.LinAlgError):
            condensation = None
        U = np.asarray(solution.displacement, dtype=float)
        U1 = baseline_response(nl, float(solution.omega), condensation)
        prepared.append((condensation, U, U1))
    W_all = radiating_displacement(stage, np.concatenate(
        [np.concatenate([U, baseline_harmonics(U1)[1:]]) for _, U, U1 in prepared]))
    records, first = [], 0
    for (index, solution, estimate), (condensation, U, U1) in zip(points, prepared):
        W_both = W_all[first:first + U.shape[0] + 2]
        first += U.shape[0] + 2
        records.append(_point_record(config, stage, nl, index, solution, estimate,
                                     condensation, U, U1, W_both))
    return records


def _point_record(config, stage, nl, index, solution, error_estimate, condensation, U, U1,
                  W_both):
    """:func:`point_record` of a point whose condensation, displacement harmonics U, linear
    baseline Û and radiating displacements W_both (2H+3, n_s: U's rows, then the baseline's
    [Re Û, −Im Û]) :func:`point_records` computed."""
    omega = float(solution.omega)
    contacts = contact_indicators(solution, nl) if nl.contacts.count else []
    for record, dynamics in zip(contacts, contact_dynamics(solution, nl)):
        record.update({k: v for k, v in dynamics.items() if k != "name"})
    contributions = contributions_record(config.erp, stage, nl, solution, condensation)
    if contributions.get("available"):
        shares = {c["name"]: c for c in contributions["sources"]}
        for record in contacts:
            source = shares.get(record["name"], {})
            record.update({"erp_level_dba": source.get("level_dba", float("nan")),
                           "erp_share_a": source.get("share_a", float("nan"))})
    erp, W = point_erp(config.erp, stage, U, omega, W_both[:U.shape[0]])
    linear = linear_baseline(config.erp, stage, nl, omega, condensation, response=U1,
                             normal_displacement=W_both[U.shape[0]:])
    for record, margin in zip(contacts, point_margins(config, stage, nl, solution)):
        record.update(margin)           # onset factor and level sensitivities (what would fix it)
    areas = stage.erp_areas if W.shape[1] == np.size(stage.erp_areas) else np.zeros(W.shape[1])
    audibility = point_audibility(config, erp, W, areas, contributions)
    alone = {source["name"]: source for source in audibility["sources"]}
    for record in contacts:
        record["audibility"] = alone.get(record["name"])
    point = {
        "index": index, "frequency_hz": omega / (2 * np.pi), "omega_rad_s": omega,
        "converged": bool(solution.converged), "stable": None, "stability_note": "",
        "floquet_exponent_1_s": float("nan"),
        "iterations": int(solution.iterations),
        "residual_norm": float(solution.residual_norm),
        "reason": str(solution.reason),
        "erp": _erp_dict(erp), "contacts": contacts, "linear": linear,
        "error_estimate": None,
        "harmonic_set": harmonic_set_record(config.solver, solution),
        "bands": band_record(erp, linear, omega),
        "contributions": contributions,
        "audibility": audibility,
    }
    row = {"case": config.name, "point": index, "frequency_hz": point["frequency_hz"],
           "converged": point["converged"], "stable": None,
           "iterations": point["iterations"], "erp_W": erp.power_total,
           "erp_db": erp.level_total_db, "erp_dba": erp.level_total_a_db,
           "linear_erp_db": linear["erp_level_db"], "linear_erp_dba": linear["erp_level_dba"],
           "erp_error_db": float("nan"), "occupant_spl_dba": audibility["spl_dba"],
           "loudness_sone": audibility["loudness_sone"], "audible": audibility["audible"],
           "audibility_margin_db": audibility["margin_db"]}
    with_verdict(point, row, solution)
    with_estimate(point, row, _error_estimate(config.solver, stage, nl, solution)
                  if error_estimate is False else error_estimate)
    for c in contacts:
        for key in ("max_penetration_m", "peak_normal_force_N", "peak_friction_force_N",
                    "open_fraction", "slip_fraction", "impacts_per_period", "erp_share_a"):
            if key in c:
                row[f"{c['name']}.{key}"] = c[key]
    for c in linear["contacts"]:
        row[f"{c['name']}.linear_rattle_risk"] = c["rattle_risk"]
        row[f"{c['name']}.dynamic_tolerance_m"] = c["dynamic_tolerance_m"]
    for c in contacts:
        row[f"{c['name']}.onset_factor"] = (c.get("onset") or {}).get("factor", float("nan"))
    return (point, row) + map_fields(config, stage, erp, W, omega)


def with_verdict(point, row, solution):
    """Fill the stability fields of a point record (:func:`point_record`) from its solution: a
    record computed before the solution's deferred Hill stability gets them afterwards."""
    stable = solution.stable
    point["stable"] = row["stable"] = None if stable is None else bool(stable)
    point["stability_note"] = str(solution.stability_note)
    point["floquet_exponent_1_s"] = float(solution.floquet_exponent)


def with_estimate(point, row, estimate):
    """Fill the error-estimate fields of a point record (:func:`point_record`): the estimate dict
    (or None) and the table's ±dB."""
    point["error_estimate"] = estimate
    row["erp_error_db"] = (abs(float(estimate["erp_db"])) if estimate and "erp_db" in estimate
                           else float("nan"))
    row["erp_error_interpolated"] = bool(estimate and estimate.get("interpolated", False))


def loudest_point(points) -> int | None:
    """Index (into ``points``) of the loudest point: the highest finite A-weighted ERP among the
    converged points that are not unstable (``stable`` true or not assessed); None if there is none.
    """
    candidates = [i for i, p in enumerate(points)
                  if p["converged"] and p.get("stable") is not False
                  and math.isfinite(p["erp"]["level_dba"])]
    if not candidates:
        return None
    return max(candidates, key=lambda i: points[i]["erp"]["level_dba"])


def worst_of(points):
    """summary.json ``worst``: the loudest point (:func:`loudest_point`: its ``index``, frequency,
    levels, contact ranking and bands) and per contact the sweep maxima over all points."""
    if not points:
        return {}
    j = loudest_point(points)
    if j is None:
        worst = {"index": None, "erp_level_dba": float("nan"), "erp_level_db": float("nan"),
                 "frequency_hz": float("nan"),
                 "note": "no converged, not unstable point with a finite level", "contacts": {}}
    else:
        p = points[j]
        contributions = p.get("contributions") or {}
        excitation = next((s for s in contributions.get("sources", [])
                           if s["name"] == "excitation"), None)
        estimate = p.get("error_estimate") or {}
        error_db = estimate.get("erp_db")
        worst = {"index": p["index"], "erp_level_dba": p["erp"]["level_dba"],
                 "erp_level_db": p["erp"]["level_db"], "frequency_hz": p["frequency_hz"],
                 # the headline's ± and its notes: the point's error bound [dB] (None: none),
                 # whether an estimate was made (its re-solve may have failed: bound unknown),
                 # whether it is interpolated between estimated points, and the stability
                 # verdict (None: not assessed)
                 "erp_error_db": None if error_db is None or not math.isfinite(error_db)
                 else abs(float(error_db)),
                 "error_estimated": bool(estimate),
                 "error_interpolated": bool(estimate.get("interpolated", False)),
                 "stable": p.get("stable"),
                 "ranking": contributions.get("ranking", []),
                 "excitation": None if excitation is None else {
                     "level_dba": excitation["level_dba"], "share_a": excitation["share_a"]},
                 "bands": p.get("bands"), "contacts": {}, **loudest_review(p)}
        if (estimate.get("contact_resolution") or {}).get("resolved") is False:   # why: notes
            worst["error_note"] = ("± by time integration: impact not resolved by H"
                                   if "time_check" in estimate
                                   else "no error bound: impact not resolved by H")
    for c_index, c in enumerate(points[0]["contacts"]):
        pen = [p["contacts"][c_index]["max_penetration_m"] for p in points]
        force = [p["contacts"][c_index]["peak_normal_force_N"] for p in points]
        risk = [p["linear"]["contacts"][c_index]["rattle_risk"] for p in points
                if p["linear"]["contacts"]]
        worst["contacts"][c["name"]] = {
            "max_penetration_m": float(np.nanmax(pen)) if np.isfinite(pen).any() else float("nan"),
            "peak_normal_force_N": float(np.nanmax(force)),
            "linear_rattle_risk_any": bool(any(risk))}
    return worst
