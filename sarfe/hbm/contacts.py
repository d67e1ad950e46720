r"""Node-to-node contacts in DOF terms: the data every contact law and the HBM solver share.

Each contact c has a local frame [normal, tangent 1, tangent 2]. Its local relative displacement
is a linear function of the kept DOFs u,

    r = G u,        G = ``gap_map`` (n_rows, n_dof), sparse,

where only the rows a contact actually uses exist: ``normal_row[c]`` is the row of its relative
normal displacement w (positive = closing the gap) or −1 when the contact has no normal DOF (a
friction contact under a constant normal load), and ``tangent_rows[c]`` holds the rows of its one or
two tangential relative displacements q (−1 where absent). The local contact force λ (normal force
positive in compression) acts on the structure as

    f_nl = Gᵀ λ,    so that   M ü + D u̇ + K u + Gᵀ λ(G u) = f_e(t).

Laws (kind):
- ``rattle``: λ_n = k_n · max(0, w − g)                      (unilateral penalty, gap g, g < 0 = preload)
- ``squeak``: λ_n = k_n · max(0, w − g) + N0,  and a Jenkins element tangentially: spring k_t in series
  with a Coulomb slider of limit μ λ_n (1 or 2 tangential directions; slider in the tangent plane).
  N0 = ``normal_load`` is a constant normal force [N], used for friction contacts with no normal DOF.
Grounded contacts (against a rigid fixed partner) are simply rows of G that involve one node only.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

KINDS = ("rattle", "squeak")


@dataclass(frozen=True)
class ContactSet:
    """Contacts acting on the kept DOFs (see module docstring for the equations).

    Attributes (n_c contacts, n_rows rows of G, n_dof kept DOFs); SI units.
    """

    gap_map: sp.csr_matrix                 # G (n_rows, n_dof) [-]
    kind: np.ndarray                       # (n_c,) str, 'rattle' | 'squeak'
    normal_row: np.ndarray                 # (n_c,) int, row of w in G, −1 if none
    tangent_rows: np.ndarray               # (n_c, 2) int, rows of q1, q2 in G, −1 if absent
    gap: np.ndarray                        # (n_c,) [m], g > 0 open, g < 0 overclosure (preload)
    normal_stiffness: np.ndarray           # (n_c,) [N/m] k_n
    tangential_stiffness: np.ndarray       # (n_c,) [N/m] k_t (squeak only, 0 for rattle)
    friction_coefficient: np.ndarray       # (n_c,) [-] μ (squeak only)
    normal_load: np.ndarray                # (n_c,) [N] constant normal force N0 (squeak only)
    names: tuple = field(default=())       # (n_c,) contact names for reports

    @property
    def count(self) -> int:
        return len(self.kind)

    @property
    def row_count(self) -> int:
        return self.gap_map.shape[0]


def make_contact_set(
    gap_map,
    kind,
    normal_row,
    tangent_rows,
    gap,
    normal_stiffness,
    tangential_stiffness=None,
    friction_coefficient=None,
    normal_load=None,
    names=None,
) -> ContactSet:
    """Build and validate a :class:`ContactSet`; raises ValueError naming the bad parameter."""
    G = sp.csr_matrix(gap_map, dtype=float)
    kind = np.asarray(kind, dtype=object)
    n_c = kind.shape[0]

    def per_contact(value, name, default=0.0):
        arr = np.full(n_c, default, dtype=float) if value is None else np.broadcast_to(
            np.asarray(value, dtype=float), (n_c,)).copy()
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"{name} must be finite")
        return arr

    bad = [k for k in kind if k not in KINDS]
    if bad:
        raise ValueError(f"contact kind must be one of {KINDS}, got {bad[0]!r}")
    normal_row = np.asarray(normal_row, dtype=int).reshape(n_c)
    tangent_rows = np.asarray(tangent_rows, dtype=int).reshape(n_c, 2)
    for name, rows in (("normal_row", normal_row), ("tangent_rows", tangent_rows)):
        if np.any(rows >= G.shape[0]) or np.any(rows < -1):
            raise ValueError(f"{name} refers to a row outside gap_map ({G.shape[0]} rows)")
    gap = per_contact(gap, "gap")
    k_n = per_contact(normal_stiffness, "normal_stiffness")
    k_t = per_contact(tangential_stiffness, "tangential_stiffness")
    mu = per_contact(friction_coefficient, "friction_coefficient")
    n0 = per_contact(normal_load, "normal_load")
    for name, arr in (("normal_stiffness", k_n), ("tangential_stiffness", k_t),
                      ("friction_coefficient", mu), ("normal_load", n0)):
        if np.any(arr < 0):
            raise ValueError(f"{name} must be >= 0, got {arr.min():g}")
    rattle = kind == "rattle"
    if np.any(rattle & (normal_row < 0)):
        raise ValueError("a rattle contact needs a normal row (normal_row >= 0)")
    if np.any(rattle & (k_n <= 0)):
        raise ValueError("normal_stiffness of a rattle contact must be > 0")
    squeak = kind == "squeak"
    if np.any(squeak & (tangent_rows[:, 0] < 0)):
        raise ValueError("a squeak contact needs at least one tangent row")
    if np.any(squeak & (k_t <= 0)):
        raise ValueError("tangential_stiffness of a squeak contact must be > 0")
    names = tuple(names) if names is not None else tuple(f"contact_{i}" for i in range(n_c))
    return ContactSet(G, kind, normal_row, tangent_rows, gap, k_n, k_t, mu, n0, names)
