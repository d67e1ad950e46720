"""DOF numbering, sparse assembly and support (fixed-DOF) sets for 6-DOF shell nodes.

DOF order is node-major: dof = 6·node + c with c = 0..5 ↔ [ux, uy, uz, rx, ry, rz].
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["element_dofs", "assemble", "assemble_pair", "fixed_dofs", "free_dofs", "lumped_mass",
           "COMPONENTS"]

#: component letters of the 6 nodal DOFs
COMPONENTS = ("ux", "uy", "uz", "rx", "ry", "rz")

_NAMED = {
    "all": (0, 1, 2, 3, 4, 5),
    "translations": (0, 1, 2),
    "rotations": (3, 4, 5),
}


def element_dofs(triangles, dofs_per_node=6):
    """Global DOF numbers of each element, (n_el, 3·dofs_per_node), node-major."""
    triangles = np.asarray(triangles, dtype=np.int64)
    return (dofs_per_node * triangles[:, :, None] + np.arange(dofs_per_node)).reshape(
        triangles.shape[0], -1
    )


def _coo_indices(dofs, n_dof):
    index_type = np.int32 if n_dof < 2**31 - 1 else np.int64
    dofs = np.asarray(dofs, dtype=index_type)
    n_el, k = dofs.shape
    rows = np.broadcast_to(dofs[:, :, None], (n_el, k, k)).ravel()
    cols = np.broadcast_to(dofs[:, None, :], (n_el, k, k)).ravel()
    return rows, cols


def assemble(element_matrices, dofs, n_dof):
    """Sum element matrices (n_el, k, k) into a CSR (n_dof, n_dof) in one coo → csr pass."""
    rows, cols = _coo_indices(dofs, n_dof)
    matrix = sp.coo_matrix((element_matrices.ravel(), (rows, cols)), shape=(n_dof, n_dof))
    return matrix.tocsr()


def assemble_pair(element_stiffness, element_mass, dofs, n_dof):
    """Assemble two matrices with the same element DOFs (K and M) in a single pass.

    The pair is summed as one complex matrix K + iM (coo → csr sums duplicates in both
    parts at once), then split into real CSR matrices with identical sparsity patterns.
    element_stiffness / element_mass: (n_el, k, k) real, or pass a complex (n_el, k, k)
    array as element_stiffness and None as element_mass.
    """
    if element_mass is None:
        combined = np.asarray(element_stiffness)
    else:
        combined = element_stiffness + 1j * element_mass
    rows, cols = _coo_indices(dofs, n_dof)
    matrix = sp.coo_matrix((combined.ravel(), (rows, cols)), shape=(n_dof, n_dof)).tocsr()
    pattern = (matrix.indices, matrix.indptr)
    stiffness = sp.csr_matrix((matrix.data.real.copy(), *pattern), shape=matrix.shape)
    mass = sp.csr_matrix((matrix.data.imag.copy(), matrix.indices.copy(), matrix.indptr.copy()),
                         shape=matrix.shape)
    return stiffness, mass


def _components(components):
    if isinstance(components, str):
        if components in _NAMED:
            return np.array(_NAMED[components])
        names = [c.strip() for c in components.replace(",", " ").split()]
        if not names or any(c not in COMPONENTS for c in names):
            raise ValueError(
                f"components {components!r}: use 'all', 'translations', 'rotations', "
                f"names from {COMPONENTS} or integers 0..5"
            )
        return np.array([COMPONENTS.index(c) for c in names])
    comps = np.asarray(components, dtype=np.int64).ravel()
    if comps.size == 0 or comps.min() < 0 or comps.max() > 5:
        raise ValueError(f"components must be integers in 0..5, got {components!r}")
    return comps


def fixed_dofs(nodes, components="all"):
    """Sorted unique DOF numbers 6·node + c of a clamped/supported node set.

    nodes: node indices (any shape); components: 'all' (clamped), 'translations'
    (pinned), 'rotations', a string of names like 'ux uy uz' or integers 0..5.
    """
    nodes = np.asarray(nodes, dtype=np.int64).ravel()
    comps = _components(components)
    return np.unique(6 * nodes[:, None] + comps[None, :])


def free_dofs(n_dof, fixed):
    """Complement of ``fixed`` in range(n_dof), sorted."""
    mask = np.ones(n_dof, dtype=bool)
    mask[np.asarray(fixed, dtype=np.int64)] = False
    return np.flatnonzero(mask)


def lumped_mass(mass, dofs):
    """Lumped element masses (n_el, k, k) from consistent ones (n_el, k, k), global frame.

    Per translation direction c the HRZ diagonal m_ii · (Σ_ij M_ij / Σ_i M_ii) over that
    direction's DOFs: the element's mass in c, r_cᵀ M r_c, is kept exactly (so is the
    model's), and every entry is positive (quadratic cells too; a linear triangle's corner gets
    m''A/3). The rotation–rotation block (rotary inertia) is kept, so M stays definite; the
    translation–rotation coupling (offset shells, beams) is dropped. dofs (n_el, k): global DOF
    numbers 6·node + c (only the component dof % 6 is used). A loop over the three directions,
    vectorized over elements."""
    component = np.asarray(dofs) % 6
    n_el, size = component.shape
    diagonal = np.einsum("eii->ei", mass)
    lumped = np.zeros_like(mass)
    index = np.arange(size)
    for c in range(3):
        pick = (component == c).astype(float)
        total = (pick[:, None, :] @ mass @ pick[:, :, None])[:, 0, 0]
        diag_sum = (diagonal * pick).sum(axis=1)
        scale = np.divide(total, diag_sum, out=np.zeros(n_el), where=diag_sum > 0)
        lumped[:, index, index] += diagonal * pick * scale[:, None]
    rotation = component >= 3
    lumped += mass * (rotation[:, :, None] & rotation[:, None, :])
    return lumped
