r"""Nonlinear stage of a case: damping, contacts, excitation harmonics → HBM per point → ERP,
contact indicators and the linear risk baseline → summary.json and the other result files.

Excitation (one harmonic at ω): f_e(θ) = Re(F̂ e^{iθ}), F̂ = Σ_l F_l e^{iφ_l} b_l (+ A e^{iφ} b_base),
so in sarfe's Fourier convention F[1] = Re F̂ (cos), F[2] = −Im F̂ (sin), all other rows 0.
ERP of a point: w_s = N ũ (radiating-node normal displacement harmonics) → :func:`sarfe.erp.
equivalent_radiated_power`. Linear baseline: (K − ω² M + iω D) Û = F̂ without contacts →
:func:`sarfe.risk.linear_risk_from_contacts` and its ERP.
"""
from __future__ import annotations

import dataclasses
import datetime as _dt
import math
import os
import shutil
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from sarfe.io.case import Case, load_case
from sarfe.io.errors import EXIT_NOT_CONVERGED, CaseError
from sarfe.pipeline import adapters
from sarfe.pipeline.linear import LinearStage, build_linear_model, linear_model_key

adapters.guard_fft_backend()


@dataclass
class CaseResult:
    """Result of :func:`solve_case`: ``summary`` (= summary.json), ``rows`` (one flat dict per
    frequency point), ``exit_code`` (0 all converged, 3 some point did not converge),
    ``solutions`` (HarmonicSolution per point), ``output_dir`` (None if nothing was written)."""

    summary: dict
    rows: list
    exit_code: int
    solutions: list = field(default_factory=list, repr=False)
    output_dir: Path | None = None


@dataclass(frozen=True)
class NonlinearModel:
    """What the HBM needs for one case: model, contacts, excitation harmonics and bookkeeping."""

    model: object                 # sarfe.hbm.model.LinearModel
    contacts: object              # sarfe.hbm.contacts.ContactSet
    excitation: np.ndarray        # (2H+1, n) [N]
    excitation_amplitude: np.ndarray  # F̂ (n,) complex [N]
    groups: list                  # per named contact: (name, type, contact indices in the set)
    tolerance: np.ndarray         # (n_c,) [m]


# ------------------------------------------------------------------------------------- damping
def damping_matrix(case: Case, stage: LinearStage):
    """D on the kept DOFs: the matrices' own D, modal ζ (reduced eigenmodes) or α M + β K."""
    damping = case.data["damping"]
    M, K = stage.mass, stage.stiffness
    if stage.damping is not None:
        return stage.damping
    if "rayleigh" in damping:
        return damping["rayleigh"]["alpha_1_s"] * M + damping["rayleigh"]["beta_s"] * K
    from sarfe.reduction.damping import reduced_modal_damping

    n = M.shape[0]
    zeta = damping.get("modal_zeta", 0.0)
    if isinstance(zeta, list):
        values = np.full(n, zeta[-1]["zeta"])
        for entry in zeta:
            first, last = entry["modes"]
            values[first - 1:min(last, n)] = entry["zeta"]
        zeta = values
    dense = (lambda A: A.toarray() if sp.issparse(A) else np.asarray(A))
    return reduced_modal_damping(dense(M), dense(K), zeta)


# ------------------------------------------------------------------------------------ contacts
def _dof_row(ref, n):
    row = np.zeros(n)
    row[ref["dof"]] += ref["sign"]
    if ref["relative_to"] != "ground":
        row[ref["relative_to"]] -= ref["sign"]
    return row


