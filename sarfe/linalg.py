r"""Sparse direct solves A x = b with one factorization reused for many right-hand sides.

``factorize(A, solver="auto", structure="spd")`` returns a :class:`Factorization` whose
``.solve(b)`` takes b of shape (n,) or (n, k) (real or complex) and returns x of the same shape.
Craig–Bampton factorizes K_ii once and calls ``.solve`` for the n_b constraint-mode columns
(one block) and for every shift-invert Lanczos step.

Backends (measured in ``benchmarks/results/linear.md``):

============  =========================================================  ==============================
name          library and licence                                        use
============  =========================================================  ==============================
``pardiso``   pypardiso 0.4 (BSD-3) over Intel MKL PARDISO (Intel         SPD (mtype 2, upper triangle),
              Simplified Software Licence, redistributable, closed       symmetric indefinite (mtype -2),
              source); pip wheel ``mkl`` ~700 MB, x86-64 only            general (mtype 11). Fastest.
``cholespy``  cholespy 2 (BSD-3) with a bundled CHOLMOD (SuiteSparse;    SPD only (lower triangle read),
              CHOLMOD's Cholesky module is LGPL-2.1+) and reference      raises if not positive definite.
              BLAS/LAPACK; small pip wheels for Linux/macOS/Windows
``superlu``   SciPy ``splu`` (BSD-3, SuperLU BSD-3-like); always there    anything, incl. complex;
                                                                         slowest, most memory.
============  =========================================================  ==============================

``solver="auto"`` takes, in this order, the first backend that is importable and fits the
structure: pardiso → cholespy → superlu for ``"spd"``; pardiso → superlu otherwise; superlu for
complex matrices. The order is the measured speed order on the door trim K_ii (CPU seconds, one
thread; 205,686 DOFs at 5 mm / 55,230 at 10 mm):

    factorize   pardiso 3.0 / 0.8,  cholespy 14.5 / 1.2,  superlu 11.0 / 1.6
    one solve   pardiso 0.086 / 0.019, cholespy 0.105 / 0.022, superlu 0.115 / 0.025
    per RHS in a 36-column block  pardiso 0.017 / 0.0054, cholespy 0.046 / 0.0077, superlu 0.063 / 0.011
    factor memory [GB]  pardiso 0.60 / 0.19, cholespy 0.51 / 0.14, superlu 1.71 / 0.34

cholespy stays ahead of SuperLU for Craig–Bampton (≈ 300 Lanczos columns: 14.5 + 300·0.046 ≈ 28 s
vs 11.0 + 300·0.063 ≈ 30 s at 5 mm) and holds a third of its memory.

PARDISO's SPD solves run without MKL's default two iterative-refinement steps (3× the cost, no
gain for a Cholesky factor). cholespy factorizes simplicially (no supernodes, reference BLAS),
hence its slow factorization of large models. SuperLU uses the symmetric MMD(AᵀA+A) ordering
with diagonal pivots (3.6× less fill than its COLAMD default on these matrices).
"""
from __future__ import annotations

import functools
import os
import pathlib
import weakref
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

SOLVERS = ("pardiso", "cholespy", "superlu")
STRUCTURES = ("spd", "symmetric", "general")
_BLOCK_COLUMNS = 128  # right-hand sides per backend call (bounds temporary memory)


