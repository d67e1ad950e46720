r"""What would fix it: per named contact at a point, the onset factor of the excitation and the
sensitivities of the A-weighted ERP level to the contact's case parameters.

Onset (:func:`sarfe.hbm.onset.excitation_onset`, the linear rest state of
:func:`sarfe.hbm.onset.rest_rows` — the linear baseline's): per node pair the factor s* by which
the excitation may grow before the pair closes, separates or slips; a named contact takes the
smallest over its pairs (mechanism and phase of that pair), and likewise the steady factor
(steady stick–slip, what squeaks period after period). 20 lg s* [dB] is the excitation margin:
negative = already active.

Sensitivities (:func:`sarfe.erp.level_sensitivity.level_sensitivities`: one adjoint solve with
the converged Jacobian, no re-solve) per node pair i, aggregated to the case parameter p of the
named contact c with pairs P_c (n_p of them):

    gap_m (one shift for all pairs)          dL/dg   = Σ_i∈P_c dL/dg_i
    normal/tangential_stiffness_N_m (split)  p dL/dp = Σ_i k_i dL/dk_i
    friction_coefficient (shared)            dL/dμ   = Σ_i dL/dμ_i
    preload_N without a normal DOF           dL/dP   = (1/n_p) Σ_i dL/dN0_i
    preload_N with a normal DOF (it sets the overclosures, sarfe.pipeline.model.nonlinear_model.
    preload_gaps: g = −(δ(λ) + C λ), λ_i = P/n_p, C = G_n K⁻¹ G_nᵀ over all preloaded pairs)
                                             dL/dP_c = Σ_i dL/dg_i dg_i/dP_c,
                                             dg_i/dP_c = −(δ'(λ_i) 1[i ∈ P_c] + Σ_j∈P_c C_ij)/n_p,
    and k_n of such a contact moves its overclosure at a fixed preload:
                                             k dL/dk|_P = Σ_i k_i dL/dk_i − Σ_i∈P_c dL/dg_i k ∂δ_i/∂k.

δ' and k ∂δ/∂k are central differences of the law's ``static_deflection`` (exact 1/k_n and
−λ/k_n for the penalty laws). A contact whose gap comes from its preload has no gap parameter
(``gap_m``: NaN). ``per_relative_change_dba`` = p dL/dp [dB(A)]: ×0.1 is the change of the
level for +10 % of p (linear estimate, valid while no contact changes state).
"""
from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from sarfe.erp.level_sensitivity import level_sensitivities
from sarfe.hbm import laws
from sarfe.hbm.onset import excitation_onset

# case parameter → the ContactSet parameter it scales ('gap' is ContactSet.gap)
CASE_PARAMETERS = {"gap_m": "gap", "normal_stiffness_N_m": "normal_stiffness",
                   "tangential_stiffness_N_m": "tangential_stiffness",
                   "friction_coefficient": "friction_coefficient", "preload_N": "preload"}
SENSITIVITY_NAMES = ("gap", "normal_stiffness", "tangential_stiffness", "friction_coefficient",
                     "normal_load")
DEFLECTION_STEP = 1e-6     # relative step of the central differences of static_deflection


def _used(values: dict) -> dict:
    """The entries of a parameter the contact uses (a law or row without it gives NaN), in the
    order of CASE_PARAMETERS."""
    return {k: float(values[k]) for k in CASE_PARAMETERS
            if k in values and values[k] is not None and math.isfinite(values[k])}


def onset_record(onset, idx) -> dict:
    """The onset of a named contact from the pair factors ``onset`` (OnsetFactors) of its pairs
    ``idx``: the smallest factor (its mechanism and phase) and the smallest steady factor."""
    j = idx[int(np.argmin(onset.factor[idx]))]
    factor = float(onset.factor[j])
    steady = float(np.min(onset.steady_factor[idx]))
    with np.errstate(divide="ignore"):
        return {"factor": factor, "level_db": float(20 * np.log10(factor)),
                "mechanism": str(onset.mechanism[j]) or "never",
                "phase_deg": float(np.degrees(onset.phase_rad[j])),
                "steady_factor": steady, "steady_level_db": float(20 * np.log10(steady))}


