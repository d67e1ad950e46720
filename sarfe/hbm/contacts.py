r"""Node-to-node contacts in DOF terms: the data every contact law and the HBM solver share.

Each contact c has a local frame [normal, tangent 1, tangent 2]. Its local relative displacement
is a linear function of the kept DOFs u,

    r = G u,        G = ``gap_map`` (n_rows, n_dof), sparse,

where only the rows a contact actually uses exist: ``normal_row[c]`` is the row of its relative
normal displacement w (positive = closing the gap) or −1 when the contact has no normal DOF (a
friction contact under a constant normal load), and ``tangent_rows[c]`` holds the rows of its one or
two tangential relative displacements q (−1 where absent). The local contact force λ (normal force
positive in compression) acts on the structure as

    f_nl = Gᵀ λ,    so that   M ü + D u̇ + K u + Gᵀ λ(G u, G u̇) = f_e(t).

The law of each contact (``kind``, a name registered in :mod:`sarfe.hbm.laws`) states λ; its
parameters live in one table, ``parameters`` {name: (n_c, ...) array}, filled with each parameter's
default (or 0) for contacts whose law does not use it. Grounded contacts (against a rigid fixed
partner) are simply rows of G that involve one node only.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from sarfe.hbm import laws


@dataclass(frozen=True)
class ContactSet:
    """Contacts acting on the kept DOFs (see module docstring for the equations).

    Attributes (n_c contacts, n_rows rows of G, n_dof kept DOFs); SI units. A parameter is also
    readable as an attribute (``contacts.normal_stiffness``: the column of the table).
    """

    gap_map: sp.csr_matrix                 # G (n_rows, n_dof) [-]
    kind: np.ndarray                       # (n_c,) str, the law of each contact
    normal_row: np.ndarray                 # (n_c,) int, row of w in G, −1 if none
    tangent_rows: np.ndarray               # (n_c, 2) int, rows of q1, q2 in G, −1 if absent
    gap: np.ndarray                        # (n_c,) [m], g > 0 open, g < 0 overclosure (preload)
    parameters: dict = field(default_factory=dict)   # {name: (n_c, ...)} law parameters, SI
    names: tuple = field(default=())       # (n_c,) contact names for reports

    @property
    def count(self) -> int:
        return len(self.kind)

    @property
    def row_count(self) -> int:
        return self.gap_map.shape[0]

    def __getattr__(self, name):
        table = self.__dict__.get("parameters") or {}
        if name in table:
            return table[name]
        if name in laws.all_parameters():
            return np.zeros(len(self.__dict__["kind"]))
        raise AttributeError(name)

    def law_parameters(self, contact_law, index) -> dict:
        """{name: values of the contacts ``index``} of every table entry (the law picks its own)."""
        return {name: values[index] for name, values in self.parameters.items()}

    def subset(self, index, gap_map, normal_row, tangent_rows):
        """The contacts ``index`` on re-numbered rows (see :func:`sarfe.hbm.pruning.subset_contacts`)."""
        idx = np.asarray(index, dtype=int)
        names = tuple(self.names[i] for i in idx) if self.names else None
        return make_contact_set(gap_map, np.asarray(self.kind, dtype=object)[idx], normal_row,
                                tangent_rows, self.gap[idx], names=names,
                                parameters={k: v[idx] for k, v in self.parameters.items()})

    def scaled(self, scale):
        """The set with every ``scaled`` parameter (contact springs, dashpots, force tables) × s."""
        declared = laws.all_parameters()
        table = {k: (scale * v if k in declared and declared[k].scaled else v)
                 for k, v in self.parameters.items()}
        return ContactSet(self.gap_map, self.kind, self.normal_row, self.tangent_rows, self.gap,
                          table, self.names)


def make_contact_set(
    gap_map,
    kind,
    normal_row,
    tangent_rows,
    gap,
    normal_stiffness=None,
    tangential_stiffness=None,
    friction_coefficient=None,
    normal_load=None,
    names=None,
    parameters=None,
) -> ContactSet:
    """Build and validate a :class:`ContactSet`; raises ValueError naming the bad parameter.

    Law parameters come in ``parameters`` {name: scalar or (n_c, ...)}; the keyword arguments
    normal_stiffness … normal_load are shorthands for the entries of the same name.
    """
    G = sp.csr_matrix(gap_map, dtype=float)
    kind = np.asarray(kind, dtype=object)
    n_c = kind.shape[0]
    for name in kind:
        laws.law(name)                     # ValueError naming the known laws
    normal_row = np.asarray(normal_row, dtype=int).reshape(n_c)
    tangent_rows = np.asarray(tangent_rows, dtype=int).reshape(n_c, 2)
    for label, rows in (("normal_row", normal_row), ("tangent_rows", tangent_rows)):
        if np.any(rows >= G.shape[0]) or np.any(rows < -1):
            raise ValueError(f"{label} refers to a row outside gap_map ({G.shape[0]} rows)")
    given = dict(parameters or {})
    for name, value in (("normal_stiffness", normal_stiffness),
                        ("tangential_stiffness", tangential_stiffness),
                        ("friction_coefficient", friction_coefficient),
                        ("normal_load", normal_load)):
        if value is not None:
            given[name] = value
    gap = np.broadcast_to(np.asarray(gap, dtype=float), (n_c,)).copy()
    if not np.all(np.isfinite(gap)):
        raise ValueError("gap must be finite")
    declared = laws.all_parameters()
    table = {}
    for name, value in given.items():
        arr = np.asarray(value, dtype=float)
        arr = np.broadcast_to(arr, (n_c,) + (arr.shape[1:] if arr.ndim > 1 else ())).copy()
        if name in declared and not np.all(np.isfinite(arr)):
            raise ValueError(f"{name} must be finite")
        table[name] = arr
    for name, p in declared.items():
        if name not in table:
            table[name] = np.full(n_c, 0.0 if p.default is None else float(p.default))
    for name in dict.fromkeys(kind):
        _check_law(laws.law(name), kind == name, normal_row, tangent_rows, table)
    names = tuple(names) if names is not None else tuple(f"contact_{i}" for i in range(n_c))
    return ContactSet(G, kind, normal_row, tangent_rows, gap, table, names)


def _check_law(contact_law, mine, normal_row, tangent_rows, table):
    """Rows and parameter bounds of the contacts ``mine`` (bool mask) of one law."""
    name = contact_law.name
    has_normal = normal_row >= 0
    if contact_law.normal_dof == "required" and np.any(mine & ~has_normal):
        raise ValueError(f"a {name} contact needs a normal row (normal_row >= 0)")
    if contact_law.tangent_dofs == "required" and np.any(mine & (tangent_rows[:, 0] < 0)):
        raise ValueError(f"a {name} contact needs at least one tangent row")
    for p in contact_law.parameters:
        applies = mine & has_normal if p.normal_part else mine
        if p.tangent_part:
            applies = applies & (tangent_rows[:, 0] >= 0)
        values = table[p.name][applies]
        if p.minimum is not None:
            bad = values <= p.minimum if p.exclusive else values < p.minimum
            if np.any(bad):
                relation = ">" if p.exclusive else ">="
                raise ValueError(f"{p.name} of a {name} contact must be {relation} "
                                 f"{p.minimum:g}, got {values[bad].min():g}")
        if p.maximum is not None and np.any(values > p.maximum):
            raise ValueError(f"{p.name} of a {name} contact must be <= {p.maximum:g}, "
                             f"got {values.max():g}")
    if contact_law.check is not None and np.any(mine):
        index = np.flatnonzero(mine)
        contact_law.check({k: v[index] for k, v in table.items()})