@dataclass(frozen=True, eq=False)  # array fields: compare explicitly, not with ==
class Factorization:
    """A factorized (n, n) matrix A. ``solve(b)`` returns A⁻¹ b for b (n,) or (n, k).

    ``name`` is the backend, ``structure`` the assumed structure ("spd", "symmetric", "general"),
    ``factor_entries`` the number of stored factor entries when the backend reports it (else None),
    ``negative_pivots`` the number of negative eigenvalues of a symmetric A (Sylvester's inertia
    of its LDLᵀ factor; pardiso "spd" and "symmetric" only, else None): for A = K − σM with K, M
    symmetric and M positive definite, the number of eigenvalues of K φ = λ M φ below σ.
    """

    name: str
    size: int
    structure: str
    factor_entries: int | None = None
    _solve_real_block: Callable = field(default=None, repr=False, compare=False)
    _keep_alive: object = field(default=None, repr=False, compare=False)
    negative_pivots: int | None = None

    def solve(self, rhs) -> np.ndarray:
        """x = A⁻¹ b. b: (n,) or (n, k), float or complex; x has b's shape (float or complex)."""
        rhs = np.asarray(rhs)
        if rhs.shape[0] != self.size or rhs.ndim not in (1, 2):
            raise ValueError(f"right-hand side must have shape ({self.size},) or ({self.size}, k), got {rhs.shape}")
        if np.iscomplexobj(rhs):
            if self.name == "superlu" and self._keep_alive.complex:
                return self._solve_blocks(rhs.astype(complex))
            columns = rhs.reshape(self.size, -1)
            k = columns.shape[1]
            both = self._solve_blocks(np.concatenate([columns.real, columns.imag], axis=1))
            return (both[:, :k] + 1j * both[:, k:]).reshape(rhs.shape)
        return self._solve_blocks(rhs)

    def _solve_blocks(self, rhs):
        if rhs.ndim == 1:
            return self._solve_real_block(rhs[:, None])[:, 0]
        if rhs.shape[1] <= _BLOCK_COLUMNS:
            return self._solve_real_block(rhs)
        out = np.empty(rhs.shape, dtype=rhs.dtype)
        for start in range(0, rhs.shape[1], _BLOCK_COLUMNS):
            out[:, start:start + _BLOCK_COLUMNS] = self._solve_real_block(rhs[:, start:start + _BLOCK_COLUMNS])
        return out

    def as_operator(self) -> spla.LinearOperator:
        """A⁻¹ as a scipy LinearOperator (e.g. ``OPinv`` of ``eigsh``)."""
        return spla.LinearOperator((self.size, self.size), matvec=self.solve, matmat=self.solve, dtype=float)


@functools.lru_cache(maxsize=None)
def _locate_mkl_runtime() -> None:
    """Point pypardiso at MKL's runtime library once per process.

    Without ``PYPARDISO_MKL_RT`` every ``PyPardisoSolver()`` runs ``ctypes.util.find_library``
    (subprocesses) and then a recursive glob over the whole environment (≈ 0.27 s each, three per
    door-trim run: measured by cProfile). The pip ``mkl`` wheel lists the library among its files,
    so it is found from the package metadata in milliseconds; a path the user set is kept.
    """
    if os.environ.get("PYPARDISO_MKL_RT"):
        return
    from importlib import metadata

    try:
        dist = metadata.distribution("mkl")
    except metadata.PackageNotFoundError:
        return  # MKL from elsewhere (conda, system): pypardiso's own search
    for f in dist.files or ():
        if f.name.startswith("libmkl_rt") or f.name.startswith("mkl_rt"):
            path = pathlib.Path(dist.locate_file(f)).resolve()
            if path.is_file():
                os.environ["PYPARDISO_MKL_RT"] = str(path)
                return


@functools.lru_cache(maxsize=None)
def available_solvers() -> tuple[str, ...]:
    """Backends importable in this environment, in the "auto" preference order."""
    found = []
    for name in SOLVERS:
        try:
            if name == "pardiso":
                import pypardiso  # noqa: F401
                _locate_mkl_runtime()
                pypardiso.PyPardisoSolver()  # loads libmkl_rt; fails on non-x86 / missing MKL
            elif name == "cholespy":
                import cholespy  # noqa: F401
        except Exception:  # noqa: BLE001 - any import/load failure means "not available"
            continue
        found.append(name)
    return tuple(found)


def choose_solver(structure: str = "spd", complex_matrix: bool = False) -> str:
    """The backend "auto" uses for this structure (see module docstring for the order)."""
    if complex_matrix:
        return "superlu"
    for name in available_solvers():
        if name == "cholespy" and structure != "spd":
            continue
        return name
    return "superlu"


