r"""Model only what the scene requires: contacts that never switch are solved linearly (the engine
is :mod:`sarfe.hbm.pruning`, re-exported here).
"""
from __future__ import annotations

from sarfe.hbm.pruning import (CLOSED, NONLINEAR, OPEN, ContactDecision, PrunedProblem,  # noqa: F401
                               check_pruning, kept_rows, linear_responses, linearized_damping,
                               linearized_stiffness, prune_contacts, restore_solution,
                               screen_contacts, solve_frequency_pruned, subset_contacts)

__all__ = ["OPEN", "CLOSED", "NONLINEAR", "ContactDecision", "PrunedProblem", "screen_contacts",
           "subset_contacts", "kept_rows", "prune_contacts", "check_pruning", "restore_solution",
           "linearized_stiffness", "linear_responses",
           "solve_frequency_pruned"]