_CHAIN = {}      # the preload chain of the last model (every point of a run shares it)


def preload_chain(config, nl) -> dict:
    """{contact index in nl.groups: (dg/dP (n_c,) [m/N], k ∂g/∂k (n_c,) [m])} of the contacts whose
    overclosures their preload sets (module docstring), built once per model."""
    hit = _CHAIN.get(id(nl))
    if hit is not None and hit[0] is nl:
        return hit[1]
    cs = nl.contacts
    normal_row = np.asarray(cs.normal_row)
    preloaded = [(g, idx, c.preload_N) for g, (c, (_, _, idx)) in
                 enumerate(zip(config.contacts, nl.groups))
                 if c.preload_N is not None and c.gap_m is None and np.all(normal_row[idx] >= 0)]
    chain = {}
    if preloaded:
        index = np.concatenate([idx for _, idx, _ in preloaded])
        force = np.concatenate([np.full(len(idx), load / len(idx)) for _, idx, load in preloaded])
        slope, stiffness_term = np.zeros(len(index)), np.zeros(len(index))
        kinds = np.asarray(cs.kind)[index]
        for name in dict.fromkeys(kinds):
            law = laws.law(name)
            sel = np.flatnonzero(kinds == name)
            p = cs.law_parameters(law, index[sel])
            h = DEFLECTION_STEP * np.maximum(np.abs(force[sel]), 1e-12)
            slope[sel] = (law.static_deflection(p, force[sel] + h)
                          - law.static_deflection(p, force[sel] - h)) / (2 * h)
            if "normal_stiffness" in p:
                up, down = dict(p), dict(p)
                up["normal_stiffness"] = p["normal_stiffness"] * (1 + DEFLECTION_STEP)
                down["normal_stiffness"] = p["normal_stiffness"] * (1 - DEFLECTION_STEP)
                stiffness_term[sel] = -(law.static_deflection(up, force[sel])
                                        - law.static_deflection(down, force[sel])) \
                    / (2 * DEFLECTION_STEP)
        rows = sp.csr_matrix(cs.gap_map)[normal_row[index]].toarray()
        K = nl.model.stiffness
        K = K.toarray() if sp.issparse(K) else np.asarray(K, dtype=float)
        try:
            compliance = rows @ np.linalg.solve(K, rows.T)
            if not np.all(np.isfinite(compliance)):
                raise np.linalg.LinAlgError("singular")
        except np.linalg.LinAlgError:       # as preload_gaps: g = −δ(λ) alone
            compliance = np.zeros((len(index), len(index)))
        start = 0
        for g, idx, _ in preloaded:
            mine = np.arange(start, start + len(idx))
            start += len(idx)
            d_gap = np.zeros(cs.count)
            d_gap[index] = -compliance[:, mine].sum(axis=1) / len(idx)
            d_gap[idx] -= slope[mine] / len(idx)
            k_term = np.zeros(cs.count)
            k_term[idx] = stiffness_term[mine]
            chain[g] = (d_gap, k_term)
    _CHAIN.clear()
    _CHAIN[id(nl)] = (nl, chain)
    return chain


