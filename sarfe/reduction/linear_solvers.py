"""Alias: the sparse direct solvers live in :mod:`sarfe.fe.linear_solvers` (below fe, whose modal
analysis factorizes K − σM with them); kept so ``sarfe.reduction.linear_solvers`` still imports."""
from sarfe.fe.linear_solvers import (Factorization, available_solvers, choose_solver,  # noqa: F401
                                     factorize)

__all__ = ["Factorization", "available_solvers", "choose_solver", "factorize"]