def factorize(matrix, solver: str = "auto", structure: str = "spd") -> Factorization:
    """Factorize the square sparse matrix A once for repeated solves.

    matrix: (n, n) scipy sparse (any format) or dense array. For ``structure`` "spd" and
    "symmetric" A must be symmetric (only one triangle is read by pardiso/cholespy).
    solver: "auto" | "pardiso" | "cholespy" | "superlu".
    """
    if structure not in STRUCTURES:
        raise ValueError(f"structure must be one of {STRUCTURES}, got {structure!r}")
    matrix = sp.csr_matrix(matrix)
    if matrix.shape[0] != matrix.shape[1]:
        raise ValueError(f"matrix must be square, got shape {matrix.shape}")
    complex_matrix = np.iscomplexobj(matrix.data)
    if solver == "auto":
        solver = choose_solver(structure, complex_matrix)
    if solver not in SOLVERS:
        raise ValueError(f"solver must be 'auto' or one of {SOLVERS}, got {solver!r}")
    if complex_matrix and solver != "superlu":
        raise ValueError(f"solver {solver!r} is real-only; use 'superlu' for complex matrices")
    if solver == "cholespy" and structure != "spd":
        raise ValueError("cholespy needs a symmetric positive definite matrix (structure='spd')")
    return {"pardiso": _factorize_pardiso, "cholespy": _factorize_cholespy,
            "superlu": _factorize_superlu}[solver](matrix, structure)


def _with_full_diagonal(triangle):
    """Add explicit (possibly zero) diagonal entries: PARDISO's symmetric types require them."""
    n = triangle.shape[0]
    coo = triangle.tocoo()
    rows = np.concatenate([coo.row, np.arange(n)])
    cols = np.concatenate([coo.col, np.arange(n)])
    values = np.concatenate([coo.data, np.zeros(n)])
    out = sp.csr_matrix((values, (rows, cols)), shape=triangle.shape)  # sums duplicates, keeps zeros
    out.sort_indices()
    return out


class _PardisoHandle:
    """Owns one PARDISO instance; frees MKL's factor memory when garbage-collected."""

    def __init__(self, solver, matrix):
        self.solver, self.matrix = solver, matrix
        weakref.finalize(self, _pardiso_release, solver)


def _pardiso_release(solver):
    try:
        # phase −1: all of this instance's memory; phase 0 (the factor only) left ~0.19 GB per
        # factorization of the 5 mm door trim behind (measured over 4 factorizations)
        solver.free_memory(everything=True)
    except Exception:  # noqa: BLE001 - interpreter shutdown
        pass


def _factorize_pardiso(matrix, structure):
    import pypardiso

    mtype = {"spd": 2, "symmetric": -2, "general": 11}[structure]
    stored = _with_full_diagonal(sp.triu(matrix, format="csr")) if mtype != 11 else matrix.copy()
    stored.sort_indices()
    _locate_mkl_runtime()
    solver = pypardiso.PyPardisoSolver(mtype=mtype)
    solver.factorize(stored)  # phase 12: analysis + numerical factorization
    solver.remove_stored_factorization()  # the wrapper's copy of A is not needed: we call phase 33
    if mtype == 2:
        # MKL's defaults run two iterative-refinement steps per solve (iparm(7) reported 2), tripling
        # the solve cost; an SPD Cholesky factor has no perturbed pivots and the residual stays at
        # ~1e-11 without them (measured on the door trim K_ii), so switch refinement off.
        solver.set_iparm(8, 0)
    elif mtype == -2 and int(solver.iparm[13]) == 0:
        # the same for an LDLᵀ factor without perturbed pivots (iparm(14) = 0): its solves are
        # exact to round-off, and the refinement steps made them 4.5× dearer (door trim K − σM)
        solver.set_iparm(8, 0)
    handle = _PardisoHandle(solver, stored)
    # PARDISO's 1-based CSR indices, built once: pypardiso's _call_pardiso copied both (8.6 M
    # entries at 206k DOFs) and X to row-major at every solve, ≈ 0.07 of a 12-column solve's 0.2 s
    one_based = (stored.indptr.astype(np.int32) + 1, stored.indices.astype(np.int32) + 1)

    def solve_block(rhs):
        return _pardiso_solve(solver, stored, one_based, rhs)  # phase 33, X column-major

    entries = int(solver.iparm[17]) if solver.iparm[17] > 0 else None
    # iparm(23) (0-based 22): negative eigenvalues of a symmetric indefinite matrix (mtype -2);
    # a Cholesky factor (mtype 2) succeeded, so it has none
    negative = {2: 0, -2: int(solver.iparm[22])}.get(mtype)
    return Factorization("pardiso", matrix.shape[0], structure, entries, solve_block, handle,
                         negative_pivots=negative)


