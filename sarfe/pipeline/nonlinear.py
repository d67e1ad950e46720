r"""The nonlinear model of a case on the kept DOFs: damping, contacts, excitation harmonics.

Excitation (one harmonic at ω): f_e(θ) = Re(F̂ e^{iθ}), F̂ = Σ_l F_l e^{iφ_l} b_l (+ A e^{iφ} b_base),
so in sarfe's Fourier convention F[1] = Re F̂ (cos), F[2] = −Im F̂ (sin), all other rows 0.
Contacts: one ContactSet entry per node pair (FE) or per named contact (matrices), with rows
w = n·(u_a − u_b), q_i = t_i·(u_a − u_b) of G; stiffness and preload of a named contact are split
equally over its pairs.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from sarfe.io.case import Case, load_case
from sarfe.pipeline.linear import LinearStage


@dataclass(frozen=True)
class NonlinearModel:
    """What the HBM needs for one case: model, contacts, excitation harmonics and bookkeeping."""

    model: object                 # sarfe.hbm.model.LinearModel
    contacts: object              # sarfe.hbm.contacts.ContactSet
    excitation: np.ndarray        # (2H+1, n) [N]
    excitation_amplitude: np.ndarray  # F̂ (n,) complex [N]
    groups: list                  # per named contact: (name, type, contact indices in the set)
    tolerance: np.ndarray         # (n_c,) [m]


def damping_matrix(case: Case, stage: LinearStage):
    """D on the kept DOFs: the matrices' own D, modal ζ (reduced eigenmodes) or α M + β K,
    plus a deck's discrete dampers (CBUSH B, reduced: ``stage.info['spring_damping']``)."""
    added = getattr(stage, "added_damping", None)
    matrix = _case_damping(case, stage)
    return matrix if added is None else matrix + added


def _case_damping(case: Case, stage: LinearStage):
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
        k_pairs = np.full(pairs, stiffness * share)
        kt_pairs = np.full(pairs, contact.get("tangential_stiffness_N_m", 0.0) * share)
        geometry = stage.contacts.get(name) if stage.kind == "fe" else None
        if getattr(geometry, "normal_stiffness", None) is not None:  # deck springs (from_elements)
            if "normal_stiffness_N_m" not in contact:
                k_pairs = np.asarray(geometry.normal_stiffness, dtype=float)
                stiffness = float(k_pairs.sum())
            if "tangential_stiffness_N_m" not in contact:
                kt_pairs = np.asarray(geometry.tangential_stiffness, dtype=float)
        if not has_normal:
            g, load = np.zeros(pairs), contact["preload_N"]
        elif "gap_m" in contact:
            g, load = np.full(pairs, float(contact["gap_m"])), 0.0
        elif "preload_N" in contact:
            g, load = -contact["preload_N"] * share / k_pairs, 0.0
        else:  # FE default: the geometric gap of each node pair along its normal
            g, load = np.asarray(stage.contacts[name].distances, dtype=float), 0.0
        for p in range(pairs):
            kind.append(contact["type"])
            gap.append(g[p])
            k_n.append(k_pairs[p])
            k_t.append(kt_pairs[p])
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
