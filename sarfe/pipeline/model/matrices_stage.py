r"""The linear stage of a ``model.matrices`` case: M, K (and D) as given — inline rows or a file
(.npz, .npy, .mtx) — on all n DOFs, no reduction.

Load vectors: a unit force on the DOF of each ``excitation.forces`` entry; base acceleration
−M ι with the ``influence`` vector ι (default all ones); ERP map: the selection of ``erp.dofs``
(areas ``erp.areas_m2``). Contact DOFs are checked here (in range, not relative to themselves);
the contacts themselves are built from the case (:mod:`sarfe.pipeline.model.nonlinear_model`).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from sarfe.case.errors import CaseError
from sarfe.hbm.model import make_linear_model


def read_matrix(case, key):
    """``model.matrices.<key>`` as a square array (inline rows) or matrix (a file); CaseError
    naming the key for a wrong shape or an unreadable file."""
    path_key = ("model", "matrices", key)
    value = case.config.model.matrices.entry(key)
    if not isinstance(value, str):
        rows = [len(r) for r in value]
        if any(n != len(value) for n in rows):
            raise case.error(f"must be a square matrix (list of {len(value)} rows of "
                             f"{len(value)} numbers)", path_key)
        return np.asarray(value, dtype=float)
    path = case.resolve(value)
    try:
        suffix = path.suffix.lower()
        if suffix == ".mtx":
            import scipy.io   # Matrix Market files only

            matrix = sp.csr_matrix(scipy.io.mmread(str(path)))
        elif suffix == ".npy":
            matrix = np.load(path, allow_pickle=False)
        else:
            try:
                matrix = sp.load_npz(path).tocsr()
            except (ValueError, KeyError, OSError):
                with np.load(path, allow_pickle=False) as archive:
                    names = list(archive.files)
                    name = key if key in names else (names[0] if len(names) == 1 else None)
                    if name is None:
                        raise CaseError(f"{path.name} holds arrays {names}; none is named '{key}'")
                    matrix = archive[name]
    except CaseError as exc:
        raise case.error(exc.message, path_key) from None
    except Exception as exc:  # unreadable file of any kind
        if "allow_pickle" in str(exc) or "pickled" in str(exc):   # numpy's advice to unpickle
            with open(path, "rb") as handle:
                head = handle.read(6)
            what = ("holds pickled Python objects, which sarfe does not load"
                    if head.startswith((b"PK", b"\x93NUMPY")) or head[:1] == b"\x80"
                    else "is not a NumPy .npy/.npz file (no zip or NPY header): corrupt or "
                         "another format")
            raise case.error(f"cannot read matrix file {path}: it {what}; save the matrix with "
                             "numpy.save / numpy.savez or scipy.sparse.save_npz", path_key) from None
        raise case.error(f"cannot read matrix file {path}: {exc}", path_key) from None
    if matrix.ndim != 2 or matrix.shape[0] != matrix.shape[1]:
        raise case.error(f"must be a square matrix, file holds shape {matrix.shape}", path_key)
    return matrix


def check_dof(case, dof, n, path):
    """A DOF index (or 'ground') of an n-DOF model, else CaseError at ``path``."""
    if dof != "ground" and not 0 <= dof < n:
        raise case.error(f"DOF {dof} out of range (the model has {n} DOFs: 0…{n - 1})", path)


def build_matrices_stage(case) -> dict:
    """The linear stage of a matrices case (the fields of :class:`sarfe.pipeline.model.stage.
    LinearStage`, module docstring)."""
    config = case.config
    mass = read_matrix(case, "mass")
    stiffness = read_matrix(case, "stiffness")
    damping = read_matrix(case, "damping") if config.model.matrices.entry("damping") is not None \
        else None
    n = mass.shape[0]
    for key, matrix in (("stiffness", stiffness), ("damping", damping)):
        if matrix is not None and matrix.shape != (n, n):
            raise case.error(f"has shape {matrix.shape}, mass has ({n}, {n})",
                             ("model", "matrices", key))
    try:
        make_linear_model(mass, damping, stiffness)
    except ValueError as exc:
        word = str(exc).split()[0]
        key = word if word in ("mass", "stiffness", "damping") else "mass"
        raise case.error(str(exc), ("model", "matrices", key)) from None
    for contact in config.contacts:
        i = contact.index
        refs = ([(("normal_dof",), contact.normal_dof)] if contact.normal_dof is not None else []) \
            + [(("tangential_dofs", j), t) for j, t in enumerate(contact.tangential_dofs)]
        for key, ref in refs:
            check_dof(case, ref.dof, n, ("contacts", i) + key + ("dof",))
            check_dof(case, ref.relative_to, n, ("contacts", i) + key + ("relative_to",))
            if ref.relative_to == ref.dof:
                raise case.error("a DOF cannot be relative to itself",
                                 ("contacts", i) + key + ("relative_to",))
    exc = config.excitation
    loads = np.zeros((len(exc.forces), n))
    for i, load in enumerate(exc.forces):
        check_dof(case, load.dof, n, ("excitation", "forces", i, "dof"))
        loads[i, load.dof] = 1.0
    base = None
    if exc.base_acceleration is not None:
        influence = exc.base_acceleration.influence           # ι, all ones when not given
        influence = np.ones(n) if influence is None else np.asarray(influence, dtype=float)
        if influence.shape != (n,):
            raise case.error(f"needs {n} entries (one per DOF), got {len(influence)}",
                             ("excitation", "base_acceleration", "influence"))
        base = -(mass @ influence)
    erp = config.erp
    dofs = np.asarray(erp.dofs or [], dtype=int)
    for j, dof in enumerate(dofs):
        check_dof(case, int(dof), n, ("erp", "dofs", j))
    erp_map = np.zeros((len(dofs), n))
    erp_map[np.arange(len(dofs)), dofs] = 1.0
    return dict(kind="matrices", mass=mass, stiffness=stiffness, damping=damping,
                load_vectors=loads, base_vector=base, contacts={}, erp_map=erp_map,
                erp_areas=np.asarray(erp.areas_m2 or [], dtype=float), erp_nodes=dofs,
                info={"dofs": n})


__all__ = ["read_matrix", "check_dof", "build_matrices_stage"]