def _factorize_cholespy(matrix, structure):
    import cholespy

    lower = sp.tril(matrix, format="csc")  # CHOLMOD reads the lower triangle (stype = -1)
    lower.sort_indices()
    n = matrix.shape[0]
    solver = cholespy.CholeskySolverD(n, lower.indptr.astype(np.int32), lower.indices.astype(np.int32),
                                      np.ascontiguousarray(lower.data, dtype=float), cholespy.MatrixType.CSC)

    def solve_block(rhs):
        rhs = np.ascontiguousarray(rhs, dtype=float)
        out = np.empty_like(rhs)
        solver.solve(rhs, out)
        return out

    return Factorization("cholespy", n, structure, None, solve_block, solver)


class _SuperLUHandle:
    def __init__(self, lu, complex_matrix):
        self.lu, self.complex = lu, complex_matrix


def _factorize_superlu(matrix, structure):
    options = {}
    if structure in ("spd", "symmetric"):
        # symmetric ordering of A + Aᵀ and diagonal pivots: far less fill than COLAMD on FE matrices
        options = dict(permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options=dict(SymmetricMode=True))
    lu = spla.splu(matrix.tocsc(), **options)
    complex_matrix = np.iscomplexobj(matrix.data)

    def solve_block(rhs):
        return lu.solve(np.asarray(rhs, dtype=complex if complex_matrix else float))

    return Factorization("superlu", matrix.shape[0], structure, int(lu.L.nnz + lu.U.nnz), solve_block,
                         _SuperLUHandle(lu, complex_matrix))


def _pardiso_solve(pardiso, matrix, one_based, rhs):
    """X = A⁻¹ B with PARDISO's current factor (phase 33) of ``matrix`` (its upper-triangle CSR;
    ``one_based`` = (indptr + 1, indices + 1) as int32). rhs (n, k) float; X (n, k) column-major.

    The call pypardiso's ``_call_pardiso`` makes, without its per-call copies of the index
    arrays (8.6 M entries at 206k DOFs) and of X to row-major: the Lanczos steps take X
    column-major, as their solves want it back."""
    import ctypes

    rhs = np.asfortranarray(rhs, dtype=float)
    x = np.zeros_like(rhs, order="F")
    error = ctypes.c_int32(0)
    int_p, float_p = ctypes.POINTER(ctypes.c_int32), ctypes.POINTER(ctypes.c_double)
    pardiso.set_phase(33)
    pardiso._mkl_pardiso(pardiso.pt.ctypes.data_as(ctypes.POINTER(pardiso._pt_type[0])),
                         ctypes.byref(ctypes.c_int32(1)), ctypes.byref(ctypes.c_int32(1)),
                         ctypes.byref(ctypes.c_int32(pardiso.mtype)),
                         ctypes.byref(ctypes.c_int32(33)),
                         ctypes.byref(ctypes.c_int32(matrix.shape[0])),
                         matrix.data.ctypes.data_as(float_p),
                         one_based[0].ctypes.data_as(int_p), one_based[1].ctypes.data_as(int_p),
                         pardiso.perm.ctypes.data_as(int_p),
                         ctypes.byref(ctypes.c_int32(1 if rhs.ndim == 1 else rhs.shape[1])),
                         pardiso.iparm.ctypes.data_as(int_p),
                         ctypes.byref(ctypes.c_int32(int(pardiso.msglvl))),
                         rhs.ctypes.data_as(float_p), x.ctypes.data_as(float_p),
                         ctypes.byref(error))
    if error.value != 0:
        raise RuntimeError(f"PARDISO solve failed (error {error.value})")
    return x