def build_contacts(case: Case, stage: LinearStage):
    """ContactSet in the kept DOFs (one set entry per node pair, FE) and per-name groups."""
    from sarfe.hbm.contacts import make_contact_set

    n = stage.dof_count
    rows, kind, normal_row, tangent_rows = [], [], [], []
    gap, k_n, k_t, mu, n0, names, tolerance, groups = [], [], [], [], [], [], [], []

    def add_row(vector):
        rows.append(vector)
        return len(rows) - 1

    for contact in case.data["contacts"]:
        name, squeak = contact["name"], contact["type"] == "squeak"
        start = len(kind)
        if stage.kind == "fe":
            geometry = stage.contacts[name]
            pairs = len(geometry.nodes_a)
            for p in range(pairs):
                directions = geometry.frames[p] if squeak else geometry.frames[p][:1]
                made = []
                for e in directions:
                    vector = np.zeros(n)
                    for comp in range(3):
                        if geometry.coords_a[p, comp] >= 0:
                            vector[geometry.coords_a[p, comp]] += e[comp]
                        if geometry.coords_b[p, comp] >= 0:
                            vector[geometry.coords_b[p, comp]] -= e[comp]
                    made.append(add_row(vector))
                normal_row.append(made[0])
                tangent_rows.append(made[1:3] if squeak else [-1, -1])
            share = 1.0 / pairs
            has_normal = True
        else:
            pairs = 1
            has_normal = "normal_dof" in contact
            normal_row.append(add_row(_dof_row(contact["normal_dof"], n)) if has_normal else -1)
            t = [add_row(_dof_row(ref, n)) for ref in contact.get("tangential_dofs", [])]
            tangent_rows.append((t + [-1, -1])[:2])
            share = 1.0
        stiffness = contact.get("normal_stiffness_N_m", 0.0)
        if not has_normal:
            g, load = np.zeros(pairs), contact["preload_N"]
        elif "gap_m" in contact:
            g, load = np.full(pairs, float(contact["gap_m"])), 0.0
        elif "preload_N" in contact:
            g, load = np.full(pairs, -contact["preload_N"] / stiffness), 0.0
        else:  # FE default: the geometric gap of each node pair along its normal
            g, load = np.asarray(stage.contacts[name].distances, dtype=float), 0.0
        for p in range(pairs):
            kind.append(contact["type"])
            gap.append(g[p])
            k_n.append(stiffness * share)
            k_t.append(contact.get("tangential_stiffness_N_m", 0.0) * share)
            mu.append(contact.get("friction_coefficient", 0.0))
            n0.append(load * share)
            tolerance.append(contact["tolerance_m"])
        names += [name] if pairs == 1 else [f"{name}[{p}]" for p in range(pairs)]
        groups.append((name, contact["type"], np.arange(start, len(kind))))
    G = sp.csr_matrix(np.array(rows).reshape(len(rows), n))
    gap = np.array(gap, dtype=float)
    preloaded = [(idx, c["preload_N"]) for c, (_, _, idx) in zip(case.data["contacts"], groups)
                 if "preload_N" in c and "gap_m" not in c and np.all(np.array(normal_row)[idx] >= 0)]
    if preloaded:
        gap = preload_gaps(stage.stiffness, G, np.array(normal_row), gap, np.array(k_n), preloaded)
    contacts = make_contact_set(G, np.array(kind, dtype=object), np.array(normal_row, dtype=int),
                                np.array(tangent_rows, dtype=int).reshape(-1, 2), gap, k_n, k_t,
                                mu, n0, names)
    return contacts, groups, np.array(tolerance, dtype=float)


def preload_gaps(stiffness, gap_map, normal_row, gap, normal_stiffness, preloaded):
    r"""Overclosures g that make the static solution carry the requested preloads.

    Static equilibrium with the preloaded contacts closed: K u + G_nᵀ λ = 0 → w = G_n u = −C λ with
    the static compliance C = G_n K⁻¹ G_nᵀ between the paired DOFs, and λ = k_n (w − g), so

        g = −(λ / k_n + C λ),    λ_i = P / n_p  for the n_p node pairs of a contact with preload P.

    Only the preloaded contacts are assumed closed (the others open) and all are solved together.
    A singular K (a free-floating matrices model) falls back to g = −λ / k_n.
    """
    contacts = np.concatenate([idx for idx, _ in preloaded])
    force = np.concatenate([np.full(len(idx), load / len(idx)) for idx, load in preloaded])
    rows = gap_map[normal_row[contacts]].toarray()
    K = stiffness.toarray() if sp.issparse(stiffness) else np.asarray(stiffness, dtype=float)
    gap = gap.copy()
    try:
        compliance = rows @ np.linalg.solve(K, rows.T)
        if not np.all(np.isfinite(compliance)):
            raise np.linalg.LinAlgError("singular")
    except np.linalg.LinAlgError:
        compliance = np.zeros((len(contacts), len(contacts)))
    gap[contacts] = -(force / normal_stiffness[contacts] + compliance @ force)
    return gap


def excitation_amplitude(case: Case, stage: LinearStage) -> np.ndarray:
    """F̂ (n,) complex [N]: f_e(θ) = Re(F̂ e^{iθ})."""
    exc = case.data["excitation"]
    amplitude = np.zeros(stage.dof_count, dtype=complex)
    for load, vector in zip(exc.get("forces", []), stage.load_vectors):
        amplitude += load["force_N"] * np.exp(1j * math.radians(load["phase_deg"])) * vector
    if "base_acceleration" in exc:
        base = exc["base_acceleration"]
        amplitude += (base["amplitude_m_s2"] * np.exp(1j * math.radians(base["phase_deg"]))
                      * stage.base_vector)
    return amplitude


