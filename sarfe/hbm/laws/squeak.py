r"""Squeak: normal penalty with a constant normal load and a Jenkins friction element tangentially.

    λ_n = k_n · max(0, w − g) + N0,      λ_t = k_t (q − w_s),  |λ_t| ≤ μ λ_n   (:mod:`.jenkins`)

N0 = ``normal_load`` [N] is a constant normal force, the whole normal load of a friction contact
with no normal DOF (case key ``preload_N``). 1 or 2 tangential directions (slider in the tangent
plane). States: 0 separated, 1 stick, 2 slip.

Optionally (case key ``partner_radius_m``) the partners are curved (:mod:`.curvature`): the
penetration is then w − g − ½ Σ κ_i q_i², so the normal force varies with the slide, and the
normal force's tangential components −κ_i q_i λ_n act on the tangent rows.
"""
from __future__ import annotations

from sarfe.hbm.laws import curvature, jenkins
from sarfe.hbm.laws.contract import ContactLaw, NormalForce, Parameter
from sarfe.hbm.laws.rattle import NORMAL_STIFFNESS, penalty_force, penalty_linearization

NORMAL_LOAD = Parameter("normal_load", None, "N",
                        "constant normal force N0 (case: preload_N of a contact without a normal "
                        "DOF)", minimum=0.0, default=0.0, split=True)


def normal(p, gap, w, wdot):
    force, stiffness, closed = penalty_force(w, gap, p["normal_stiffness"])
    return NormalForce(force + p["normal_load"], stiffness, None, closed)


def linearize(p, gap):
    return penalty_linearization(p, gap, p["normal_load"])


def static_deflection(p, force):
    return force / p["normal_stiffness"]


def prune_open(p):
    """A pair under a constant normal load keeps its slider history: never dropped; nor one on a
    concave partner (κ < 0: the slide closes the gap, which the screen's w alone does not see)."""
    concave = (p["partner_curvature_1"] < 0) | (p["partner_curvature_2"] < 0)
    return ~(p["normal_load"] > 0) & ~concave


LAW = ContactLaw(
    name="squeak",
    summary="normal penalty + constant load N0, Jenkins friction element (k_t, μ) tangentially",
    parameters=(NORMAL_STIFFNESS, NORMAL_LOAD)
    + jenkins.PARAMETERS + curvature.PARAMETERS,
    normal=normal, linearize=linearize, static_deflection=static_deflection,
    tangent=jenkins, normal_dof="optional", tangent_dofs="required", prune_open=prune_open,
    states=jenkins.STATES, table_column="slip_fraction",
    case_keys=curvature.CASE_KEYS, prepare=curvature.prepare,
)