def named_sensitivities(config, nl, sensitivities) -> list[dict]:
    """Per named contact: {"dL_dp": {case key: dL/dp [dB(A) per unit]}, "per_relative_change_dba":
    {case key: p dL/dp [dB(A)]}, "method"} from the pair derivatives (module docstring); a
    parameter the contact's law or rows do not use is left out (all of them: method 'singular')."""
    cs = nl.contacts
    d = sensitivities.derivative
    chain = preload_chain(config, nl)
    out = []
    for g, ((name, _, idx), entry) in enumerate(zip(nl.groups, config.contacts)):
        def total(values, weights=None):
            v = np.asarray(values, dtype=float)[idx]
            w = np.ones(len(idx)) if weights is None else np.asarray(weights, dtype=float)[idx]
            return float(np.sum(v * w)) if np.any(np.isfinite(v)) else float("nan")

        slope, relative = {}, {}
        d_gap = d.get("gap", np.full(cs.count, np.nan))
        if g not in chain:
            slope["gap_m"] = total(d_gap)
            relative["gap_m"] = total(d_gap, cs.gap)
        for key in ("normal_stiffness", "tangential_stiffness"):
            values = cs.parameters.get(key)
            if key in d and values is not None:
                relative[f"{key}_N_m"] = total(d[key], values)
        if g in chain and math.isfinite(relative.get("normal_stiffness_N_m", float("nan"))):
            relative["normal_stiffness_N_m"] += float(np.nansum(d_gap * chain[g][1]))
        mu = cs.parameters.get("friction_coefficient")
        if "friction_coefficient" in d and mu is not None:
            slope["friction_coefficient"] = total(d["friction_coefficient"])
            relative["friction_coefficient"] = total(d["friction_coefficient"], mu)
        load = entry.preload_N
        if load is not None and g in chain:
            slope["preload_N"] = float(np.nansum(d_gap * chain[g][0]))
        elif load is not None and "normal_load" in d:
            slope["preload_N"] = total(d["normal_load"]) / len(idx)
        if "preload_N" in slope:
            relative["preload_N"] = slope["preload_N"] * float(load)
        for key, value in entry.params.items():     # the split stiffnesses per unit of the total
            if key in ("normal_stiffness_N_m", "tangential_stiffness_N_m") and key in relative \
                    and isinstance(value, (int, float)) and value:
                slope[key] = relative[key] / float(value)
        out.append({"dL_dp": _used(slope), "per_relative_change_dba": _used(relative),
                    "method": sensitivities.method})
    return out


def point_margins(config, stage, nl, solution) -> list[dict]:
    """Per named contact (``nl.groups`` order): {"onset": onset_record | None, "sensitivities":
    named sensitivities | None} of one point. The onset needs only ω (any point with contacts);
    the sensitivities a converged harmonic-balance point (not 'linear', not a time-integration
    stand-in) with a radiating surface. A failure is reported in the record, never raised."""
    if not nl.contacts.count:
        return []
    out = [{"onset": None, "sensitivities": None} for _ in nl.groups]
    omega = float(solution.omega)
    try:
        onset = excitation_onset(nl.model, nl.contacts, nl.excitation, omega)
        for record, (_, _, idx) in zip(out, nl.groups):
            record["onset"] = onset_record(onset, idx)
    except Exception as error:     # a diagnostic must not break a solve
        for record in out:
            record["onset"] = {"failed": f"{type(error).__name__}: {error}"}
    if not (solution.converged and solution.method == "harmonic balance"
            and stage.erp_map.shape[0]):
        return out
    erp = config.erp
    try:
        _, sensitivities = level_sensitivities(
            nl.model, nl.contacts, nl.excitation, solution, stage.erp_map, stage.erp_areas,
            names=SENSITIVITY_NAMES, density=erp.rho_kg_m3, sound_speed=erp.c_m_s,
            radiation_loss_factor=erp.radiation_loss_factor,
            reference_power=erp.reference_power_W)
        for record, named in zip(out, named_sensitivities(config, nl, sensitivities)):
            record["sensitivities"] = named
    except Exception as error:     # a diagnostic must not break a solve
        for record in out:
            record["sensitivities"] = {"failed": f"{type(error).__name__}: {error}"}
    return out


def best_change(contacts, step: float = 0.1) -> dict | None:
    """The change of one contact parameter by ±``step`` (relative) that lowers the A-weighted
    level most, from the records' ``per_relative_change_dba`` (linear estimate): {"contact",
    "parameter", "change": "+10 %" | "-10 %", "level_change_dba" (< 0)}; None if none lowers it."""
    best = None
    for c in contacts:
        sens = c.get("sensitivities") or {}
        for key, value in (sens.get("per_relative_change_dba") or {}).items():
            if value is None or not math.isfinite(value) or value == 0:
                continue
            gain = -abs(step * value)
            if best is None or gain < best["level_change_dba"]:
                best = {"contact": c["name"], "parameter": key,
                        "change": f"{'-' if value > 0 else '+'}{round(100 * step)} %",
                        "level_change_dba": gain}
    return best
