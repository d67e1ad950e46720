r"""The linear stage record of a case and its key.

    LinearStage                 picklable reduced model + contact geometry, load and ERP maps
    linear_model_key(case)      SHA-256 of everything the linear stage depends on

Everything in a linear stage is independent of the contact law parameters, damping, force
amplitudes and frequencies, so a batch over those reuses it: two cases with the same key share
one stage (:func:`sarfe.pipeline.model.linear_stage.build_linear_model`).
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field

import numpy as np

from sarfe.case.read import load_case
from sarfe.hbm import laws
from sarfe.pipeline.model.cutoff import default_cutoff_hz
from sarfe.pipeline.model.deck_model import deck_files
from sarfe.util.hashing import file_sha256, sha256_hex


@dataclass(frozen=True)
class LinearStage:
    """Picklable linear part of a case (see module docstring). n_r kept DOFs, SI units.

    mass, stiffness (n_r, n_r) [kg], [N/m] dense or sparse; damping (n_r, n_r) [N s/m] or None (the
    matrices path's own D; FE damping is applied per case in :func:`solve_case`).
    load_vectors (n_loads, n_r): force on q per 1 N of each ``excitation.forces`` entry (direction
    included); base_vector (n_r,) or None: −Tᵀ M ι per 1 m/s² base acceleration.
    contacts: {name: ContactGeometry} (FE) — matrices contacts are built from the case directly.
    erp_map (n_s, n_r): normal displacement of the radiating nodes w_s = erp_map q; erp_areas (n_s,)
    [m²]; erp_nodes (n_s,) mesh nodes (FE) or DOFs (matrices).
    """

    key: str
    kind: str
    mass: object
    stiffness: object
    damping: object
    load_vectors: np.ndarray
    base_vector: np.ndarray | None
    contacts: dict
    erp_map: np.ndarray
    erp_areas: np.ndarray
    erp_nodes: np.ndarray
    mesh: object = None
    reduced: object = None
    mode_frequencies_hz: np.ndarray = field(default_factory=lambda: np.zeros(0))
    info: dict = field(default_factory=dict)
    timings: dict = field(default_factory=dict)
    node_ids: np.ndarray | None = None     # deck GRID / node id of each mesh point (deck path)
    added_damping: np.ndarray | None = None  # (n_r, n_r) [N s/m] a deck's dampers (CBUSH B), reduced

    @property
    def dof_count(self) -> int:
        return self.mass.shape[0]


# -------------------------------------------------------------------------------------- hashing
def _reduction_key(reduction: dict, config) -> dict:
    """The reduction settings a stage depends on: the given ones, plus the default cutoff (which
    follows H and f_max) only when neither cutoff_hz nor mode_count is given."""
    if "cutoff_hz" in reduction or "mode_count" in reduction:
        return dict(reduction)
    return dict(reduction, effective_cutoff_hz=default_cutoff_hz(config))


def linear_model_key(case) -> str:
    """SHA-256 of everything the linear stage depends on (mesh bytes or generator parameters,
    materials, thicknesses, fixed groups, reduction, contact node sets and normals, excitation
    DOFs/groups and directions, ERP surface). Same key → :func:`build_linear_model` is reusable.
    The key hashes the case's normalized mapping (``case.data``), files by their bytes.
    """
    case = load_case(case)
    data = case.data
    model = json.loads(json.dumps(data["model"]))
    for section in model.values():
        for key in ("mesh", "deck", "mass", "stiffness", "damping"):
            if key == "deck" and isinstance(section.get(key), str):   # with its INCLUDEs
                section[key] = {"file_sha256": [file_sha256(f) for f in
                                                deck_files(case.resolve(section[key]))]}
            elif isinstance(section.get(key), str):
                section[key] = {"file_sha256": file_sha256(case.resolve(section[key]))}
    exc = data["excitation"]
    parts = {
        "model": model,
        "reduction": _reduction_key(data.get("reduction", {}), case.config) if case.is_fe else None,
        "contacts": [{k: c.get(k) for k in ("name", "between", "pairs", "points_m", "surfaces",
                                            "pairing_tolerance_m", "normal", "patch_radius_m",
                                            "normal_dof", "tangential_dofs", "from_elements",
                                            "element_axis")}
                     # a law without a tangent element keeps only the normal rows (their boundary)
                     | {"tangent_rows": laws.uses_tangent(laws.law(entry.kind), entry.params)}
                     for c, entry in zip(data["contacts"], case.config.contacts)],
        "forces": [{k: f.get(k) for k in ("group", "dof", "direction", "load_set")}
                   for f in exc.get("forces", [])],
        "base": {k: v for k, v in exc["base_acceleration"].items() if k in ("direction", "influence")}
        if "base_acceleration" in exc else None,
        "erp": {k: data["erp"].get(k) for k in ("surface", "dofs", "areas_m2")},
        # 2: contact rows from the geometry (points on the shells' faces, the partner surface's
        # normal), the boundary = the DOFs they touch (issue 29)
        "sarfe_linear_stage": 2,
    }
    return sha256_hex(json.dumps(parts, sort_keys=True, default=str))


# ------------------------------------------------------------------------------------- progress
def next_step(bar, description):
    """Move a linear-stage progress bar (or None) on to the step ``description`` (None: done)."""
    if bar is None:
        return
    bar.update(1)
    if description is None:
        bar.close()
    else:
        bar.set_description(f"linear stage: {description}")


__all__ = ["LinearStage", "linear_model_key", "next_step"]
