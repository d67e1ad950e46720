r"""The nonlinear model of a case on the kept DOFs: damping, contacts, excitation harmonics.

Excitation (one harmonic at ω): f_e(θ) = Re(F̂ e^{iθ}), F̂ = Σ_l F_l e^{iφ_l} b_l (+ A e^{iφ} b_base),
so in sarfe's Fourier convention F[1] = Re F̂ (cos), F[2] = −Im F̂ (sin), all other rows 0.
Contacts: one ContactSet entry per contact point (FE) or per named contact (matrices), with rows
w = n·(u_a − u_b), q_i = t_i·(u_a − u_b) of G — FE: the stage's rows of the facing shell faces
(:class:`sarfe.pipeline.model.contact_pairs.ContactGeometry`); stiffness and preload of a named
contact are split equally over its points.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from sarfe.case.config import DampingConfig, ExcitationConfig
from sarfe.case.read import Case, load_case
from sarfe.fe.damping import modal_damping
from sarfe.hbm import laws
from sarfe.hbm.contacts import make_contact_set
from sarfe.hbm.model import make_linear_model
from sarfe.pipeline.model.stage import LinearStage


@dataclass(frozen=True)
class NonlinearModel:
    """What the HBM needs for one case: model, contacts, excitation harmonics and bookkeeping."""

    model: object                 # sarfe.hbm.model.LinearModel
    contacts: object              # sarfe.hbm.contacts.ContactSet
    excitation: np.ndarray        # (2H+1, n) [N]
    excitation_amplitude: np.ndarray  # F̂ (n,) complex [N]
    groups: list                  # per named contact: (name, type, contact indices in the set)
    tolerance: np.ndarray         # (n_c,) [m]


def damping_matrix(damping: DampingConfig, stage: LinearStage):
    """D on the kept DOFs: the matrices' own D, modal ζ (reduced eigenmodes) or α M + β K,
    plus a deck's discrete dampers (CBUSH B, reduced: ``stage.info['spring_damping']``)."""
    added = getattr(stage, "added_damping", None)
    matrix = _case_damping(damping, stage)
    return matrix if added is None else matrix + added


def _case_damping(damping: DampingConfig, stage: LinearStage):
    M, K = stage.mass, stage.stiffness
    if stage.damping is not None:
        return stage.damping
    if damping.rayleigh is not None:
        return damping.rayleigh.alpha_1_s * M + damping.rayleigh.beta_s * K
    n = M.shape[0]
    zeta = 0.0 if damping.modal_zeta is None else damping.modal_zeta
    if isinstance(zeta, tuple):         # per mode range: (ModalZetaRange, …)
        values = np.full(n, zeta[-1].zeta)
        for entry in zeta:
            first, last = entry.modes
            values[first - 1:min(last, n)] = entry.zeta
        zeta = values
    dense = (lambda A: A.toarray() if sp.issparse(A) else np.asarray(A))
    return modal_damping(dense(M), dense(K), zeta)


def _dof_row(ref, n):
    """(n,) row r of a :class:`~sarfe.case.config.DofReference`: r·u = sign (u[dof] − u[relative_to])."""
    row = np.zeros(n)
    row[ref.dof] += ref.sign
    if ref.relative_to != "ground":
        row[ref.relative_to] -= ref.sign
    return row


