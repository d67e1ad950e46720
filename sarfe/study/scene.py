r"""Model only what the scene requires: contacts that never switch are solved linearly (the engine
is :mod:`sarfe.hbm.pruning`, re-exported here), and the harmonic content of a solution says which
harmonics carry nothing.
"""
from __future__ import annotations

import numpy as np

from sarfe.hbm.pruning import (CLOSED, NONLINEAR, OPEN, ContactDecision, PrunedProblem,  # noqa: F401
                               check_pruning, kept_rows, linear_responses, linearized_damping,
                               linearized_stiffness, prune_contacts, restore_solution,
                               screen_contacts, solve_frequency_pruned, subset_contacts)


# ----------------------------------------------------------------------------- harmonic content
def harmonic_content(solution, threshold=1e-3) -> dict:
    """Energy per harmonic order of the contact displacements, forces and all DOFs, and what could
    be dropped — a report on a solved point; the engine drops orders itself through
    ``solver.harmonic_set`` (odd | auto, :mod:`sarfe.hbm.harmonic_set`).

    Returns {'orders', 'displacement_share', 'contact_displacement_share', 'contact_force_share',
    'even_share', 'odd_share', 'mean_share', 'needed_harmonics', 'suggestion'}; shares are fractions
    of the energy of harmonics k ≥ 1 (the mean separately, relative to all). ``needed_harmonics``:
    smallest K with the energy above K below threshold² (amplitude share < threshold).
    """
    from sarfe.accuracy.estimates import harmonic_energy

    out = {"orders": list(range(int(solution.harmonics) + 1))}
    groups = {"displacement": solution.displacement,
              "contact_displacement": solution.contact_displacement,
              "contact_force": solution.contact_force}
    total_dyn = None
    for key, X in groups.items():
        X = np.asarray(X, dtype=float)
        e = harmonic_energy(X) if X.size else np.zeros(int(solution.harmonics) + 1)
        dyn = e[1:].sum()
        out[f"{key}_share"] = (e / dyn if dyn > 0 else np.zeros_like(e)).tolist()
        if key == "contact_displacement" and X.size:
            total_dyn = e
    e = total_dyn if total_dyn is not None else harmonic_energy(np.asarray(solution.displacement))
    dyn = e[1:].sum()
    orders = np.arange(e.size)
    even = float(e[2::2].sum() / dyn) if dyn > 0 else 0.0
    odd = float(e[1::2].sum() / dyn) if dyn > 0 else 0.0
    out["even_share"], out["odd_share"] = even, odd
    out["mean_share"] = float(e[0] / e.sum()) if e.sum() > 0 else 0.0
    tail = np.cumsum(e[::-1])[::-1]             # energy of orders ≥ k
    needed = int(solution.harmonics)
    if dyn > 0:
        small = np.flatnonzero((tail[1:] / dyn) < threshold ** 2)
        needed = int(orders[1:][small[0]] - 1) if small.size else int(solution.harmonics)
        needed = max(needed, 1)
    out["needed_harmonics"] = needed
    hints = []
    if dyn > 0 and even < threshold ** 2:
        hints.append("even harmonics carry < threshold: an odd-only set would do (symmetric response)")
    if dyn > 0 and odd < threshold ** 2:
        hints.append("odd harmonics carry < threshold")
    if needed < int(solution.harmonics):
        hints.append(f"harmonics above {needed} carry < threshold: H = {needed} would do")
    if not hints:
        hints.append("all kept harmonics matter")
    out["suggestion"] = "; ".join(hints)
    return out


__all__ = ["OPEN", "CLOSED", "NONLINEAR", "ContactDecision", "PrunedProblem", "screen_contacts",
           "subset_contacts", "kept_rows", "prune_contacts", "check_pruning", "restore_solution",
           "linearized_stiffness", "linear_responses",
           "solve_frequency_pruned", "harmonic_content"]
