"""Multipoint constraints of a deck (RBE2, RBE3) as an exact elimination u = C q.

Global DOFs g = 6·node + c (c = 0..5 = [ux, uy, uz, rx, ry, rz], global axes). Each
dependent DOF is a linear combination of other DOFs:

RBE2 (rigid): for a dependent node d of independent node i, r = x_d − x_i,
    u_d = u_i + θ_i × r = u_i − [r]× θ_i,   θ_d = θ_i        (components in CM).
RBE3 (interpolation): the reference node's motion q_r (6) is the weighted least-squares
rigid fit of its independent nodes' motions,
    q_r = H⁺ Σ_i S_iᵀ W_i u_i,  H = Σ_i S_iᵀ W_i S_i,  S_i = [[I, −[r_i]×], [0, I]],
    r_i = x_i − x_r,  W_i = w_i diag(c_i,t, L_c² c_i,r),
with c_i the node's component mask and L_c the mean distance of the independent nodes from
the reference (scales rotational weights, as Nastran). Only the REFC components of q_r are
dependent; each must be determined by the independent motions (else a ValueError names it).

Chains (an independent DOF that is itself dependent) are resolved by substitution; a DOF
made dependent twice is an error. The RBE3 loop runs over RBE3 elements (a deck has few).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from sarfe.fe.line_elements import rigid_arm

__all__ = ["constraint_matrix"]


def _rbe2_rows(points, rbe2):
    """(dependent DOF, column DOF, coefficient) triplets of all RBE2s, vectorized."""
    dep = np.asarray(rbe2.dependent)
    if dep.size == 0:
        return [np.zeros(0, np.int64)] * 2 + [np.zeros(0)], np.zeros(0, np.int64)
    ind = np.asarray(rbe2.independent)[rbe2.dependent_element]
    mask = np.asarray(rbe2.components)[rbe2.dependent_element]  # (q, 6)
    g = rigid_arm(points[dep] - points[ind])  # (q, 6, 6): q_d = G q_i
    rows = 6 * dep[:, None, None] + np.arange(6)[None, :, None]
    cols = 6 * ind[:, None, None] + np.arange(6)[None, None, :]
    keep = mask[:, :, None] & (g != 0)
    rows_b, cols_b = np.broadcast_arrays(rows, cols)
    dependent = (6 * dep[:, None] + np.arange(6))[mask]
    return [rows_b[keep], cols_b[keep], g[keep]], dependent


def _rbe3_rows(points, rbe3, name_of):
    rows, cols, vals, dependent = [], [], [], []
    for e, ref in enumerate(np.asarray(rbe3.reference)):
        pick = np.asarray(rbe3.independent_element) == e
        nodes = np.asarray(rbe3.independent)[pick]
        weights = np.asarray(rbe3.weights)[pick]
        masks = np.asarray(rbe3.independent_components)[pick].astype(float)
        r = points[nodes] - points[ref]
        lc2 = np.mean(np.linalg.norm(r, axis=1)) ** 2 or 1.0
        w = weights[:, None] * masks * np.array([1, 1, 1, lc2, lc2, lc2])  # (k, 6)
        s = rigid_arm(r)  # (k, 6, 6): rigid motion at node i of the reference motion
        h = np.einsum("kai,ka,kaj->ij", s, w, s)
        h_pinv = np.linalg.pinv(h, rcond=1e-10)
        determined = np.diag(h_pinv @ h)
        refc = np.asarray(rbe3.reference_components[e], bool)
        if np.any(np.abs(determined[refc] - 1.0) > 1e-8):
            c = int(np.flatnonzero(refc & (np.abs(determined - 1.0) > 1e-8))[0]) + 1
            raise ValueError(f"RBE3 {name_of(e)}: reference component {c} is not determined "
                             "by its independent nodes and components")
        coeff = np.einsum("ij,kaj,ka->kia", h_pinv, s, w)  # (k, 6 ref comps, 6 node comps)
        for c in np.flatnonzero(refc):
            block = coeff[:, c, :]
            nz = block != 0
            rows.append(np.full(int(nz.sum()), 6 * ref + c))
            cols.append((6 * nodes[:, None] + np.arange(6))[nz])
            vals.append(block[nz])
            dependent.append(6 * ref + c)
    if not rows:
        return [np.zeros(0, np.int64)] * 2 + [np.zeros(0)], np.zeros(0, np.int64)
    return ([np.concatenate(rows), np.concatenate(cols), np.concatenate(vals)],
            np.array(dependent, np.int64))


def constraint_matrix(points, rbe2, rbe3, n_nodes):
    """(C, independent): u_global (6n) = C q, C sparse (6n, n_indep), ``independent`` (n_indep,)
    the global DOFs that remain unknowns (C is the identity on them).

    points (n, 3) [m]; rbe2: `RigidElements`; rbe3: `InterpolationElements`.
    Raises ValueError for a DOF dependent twice or circular rigid chains.
    """
    points = np.asarray(points, float)
    n_dof = 6 * n_nodes
    (r2, c2, v2), dep2 = _rbe2_rows(points, rbe2)
    (r3, c3, v3), dep3 = _rbe3_rows(points, rbe3, lambda e: int(rbe3.element_ids[e]))
    dependent = np.concatenate([dep2, dep3])
    unique, counts = np.unique(dependent, return_counts=True)
    if np.any(counts > 1):
        dof = int(unique[counts > 1][0])
        raise ValueError(f"node row {dof // 6} component {dof % 6 + 1} is dependent in two "
                         "rigid/interpolation elements")
    is_dep = np.zeros(n_dof, bool)
    is_dep[dependent] = True
    free = np.flatnonzero(~is_dep)
    rows = np.concatenate([r2, r3, free])
    cols = np.concatenate([c2, c3, free])
    vals = np.concatenate([v2, v3, np.ones(len(free))])
    p = sp.csr_matrix((vals, (rows, cols)), shape=(n_dof, n_dof))
    for _ in range(50):  # substitute chains until no dependent DOF is referenced
        referenced = np.zeros(n_dof, bool)
        referenced[p.indices] = True
        if not np.any(referenced & is_dep):
            break
        p = (p @ p).tocsr()
        p.eliminate_zeros()
    else:
        raise ValueError("circular chain of rigid/interpolation elements")
    return p[:, free].tocsr(), free
