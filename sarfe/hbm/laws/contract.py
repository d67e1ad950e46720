r"""What a contact law declares: the one interface every solver stage goes through.

A law acts on one contact c with (optionally) a relative normal displacement w = G_n u (closing
the gap g when w > g) and up to two tangential displacements q = G_t u, all rows of the contact map
G (:mod:`sarfe.hbm.contacts`). Its force λ acts on the structure as f_nl = Gᵀ λ.

A law is a :class:`ContactLaw` (a frozen record of plain module-level functions) made in the law's
own module and registered with one line in :mod:`sarfe.hbm.laws`. It declares

- ``parameters``: names, SI units, bounds, defaults, the case-file key (the single source of the
  contact part of the case schema, of the case normalization and of ``build_contacts``);
- ``normal(p, gap, w, wdot)``: the pointwise normal force λ_n [N] over (samples × contacts) and its
  derivatives ∂λ_n/∂w [N/m], ∂λ_n/∂ẇ [N s/m], and the closed flag, as :class:`NormalForce`;
- ``tangent``: None, or a hysteretic tangent element (:mod:`sarfe.hbm.laws.jenkins`) driven by λ_n,
  which provides its periodic march over the period (AFT) and its one-step return map (time
  integration);
- ``linearize(p, gap)``: the normal part at u = 0 for the cold start and the pruning screen
  (spring, dashpot, preload, closed), as :class:`Linearization`;
- ``static_deflection(p, force)``: w − g under a static normal force (a case's ``preload_N``);
- what the pruning screen may do with it (``prune_open``, ``linear_when_closed``), its state
  labels and the indicator of the console table.

Derivatives: the AFT Jacobian is ∂λ̃/∂r̃ = E diag(∂λ/∂r) Φ + ω E diag(∂λ/∂ṙ) Φ ∇, the ω-derivative
∂λ̃/∂ω = E diag(∂λ/∂ṙ) Φ ∇ r̃ and Hill's damping term E diag(∂λ/∂ṙ) Φ; the time integrator's
Newmark step uses ∂λ/∂r₊ + (2/h) ∂λ/∂ṙ₊. A law whose ``velocity_dependent`` is False returns
∂λ/∂ẇ = 0 and every velocity term is skipped.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, NamedTuple

import numpy as np


@dataclass(frozen=True)
class Parameter:
    """One law parameter. ``name``: the key in ContactSet.parameters; ``key``: the case-file key
    (with its unit); ``unit``: SI unit; ``minimum`` with ``exclusive`` (> rather than ≥), or None;
    ``default`` (None: no default); ``required`` in a case file; ``split``: a named contact's value
    is shared equally over its node pairs (stiffnesses, forces); ``scaled``: multiplied by s in the
    cold start's contact-stiffness homotopy; ``normal_part``: only with a normal DOF (required
    then, not allowed without); ``tangent_part``: only checked where the contact has tangent rows
    (a law whose tangent element is optional); ``key`` None: not a case key (set by the pipeline); ``from_model``:
    when left out, the pipeline computes it from the model (the effective mass of the contact's
    normal row, 1/m_eff = g M⁻¹ gᵀ)."""

    name: str
    key: str
    unit: str
    description: str
    minimum: float | None = None
    exclusive: bool = False
    maximum: float | None = None
    default: float | None = None
    required: bool = False
    split: bool = False
    scaled: bool = False
    normal_part: bool = False
    tangent_part: bool = False
    from_model: bool = False


class LawInputError(ValueError):
    """A law's case input is invalid: ``key`` names the case key, the message says why."""

    def __init__(self, key, message):
        super().__init__(message)
        self.key = key


class NormalForce(NamedTuple):
    """Pointwise normal force over (samples × contacts): λ_n [N], ∂λ_n/∂w [N/m], ∂λ_n/∂ẇ [N s/m]
    (None when the law is rate independent), closed (bool, force-carrying contact)."""

    force: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray | None
    closed: np.ndarray


class Linearization(NamedTuple):
    """The normal part at u = 0, u̇ = 0, per contact (n,): spring [N/m] (the law's characteristic
    stiffness, also where open: the homotopy's scale), dashpot [N s/m], preload λ_n(0) [N] and
    closed (the spring acts at u = 0: g ≤ 0). λ_n ≈ preload + spring·w + dashpot·ẇ where closed."""

    spring: np.ndarray
    dashpot: np.ndarray
    preload: np.ndarray
    closed: np.ndarray


@dataclass(frozen=True)
class ContactLaw:
    """A registered contact law (see module docstring). ``normal_dof``: 'required' | 'optional'
    (without a normal row the normal force is the constant ``normal_load`` parameter);
    ``tangent_dofs``: 'forbidden' | 'optional' | 'required' (a law with a ``tangent`` element);
    ``prune_open(p)``: per contact, may a pair that never closes be dropped; ``linear_when_closed``:
    λ_n is exactly the linearization while closed (the pair may become a spring);
    ``states``: labels of the state codes 0, 1, 2; ``table_column``: contact indicator shown in the
    console table; ``case_keys``: further case-file keys {key: JSON schema} that are not scalar
    parameters, turned into parameters by ``prepare(contact, resolve) -> {name: array}`` (resolve:
    a path relative to the case file; raises :class:`LawInputError` naming the key);
    ``check(p)``: further consistency of the parameters of a ContactSet (raises ValueError)."""

    name: str
    summary: str
    parameters: tuple
    normal: Callable
    linearize: Callable
    static_deflection: Callable
    tangent: object = None
    normal_dof: str = "required"
    tangent_dofs: str = "forbidden"
    velocity_dependent: bool = False
    prune_open: Callable = None
    linear_when_closed: bool = False
    states: tuple = ("open", "closed")
    table_column: str = "max_penetration_m"
    case_keys: dict = field(default_factory=dict)
    prepare: Callable = None
    check: Callable = None

    def case_parameters(self):
        """The parameters read from a case file (those with a key), the tangent element's included."""
        own = tuple(p for p in self.parameters if p.key)
        return own

    def keys(self):
        """Every case-file key of the law (parameters and ``case_keys``)."""
        return {p.key for p in self.case_parameters()} | set(self.case_keys)