def build_contacts(case: Case, stage: LinearStage):
    """ContactSet in the kept DOFs (one set entry per node pair, FE) and per-name groups.

    Law parameters are read generically from each law's declaration (:mod:`sarfe.hbm.laws`): the
    value of its case key (or its default), shared equally over the node pairs when ``split``;
    ``preload_N`` sets the overclosure from the law's static deflection (normal DOF) or the
    constant normal load (no normal DOF); parameters declared ``from_model`` that the case leaves
    out (the effective mass of a normal row) are computed from the model."""
    n = stage.dof_count
    kind, normal_row, tangent_rows = [], [], []
    gap, names, tolerance, groups = [], [], [], []
    table = {}

    blocks, n_rows = [], [0]         # sparse row blocks of G and their running count

    def add_row(vector):
        blocks.append(sp.csr_matrix(np.asarray(vector, dtype=float).reshape(1, n)))
        n_rows[0] += 1
        return n_rows[0] - 1

    for entry in case.config.contacts:
        contact = entry.params
        name, law = entry.name, laws.law(entry.kind)
        tangent = laws.uses_tangent(law, contact)
        start = len(kind)
        if stage.kind == "fe":       # rows 3p (w), 3p+1, 3p+2 (q₁, q₂) of each point p
            geometry = stage.contacts[name]
            pairs = len(geometry.nodes_a)
            per_point = 3 if tangent else 1
            take = (3 * np.arange(pairs)[:, None] + np.arange(per_point)).ravel()
            first = n_rows[0]
            blocks.append(sp.csr_matrix(geometry.rows)[take])
            n_rows[0] += len(take)
            made = first + np.arange(len(take)).reshape(pairs, per_point)
            normal_row += made[:, 0].tolist()
            tangent_rows += (made[:, 1:3].tolist() if tangent else [[-1, -1]] * pairs)
            share = 1.0 / pairs
            has_normal = True
        else:
            pairs = 1
            has_normal = entry.normal_dof is not None
            normal_row.append(add_row(_dof_row(entry.normal_dof, n)) if has_normal else -1)
            t = [add_row(_dof_row(ref, n)) for ref in entry.tangential_dofs]
            tangent_rows.append((t + [-1, -1])[:2])
            share = 1.0
        values = {}
        for p in law.parameters:
            value = contact.get(p.key) if p.key else None
            if value is None:
                value = np.nan if p.from_model else (0.0 if p.default is None else p.default)
            if p.normal_part and not has_normal:
                value = 0.0
            values[p.name] = float(value) * (share if p.split else 1.0)
        if law.prepare is not None:
            try:
                values.update(law.prepare(contact, case.resolve))
            except ValueError as error:
                raise case.error(str(error), ("contacts", entry.index, "type")) from None
        per_pair = {}                   # deck springs (from_elements): one value per node pair
        geometry = stage.contacts.get(name) if stage.kind == "fe" else None
        if getattr(geometry, "normal_stiffness", None) is not None:
            if "normal_stiffness_N_m" not in contact:
                per_pair["normal_stiffness"] = np.asarray(geometry.normal_stiffness, dtype=float)
            if "tangential_stiffness_N_m" not in contact and "tangential_stiffness" in values:
                per_pair["tangential_stiffness"] = np.asarray(geometry.tangential_stiffness,
                                                              dtype=float)
        if not has_normal:
            g = np.zeros(pairs)
            values["normal_load"] = entry.preload_N * share
        elif entry.gap_m is not None:
            g = np.full(pairs, float(entry.gap_m))
        elif entry.preload_N is not None:    # set by preload_gaps below
            g = np.zeros(pairs)
        else:  # FE default: the geometric surface gap of each point along its normal
            g = np.asarray(stage.contacts[name].distances, dtype=float)
        for key, value in values.items():
            table.setdefault(key, [np.nan] * start)
        for key in table:
            value = values.get(key, np.nan)
            table[key] += list(per_pair[key]) if key in per_pair else [value] * pairs
        kind += [entry.kind] * pairs
        gap += list(g)
        tolerance += [entry.tolerance_m] * pairs
        names += [name] if pairs == 1 else [f"{name}[{p}]" for p in range(pairs)]
        groups.append((name, entry.kind, np.arange(start, len(kind))))
    G = sp.vstack(blocks, format="csr") if blocks else sp.csr_matrix((0, n))
    gap = np.array(gap, dtype=float)
    normal_row = np.array(normal_row, dtype=int)
    parameters = _parameter_table(table, kind)
    _fill_from_model(parameters, stage.mass, G, normal_row)
    for key, p in laws.all_parameters().items():   # parameters of the other laws: their defaults
        if key in parameters:
            parameters[key][np.isnan(parameters[key])] = 0.0 if p.default is None else p.default
    contacts = make_contact_set(G, np.array(kind, dtype=object), normal_row,
                                np.array(tangent_rows, dtype=int).reshape(-1, 2), gap,
                                names=names, parameters=parameters)
    preloaded = [(idx, c.preload_N) for c, (_, _, idx) in zip(case.config.contacts, groups)
                 if c.preload_N is not None and c.gap_m is None
                 and np.all(normal_row[idx] >= 0)]
    if preloaded:
        contacts = dataclasses.replace(contacts, gap=preload_gaps(
            stage.stiffness, G, normal_row, gap, contacts, preloaded))
    return contacts, groups, np.array(tolerance, dtype=float)


def _parameter_table(table, kind):
    """{name: (n_c, ...) array}: scalars as floats; tables (curves) padded to a common length."""
    out = {}
    for key, column in table.items():
        column = column + [np.nan] * (len(kind) - len(column))
        shapes = {np.shape(v) for v in column if np.ndim(v)}
        if not shapes:
            out[key] = np.array(column, dtype=float)
            continue
        width = max(s[0] for s in shapes)
        rest = next(iter(shapes))[1:]
        arr = np.full((len(column), width) + rest, np.nan)
        for i, v in enumerate(column):
            if np.ndim(v):
                arr[i, :len(v)] = v
        out[key] = arr
    return out