def nonlinear_model(case, stage: LinearStage) -> NonlinearModel:
    """LinearModel (with damping), ContactSet and excitation harmonics of a case."""
    from sarfe.hbm.model import make_linear_model

    case = load_case(case)
    model = make_linear_model(stage.mass, damping_matrix(case, stage), stage.stiffness)
    contacts, groups, tolerance = build_contacts(case, stage)
    H = case.data["solver"]["harmonics"]
    amplitude = excitation_amplitude(case, stage)
    F = np.zeros((2 * H + 1, stage.dof_count))
    F[1], F[2] = amplitude.real, -amplitude.imag
    return NonlinearModel(model, contacts, F, amplitude, groups, tolerance)


# ------------------------------------------------------------------------------- post-process
def _erp(case, stage, displacement, omega):
    """ErpResult of displacement harmonics (2H+1, n) at ω (zero power without radiating nodes)."""
    from sarfe.erp import equivalent_radiated_power

    erp = case.data["erp"]
    W = np.asarray(displacement) @ stage.erp_map.T
    if W.shape[1] == 0:  # no radiating surface: a zero-area node keeps the shapes valid
        W, areas = np.zeros((W.shape[0], 1)), np.zeros(1)
    else:
        areas = stage.erp_areas
    result = equivalent_radiated_power(W, omega, areas, density=erp["rho_kg_m3"],
                                       sound_speed=erp["c_m_s"],
                                       radiation_loss_factor=erp["radiation_loss_factor"],
                                       reference_power=erp["reference_power_W"])
    return result, W


def _erp_dict(result):
    return {"power_W": float(result.power_total), "level_db": float(result.level_total_db),
            "level_dba": float(result.level_total_a_db),
            "harmonics": {"frequency_hz": result.frequencies_hz, "power_W": result.power,
                          "level_db": result.level_db, "level_dba": result.level_a_db}}


def contact_indicators(solution, nl: NonlinearModel) -> list[dict]:
    """Per named contact: max penetration, peak normal/friction force, open/stick/slip fractions."""
    from sarfe.hbm.harmonics import time_samples

    cs = nl.contacts
    R = np.asarray(solution.contact_displacement)
    force = np.asarray(solution.contact_force_time)
    N = force.shape[0]
    r = time_samples(R, N) if R.shape[1] else np.zeros((N, 0))
    state = np.asarray(solution.contact_state)
    out = []
    for name, kind, idx in nl.groups:
        nr = cs.normal_row[idx]
        has = nr >= 0
        penetration = (r[:, nr[has]] - cs.gap[idx][has]).max(initial=-np.inf) if has.any() else np.nan
        normal = force[:, nr[has]].sum(axis=1) if has.any() else np.zeros(N)
        normal = normal + cs.normal_load[idx].sum()
        tr = cs.tangent_rows[idx]
        friction = np.zeros(N)
        if kind == "squeak":
            t = np.where(tr >= 0, tr, 0)
            ft = force[:, t] * (tr >= 0)
            friction = np.sqrt((ft ** 2).sum(axis=2)).sum(axis=1)
        st = state[:, idx]
        amplitude_1 = np.hypot(R[1, nr[has]], R[2, nr[has]]).max(initial=0.0) if has.any() else np.nan
        out.append({
            "name": name, "type": kind, "pairs": int(len(idx)),
            "max_penetration_m": float(max(penetration, 0.0)) if has.any() else float("nan"),
            "peak_normal_force_N": float(normal.max()),
            "peak_friction_force_N": float(friction.max()) if kind == "squeak" else float("nan"),
            "normal_amplitude_m": float(amplitude_1),
            "open_fraction": float(np.mean(st == 0)),
            "closed_or_stick_fraction": float(np.mean(st == 1)),
            "slip_fraction": float(np.mean(st == 2)),
        })
    return out


def linear_baseline(case, stage, nl: NonlinearModel, omega):
    """Linear response without contacts at ω: ERP and risk per named contact."""
    from sarfe.risk import linear_risk_from_contacts

    M, D, K = nl.model.mass, nl.model.damping, nl.model.stiffness
    dense = (lambda A: A.toarray() if sp.issparse(A) else np.asarray(A))
    S = dense(K) - omega ** 2 * dense(M) + 1j * omega * dense(D)
    U1 = np.linalg.lstsq(S, nl.excitation_amplitude, rcond=None)[0]
    H = (nl.excitation.shape[0] - 1) // 2
    U = np.zeros((2 * H + 1, stage.dof_count))
    U[1], U[2] = U1.real, -U1.imag
    erp, _ = _erp(case, stage, U, omega)
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