def shifted_factorizer(stiffness, mass, solver: str = "auto"):
    r"""A function σ → :class:`Factorization` of K − σM (symmetric indefinite, with inertia) that
    does the fill-reducing analysis once for all shifts.

    stiffness, mass: (n, n) sparse symmetric K [N/m], M [kg]. K − σM has the same pattern for
    every σ, so PARDISO's ordering and symbolic factorization (phase 11, ≈ a third of a
    factorization of the 5 mm door trim) and the upper-triangle CSR with its full diagonal are
    built once; each call then runs only the numerical LDLᵀ (phase 22) on data K_u − σ M_u.

    The calls share ONE PARDISO instance: a call replaces the previous factor, whose ``solve``
    then raises (one factor alive at a time — spectrum slicing holds one per run);
    ``factor_at.release()`` frees the factor's memory between uses (the analysis stays). Without
    PARDISO each call is a plain :func:`factorize` of K − σM (``solver``'s backend).
    """
    stiffness, mass = sp.csr_matrix(stiffness), sp.csr_matrix(mass)
    if solver == "auto":
        solver = choose_solver("symmetric")
    if solver != "pardiso":
        def factor_at(shift):
            return factorize(stiffness - shift * mass, solver=solver, structure="symmetric")
        factor_at.release = lambda: None
        return factor_at
    import pypardiso

    n = stiffness.shape[0]
    upper_k, upper_m = sp.triu(stiffness, format="coo"), sp.triu(mass, format="coo")
    rows = np.concatenate([upper_k.row, upper_m.row, np.arange(n)])
    cols = np.concatenate([upper_k.col, upper_m.col, np.arange(n)])
    # K in the real part, M in the imaginary part: one pattern (duplicates summed, zeros kept)
    values = np.concatenate([upper_k.data, 1j * upper_m.data, np.zeros(n)])
    pattern = sp.csr_matrix((values, (rows, cols)), shape=(n, n))
    pattern.sort_indices()
    k_data, m_data = pattern.data.real.copy(), pattern.data.imag.copy()
    stored = sp.csr_matrix((k_data.copy(), pattern.indices, pattern.indptr), shape=(n, n))
    del pattern, upper_k, upper_m, rows, cols, values
    _locate_mkl_runtime()
    pardiso = pypardiso.PyPardisoSolver(mtype=-2)
    handle = _PardisoHandle(pardiso, stored)
    # PARDISO's 1-based CSR indices, built once (the wrapper copies both at every call)
    one_based = (stored.indptr.astype(np.int32) + 1, stored.indices.astype(np.int32) + 1)
    state = {"generation": 0, "refinement": None}

    def factor_at(shift):
        np.subtract(k_data, shift * m_data, out=stored.data)
        if state["generation"] == 0:
            pardiso.set_phase(11)              # ordering + symbolic factorization, once
            pardiso._call_pardiso(stored, np.zeros((n, 1)))
            state["refinement"] = int(pardiso.iparm[7])
        pardiso.set_iparm(8, state["refinement"])
        pardiso.set_phase(22)                  # numerical LDLᵀ on the analysed pattern
        pardiso._call_pardiso(stored, np.zeros((n, 1)))
        state["generation"] += 1
        generation = state["generation"]
        if int(pardiso.iparm[13]) == 0:
            pardiso.set_iparm(8, 0)   # no perturbed pivots: no refinement (as in factorize)

        def solve_block(rhs):
            if state["generation"] != generation:
                raise RuntimeError("this factor of K − σM was replaced by a later shift's")
            return _pardiso_solve(pardiso, stored, one_based, rhs)

        entries = int(pardiso.iparm[17]) if pardiso.iparm[17] > 0 else None
        return Factorization("pardiso", n, "symmetric", entries, solve_block, handle,
                             negative_pivots=int(pardiso.iparm[22]))

    def release():
        """Free the current factor's memory (phase 0); the analysis stays for the next shift."""
        state["generation"] += 1
        pardiso.set_phase(0)
        pardiso._call_pardiso(stored, np.zeros((n, 1)))

    factor_at.release = release
    return factor_at