def _fill_from_model(parameters, mass, gap_map, normal_row):
    """Parameters declared ``from_model`` and left out (NaN): the effective mass of each normal
    row, 1/m_eff = g M⁻¹ gᵀ [kg] (g: the row of G)."""
    declared = laws.all_parameters()
    for key, values in parameters.items():
        p = declared.get(key)
        if p is None or not p.from_model:
            continue
        missing = np.isnan(values) & (normal_row >= 0)
        if not np.any(missing):
            values[np.isnan(values)] = 0.0
            continue
        rows = gap_map[normal_row[missing]]
        if sp.issparse(mass):
            solved = spla.spsolve(sp.csc_matrix(mass), rows.T.tocsc())
            solved = solved.toarray() if sp.issparse(solved) else np.asarray(solved)
        else:
            solved = np.linalg.solve(np.asarray(mass, dtype=float), rows.T.toarray())
        inverse = np.asarray(rows.multiply(solved.reshape(rows.shape[1], -1).T).sum(axis=1)).ravel()
        values[missing] = 1.0 / inverse
        values[np.isnan(values)] = 0.0


def preload_gaps(stiffness, gap_map, normal_row, gap, contacts, preloaded):
    r"""Overclosures g that make the static solution carry the requested preloads.

    Static equilibrium with the preloaded contacts closed: K u + G_nᵀ λ = 0 → w = G_n u = −C λ with
    the static compliance C = G_n K⁻¹ G_nᵀ between the paired DOFs, and w − g = δ(λ) the law's
    static deflection under λ (λ/k_n for the penalty law), so

        g = −(δ(λ) + C λ),    λ_i = P / n_p  for the n_p node pairs of a contact with preload P.

    Only the preloaded contacts are assumed closed (the others open) and all are solved together.
    A singular K (a free-floating matrices model) falls back to g = −δ(λ).
    """
    index = np.concatenate([idx for idx, _ in preloaded])
    force = np.concatenate([np.full(len(idx), load / len(idx)) for idx, load in preloaded])
    deflection = np.zeros(len(index))
    kinds = np.asarray(contacts.kind)[index]
    for name in dict.fromkeys(kinds):
        law = laws.law(name)
        sel = np.flatnonzero(kinds == name)
        deflection[sel] = law.static_deflection(contacts.law_parameters(law, index[sel]),
                                                force[sel])
    rows = gap_map[normal_row[index]].toarray()
    K = stiffness.toarray() if sp.issparse(stiffness) else np.asarray(stiffness, dtype=float)
    gap = gap.copy()
    try:
        compliance = rows @ np.linalg.solve(K, rows.T)
        if not np.all(np.isfinite(compliance)):
            raise np.linalg.LinAlgError("singular")
    except np.linalg.LinAlgError:
        compliance = np.zeros((len(index), len(index)))
    gap[index] = -(deflection + compliance @ force)
    return gap


def excitation_amplitude(excitation: ExcitationConfig, stage: LinearStage) -> np.ndarray:
    """F̂ (n,) complex [N]: f_e(θ) = Re(F̂ e^{iθ})."""
    amplitude = np.zeros(stage.dof_count, dtype=complex)
    for load, vector in zip(excitation.forces, stage.load_vectors):
        amplitude += load.force_N * np.exp(1j * math.radians(load.phase_deg)) * vector
    if excitation.base_acceleration is not None:
        base = excitation.base_acceleration
        amplitude += (base.amplitude_m_s2 * np.exp(1j * math.radians(base.phase_deg))
                      * stage.base_vector)
    return amplitude


def nonlinear_model(case, stage: LinearStage) -> NonlinearModel:
    """LinearModel (with damping), ContactSet and excitation harmonics of a case."""
    case = load_case(case)
    model = make_linear_model(stage.mass, damping_matrix(case.config.damping, stage),
                               stage.stiffness)
    contacts, groups, tolerance = build_contacts(case, stage)
    H = case.config.solver.harmonics
    amplitude = excitation_amplitude(case.config.excitation, stage)
    F = np.zeros((2 * H + 1, stage.dof_count))
    F[1], F[2] = amplitude.real, -amplitude.imag
    return NonlinearModel(model, contacts, F, amplitude, groups, tolerance)