# -------------------------------------------------------------------------------------- solving
def _solver_options(case):
    solver = case.data["solver"]
    engine = adapters.hbm_engine()
    if engine is None:
        return None, None, None
    _, _, SolverOptions, ContinuationOptions = engine
    values = {"tolerance": solver["tolerance"], "max_iterations": solver["max_iterations"],
              "stability": solver["stability"]}
    options = adapters.make_options(SolverOptions, values)
    cont = solver["continuation"]
    cvalues = dict(initial_step=cont["initial_step"], min_step=cont["min_step"],
                   max_step=cont["max_step"], max_points=cont["max_points"], solver=options)
    return engine, options, adapters.make_options(ContinuationOptions, cvalues)


def _bar(progress, total, description):
    if not progress or not sys.stderr.isatty():
        return None
    from tqdm import tqdm
    return tqdm(total=total, desc=description, unit="point", leave=False)


def linear_solution(nl: NonlinearModel, omega, H, N):
    """The exact periodic solution of a model without contacts, as a HarmonicSolution."""
    from sarfe.hbm.solution import HarmonicSolution
    from sarfe.hbm.time_integration import linear_harmonic_response

    U = linear_harmonic_response(nl.model, nl.excitation, omega)
    rows, count = nl.contacts.row_count, nl.contacts.count
    return HarmonicSolution(
        omega=float(omega), harmonics=int(H), samples_per_period=int(N), displacement=U,
        contact_displacement=np.zeros((2 * H + 1, rows)), contact_force=np.zeros((2 * H + 1, rows)),
        contact_force_time=np.zeros((N, rows)), contact_state=np.zeros((N, count), dtype=np.int8),
        converged=True, reason="linear model (no contacts): exact solution", iterations=0,
        residual_norm=0.0)


def _solve_one(engine, nl, omega, H, N, options, previous):
    """One HBM point; on failure retry once from a short time integration (its end state).

    An engine exception or a point that still fails is returned with ``converged=False`` and the
    reason (the time-integration state stands in when the engine raised), never dropped.
    """
    contacts = nl.contacts
    if not contacts.count:
        return linear_solution(nl, omega, H, N)
    if engine is None:
        return adapters.time_integration_point(nl.model, contacts, nl.excitation, omega, H, N)
    error = None
    try:
        solution = engine[0](nl.model, contacts, nl.excitation, omega, H, N, initial=previous,
                             options=options)
    except Exception as exc:  # an engine failure must not lose the other points
        solution, error = None, exc
    if solution is not None and (solution.converged or not contacts.count):
        return solution
    guess = adapters.time_integration_point(nl.model, contacts, nl.excitation, omega, H, N,
                                            max_periods=40)
    try:
        retry = engine[0](nl.model, contacts, nl.excitation, omega, H, N,
                          initial=guess.displacement, options=options)
        if retry.converged:
            return retry
    except Exception:
        pass
    if solution is None:
        guess.converged = False
        guess.reason = (f"HBM engine failed ({type(error).__name__}: {error}); values are the "
                        "time-integration state after 40 periods")
        return guess
    return solution


def _finish_sweep(engine, nl, solutions, start, end, H, N, options, step):
    """Complete a continuation that stopped before ``end`` point by point (natural-parameter
    steps of ``step``·|end − start| from the last converged point). The points it adds carry
    ``reason`` '… (point-by-point after the continuation stopped)'."""
    if not solutions:
        return solutions
    span = abs(end - start)
    last = solutions[-1].omega
    if abs(last - end) <= 1e-3 * span:
        return solutions
    if (end - last) * (end - start) < 0:   # past the end (e.g. turned back): nothing to add
        return solutions
    count = max(2, int(math.ceil(abs(end - last) / (step * span))) + 1)
    previous = next((s for s in reversed(solutions) if s.converged), None)
    for omega in np.linspace(last, end, count)[1:]:
        solution = _solve_one(engine, nl, float(omega), H, N, options, previous)
        try:
            solution = dataclasses.replace(
                solution, reason=f"{solution.reason} (point-by-point after the continuation stopped)")
        except TypeError:
            solution.reason += " (point-by-point after the continuation stopped)"
        solutions.append(solution)
        if solution.converged and not isinstance(solution, adapters.SimpleNamespace):
            previous = solution
    return solutions


