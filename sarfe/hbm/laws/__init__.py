r"""Contact laws: one module per law, each a :class:`~.contract.ContactLaw` registered here with one
line (the contract is in :mod:`sarfe.hbm.laws.contract`; docs/hbm.md explains how to add a law).

Everything outside a law's module reaches it through :func:`law` and the helpers below; nothing
else tests a law's name. Shared parts: :mod:`.jenkins` (+ :mod:`.jenkins_march`, its compiled
kernels) the friction element, :mod:`.curvature` a curved contact partner (the penetration and
normal force follow the slide; the squeak law's ``partner_radius_m``).
"""
from __future__ import annotations

from importlib import import_module

import numpy as np

from sarfe.hbm.laws import curvature
from sarfe.hbm.laws.contract import ContactLaw, LawInputError, Linearization, NormalForce, Parameter

LAWS = {}


def register(contact_law: ContactLaw) -> ContactLaw:
    """Add a law to the registry (a law whose normal part is rate dependent cannot drive a
    tangent element: the element's Jacobian assumes ∂λ_n/∂ẇ = 0)."""
    if contact_law.tangent is not None and contact_law.velocity_dependent:
        raise ValueError(f"law {contact_law.name!r}: a tangent element needs a rate-independent "
                         "normal force")
    LAWS[contact_law.name] = contact_law
    return contact_law


REGISTERED = (          # one line per law: its module in sarfe/hbm/laws, which defines LAW
    "rattle",
    "squeak",
    "damped_impact",
    "tabulated",
)
for _module in REGISTERED:
    register(import_module(f".{_module}", __name__).LAW)


def law(name) -> ContactLaw:
    """The registered law ``name`` (ValueError listing the known ones)."""
    try:
        return LAWS[str(name)]
    except KeyError:
        raise ValueError(f"contact law must be one of {tuple(LAWS)}, got {name!r}") from None


def names() -> tuple:
    return tuple(LAWS)


def all_parameters() -> dict:
    """{parameter name: Parameter} over all registered laws (one declaration per name)."""
    out = {}
    for contact_law in LAWS.values():
        for p in contact_law.parameters:
            out.setdefault(p.name, p)
    return out


def groups(contacts):
    """[(law, contact indices (n_g,), parameters {name: (n_g, ...)})] of a ContactSet, one entry
    per law present (in registry order)."""
    kinds = np.asarray(contacts.kind)
    out = []
    for name, contact_law in LAWS.items():
        idx = np.flatnonzero(kinds == name)
        if idx.size:
            out.append((contact_law, idx, contacts.law_parameters(contact_law, idx)))
    return out


def linearization(contacts):
    """Per contact (n_c,): the normal part at u = 0 (:class:`Linearization`), tangent spring k_t
    of the stuck tangent element [N/m] (0 without one)."""
    n = contacts.count
    spring, dashpot, preload = np.zeros(n), np.zeros(n), np.zeros(n)
    closed, tangent = np.zeros(n, bool), np.zeros(n)
    for contact_law, idx, p in groups(contacts):
        lin = contact_law.linearize(p, contacts.gap[idx])
        spring[idx], dashpot[idx], preload[idx] = lin.spring, lin.dashpot, lin.preload
        closed[idx] = lin.closed
        if contact_law.tangent is not None:
            tangent[idx] = p["tangential_stiffness"]
    return Linearization(spring, dashpot, preload, closed), tangent


def curvatures(contacts):
    """κ (n_c, 2) [1/m] of every contact (:mod:`.curvature`), or None when all are flat."""
    kappa = curvature.contact_curvatures(contacts)
    return kappa if np.any(kappa != 0.0) else None


def tangent_springs(contacts, normal=None, tangent=None, normal_force=None):
    """Per contact and tangent direction (n_c, 2) [N/m]: the stuck spring of its tangent rows,
    k_t less κ_i λ_n on a curved partner (:mod:`.curvature`: the normal force's tangential
    component −κ q λ_n, the geometric stiffness of a loaded contact); λ_n = ``normal_force``
    (n_c,) [N] (the static one), default λ_n(0) of the contacts closed at u = 0.
    ``normal``, ``tangent``: :func:`linearization` of ``contacts`` when already computed."""
    if normal is None:
        normal, tangent = linearization(contacts)
    springs = np.repeat(np.asarray(tangent, dtype=float)[:, None], 2, axis=1)
    kappa = curvatures(contacts)
    if kappa is not None:
        closed = normal.closed & (contacts.normal_row >= 0)
        loaded = np.where(closed, normal.preload if normal_force is None else normal_force, 0.0)
        springs = springs - kappa * np.maximum(loaded, 0.0)[:, None]
    return springs


def velocity_dependent(contacts) -> bool:
    return any(law(k).velocity_dependent for k in dict.fromkeys(np.asarray(contacts.kind)))





def pruning_rules(contacts):
    """Per contact (n_c,) bool: (may be dropped when it never closes, may become its linearization
    when it never opens) — the laws' ``prune_open`` and ``linear_when_closed``."""
    may_open = np.ones(contacts.count, bool)
    may_close = np.zeros(contacts.count, bool)
    for contact_law, idx, p in groups(contacts):
        if contact_law.prune_open is not None:
            may_open[idx] = contact_law.prune_open(p)
        may_close[idx] = contact_law.linear_when_closed
    return may_open, may_close


def table_column(name) -> str:
    """The contact indicator of law ``name`` shown in the console table."""
    return law(name).table_column


def uses_tangent(contact_law, given_keys) -> bool:
    """Does a contact of this law (with the case keys ``given_keys``) have tangent rows: always
    when its tangent DOFs are required, when any tangent-element key is given if optional."""
    if contact_law.tangent is None or contact_law.tangent_dofs == "forbidden":
        return False
    if contact_law.tangent_dofs == "required":
        return True
    return any(p.key in given_keys for p in contact_law.tangent.PARAMETERS)


__all__ = ["ContactLaw", "LawInputError", "Parameter", "NormalForce", "Linearization", "LAWS",
           "REGISTERED", "register", "law", "names", "all_parameters", "groups", "linearization",
           "curvatures", "tangent_springs", "velocity_dependent", "pruning_rules", "table_column",
           "uses_tangent"]