def solve_points(case, nl: NonlinearModel, progress=False):
    """HarmonicSolution per frequency point (listed frequencies in order, or a continuation)."""
    solver, exc = case.data["solver"], case.data["excitation"]
    H, N = solver["harmonics"], solver["samples_per_period"]
    engine, options, cont_options = _solver_options(case)
    contacts = nl.contacts
    if "sweep" in exc:
        start, end = (2 * np.pi * exc["sweep"][k] for k in ("start_hz", "end_hz"))
        if engine is not None and contacts.count:
            bar = _bar(progress, None, "sweep")
            try:
                solutions = list(engine[1](nl.model, contacts, nl.excitation, start, end, H, N,
                                           options=cont_options,
                                           progress=(lambda done, total: bar.update(1))
                                           if bar is not None else None))
                return _finish_sweep(engine, nl, solutions, start, end, H, N, options,
                                     solver["continuation"]["initial_step"])
            except Exception as error:  # fall back to a point-by-point sweep
                import warnings
                warnings.warn(f"continuation failed ({type(error).__name__}: {error}); "
                              "sweeping point by point instead", RuntimeWarning, stacklevel=2)
            finally:
                if bar is not None:
                    bar.close()
        count = min(max(2, int(round(1.0 / solver["continuation"]["initial_step"])) + 1), 101)
        omegas = np.linspace(start, end, count)
    else:
        omegas = 2 * np.pi * np.asarray(exc["frequency_hz"], dtype=float)
    solutions, previous = [], None
    bar = _bar(progress, len(omegas), "frequencies")
    try:
        for omega in omegas:
            solution = _solve_one(engine, nl, float(omega), H, N, options, previous)
            solutions.append(solution)
            previous = solution if getattr(solution, "converged", False) and not isinstance(
                solution, adapters.SimpleNamespace) else None
            if bar is not None:
                bar.update(1)
    finally:
        if bar is not None:
            bar.close()
    return solutions


def _point_record(case, stage, nl, index, solution):
    omega = float(solution.omega)
    erp, W = _erp(case, stage, solution.displacement, omega)
    contacts = contact_indicators(solution, nl) if nl.contacts.count else []
    linear = linear_baseline(case, stage, nl, omega)
    stable = getattr(solution, "stable", None)
    point = {
        "index": index, "frequency_hz": omega / (2 * np.pi), "omega_rad_s": omega,
        "converged": bool(solution.converged), "stable": None if stable is None else bool(stable),
        "iterations": int(getattr(solution, "iterations", 0)),
        "residual_norm": float(getattr(solution, "residual_norm", float("nan"))),
        "reason": str(getattr(solution, "reason", "")),
        "erp": _erp_dict(erp), "contacts": contacts, "linear": linear,
    }
    row = {"case": case.name, "point": index, "frequency_hz": point["frequency_hz"],
           "converged": point["converged"], "stable": point["stable"],
           "iterations": point["iterations"], "erp_W": erp.power_total,
           "erp_db": erp.level_total_db, "erp_dba": erp.level_total_a_db,
           "linear_erp_db": linear["erp_level_db"], "linear_erp_dba": linear["erp_level_dba"]}
    for c in contacts:
        for key in ("max_penetration_m", "peak_normal_force_N", "peak_friction_force_N",
                    "open_fraction", "slip_fraction"):
            row[f"{c['name']}.{key}"] = c[key]
    for c in linear["contacts"]:
        row[f"{c['name']}.linear_rattle_risk"] = c["rattle_risk"]
    return point, row, erp, W


def _worst(points):
    if not points:
        return {}
    levels = [p["erp"]["level_dba"] for p in points]
    finite = [i for i, x in enumerate(levels) if math.isfinite(x)]
    j = max(finite, key=lambda i: levels[i]) if finite else 0
    worst = {"erp_level_dba": levels[j], "erp_level_db": points[j]["erp"]["level_db"],
             "frequency_hz": points[j]["frequency_hz"], "contacts": {}}
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


# --------------------------------------------------------------------------------------- outputs
def _write_outputs(case, stage, nl, summary, rows, solutions, erps, normal_w, directory: Path):
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
            data.append(outputs.erp_point_data(mesh.n_nodes, e, W, float(s.omega),
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


def _replace_directory(temporary: Path, target: Path):
    """Move a finished temporary directory onto ``target`` (replacing an older result)."""
    backup = None
    if target.exists():
        backup = target.with_name(f".{target.name}.old-{os.getpid()}")
        os.replace(target, backup)
    os.replace(temporary, target)
    if backup is not None:
        shutil.rmtree(backup, ignore_errors=True)


def solve_case(case, linear_stage=None, output_dir=None, progress=False, write=True) -> CaseResult:
    """Solve a case end to end (module docstring). Returns :class:`CaseResult`.

    ``output_dir``: where the result files go (default ``output.directory`` of the case, relative to
    the current directory); ``write=False`` writes nothing. Files are written into a temporary
    directory next to the target and moved into place at the end, so a failed run leaves nothing.
    Raises CaseError for problems in the case; a non-converged point gives ``exit_code`` 3.
    """
    from sarfe import __version__

    started = time.perf_counter()
    case = load_case(case)
    timings = {}
    if linear_stage is None:
        linear_stage = build_linear_model(case, progress=progress)
        timings.update(linear_stage.timings)
    elif linear_stage.key != linear_model_key(case):
        raise ValueError("linear_stage was built for a different linear model (key mismatch)")
    stage = linear_stage
    clock = time.perf_counter()
    nl = nonlinear_model(case, stage)
    timings["setup_s"] = time.perf_counter() - clock

    clock = time.perf_counter()
    solutions = solve_points(case, nl, progress=progress)
    timings["hbm_s"] = time.perf_counter() - clock

    clock = time.perf_counter()
    points, rows, erps, normal_w = [], [], [], []
    for index, solution in enumerate(solutions):
        point, row, erp, W = _point_record(case, stage, nl, index, solution)
        points.append(point)
        rows.append(row)
        erps.append(erp)
        normal_w.append(W)
    timings["postprocess_s"] = time.perf_counter() - clock
    not_converged = [p["index"] for p in points if not p["converged"]]
    sweep = case.data["excitation"].get("sweep")
    sweep_complete = None
    if sweep and points:
        span = abs(sweep["end_hz"] - sweep["start_hz"])
        sweep_complete = abs(points[-1]["frequency_hz"] - sweep["end_hz"]) <= 1e-3 * span
    exit_code = EXIT_NOT_CONVERGED if (not_converged or not points or sweep_complete is False) else 0
    engine = "harmonic balance" if adapters.hbm_engine() else "time integration (no HBM engine)"
    summary = {
        "sarfe_version": __version__,
        "case": case.name,
        "case_file": case.source,
        "created_utc": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "exit_code": exit_code,
        "all_converged": not not_converged and bool(points),
        "non_converged_points": not_converged,
        "sweep_complete": sweep_complete,        # None without a sweep; False → exit code 3
        "sweep_stop_reason": (points[-1]["reason"] if sweep_complete is False else None),
        "engine": engine,
        "linear_model_key": stage.key,
        "model": dict(stage.info, kind=stage.kind, kept_dofs=int(stage.dof_count),
                      mode_frequencies_hz=np.asarray(stage.mode_frequencies_hz)[:50]),
        "solver": {k: v for k, v in case.data["solver"].items()},
        "contacts": [{"name": name, "type": kind, "pairs": int(len(idx))}
                     for name, kind, idx in nl.groups],
        "points": points,
        "worst": _worst(points),
        "timings_s": timings,
    }
    result = CaseResult(summary, rows, exit_code, solutions)
    if not write:
        summary["timings_s"]["total_s"] = time.perf_counter() - started
        return result
    target = Path(output_dir if output_dir is not None else case.data["output"]["directory"])
    target = target.resolve()
    target.parent.mkdir(parents=True, exist_ok=True)
    temporary = Path(tempfile.mkdtemp(prefix=f".{target.name}.tmp-", dir=target.parent))
    try:
        clock = time.perf_counter()
        summary["timings_s"]["outputs_s"] = 0.0
        summary["timings_s"]["total_s"] = time.perf_counter() - started
        written = _write_outputs(case, stage, nl, summary, rows, solutions, erps, normal_w,
                                 temporary)
        summary["files"] = written
        summary["timings_s"]["outputs_s"] = time.perf_counter() - clock
        summary["timings_s"]["total_s"] = time.perf_counter() - started
        from sarfe.io.outputs import write_summary_json
        write_summary_json(temporary / "summary.json", summary)
        _replace_directory(temporary, target)
    except BaseException:
        shutil.rmtree(temporary, ignore_errors=True)
        raise
    result.output_dir = target
    return result
