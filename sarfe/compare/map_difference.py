"""Difference ERP map of two results on the same mesh (``sarfe compare``).

The meshes agree when both maps have the same number of nodes and triangles, equal connectivity
and node coordinates equal within 1e-6 of the model's size. Then at every node n

    ΔL(n) = 10 log10( e_b(n) / e_a(n) )   [dB]

with e the ERP density [W/m²] of the compared point; nodes where both densities are zero (not
radiating) are masked (NaN), a node silent in one map only gets ±inf. The two maps are taken at
the reference's loudest frequency (the variant's point at the same frequency).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sarfe.compare.deltas import FREQUENCY_RTOL
from sarfe.compare.result_reader import ErpMap, Result, read_erp_map

GEOMETRY_RTOL = 1e-6


@dataclass(frozen=True)
class MapDifference:
    """``delta_db`` (n,) [dB] (NaN where neither map radiates) on ``points_m``/``triangles`` of the
    reference map, at ``frequency_hz``; ``stats()``: ``delta_min_db``/``delta_max_db`` over the nodes."""
    points_m: np.ndarray
    triangles: np.ndarray
    delta_db: np.ndarray
    frequency_hz: float

    def stats(self) -> dict:
        finite = self.delta_db[np.isfinite(self.delta_db)]
        return {"frequency_hz": self.frequency_hz, "nodes": int(self.delta_db.size),
                "radiating_nodes": int(np.count_nonzero(~np.isnan(self.delta_db))),
                "delta_max_db": float(finite.max()) if finite.size else None,
                "delta_min_db": float(finite.min()) if finite.size else None}


def meshes_agree(a: ErpMap, b: ErpMap) -> bool:
    """Same node count, connectivity and coordinates (within GEOMETRY_RTOL of the model size)."""
    if a.points_m.shape != b.points_m.shape or a.triangles.shape != b.triangles.shape:
        return False
    size = float(np.ptp(a.points_m, axis=0).max()) or 1.0
    return bool(np.array_equal(a.triangles, b.triangles)
                and np.abs(a.points_m - b.points_m).max() <= GEOMETRY_RTOL * size)


def density_difference_db(ea: np.ndarray, eb: np.ndarray) -> np.ndarray:
    """ΔL = 10 log10(e_b / e_a) per node [dB]; NaN where both are 0."""
    with np.errstate(divide="ignore", invalid="ignore"):
        out = 10.0 * np.log10(eb / ea)
    out[(ea == 0) & (eb == 0)] = np.nan
    out[(ea == eb) & (ea > 0)] = 0.0
    return out


def map_difference(a: Result, b: Result) -> tuple[MapDifference | None, str]:
    """The difference map of b against a at a's loudest point, or None and the reason why not."""
    index = a.worst.get("index")
    if index is None:
        return None, "the reference has no loudest point"
    frequency = a.points[int(index)].frequency_hz
    hit = [p.index for p in b.points
           if abs(p.frequency_hz - frequency) <= FREQUENCY_RTOL * abs(frequency)]
    if not hit:
        return None, f"{b.label} has no point at {frequency:g} Hz"
    map_a, map_b = read_erp_map(a, int(index)), read_erp_map(b, hit[0])
    if map_a is None or map_b is None:
        return None, "no ERP map (output.files without erp_vtu)"
    if not meshes_agree(map_a, map_b):
        return None, "the meshes differ"
    return MapDifference(points_m=map_a.points_m, triangles=map_a.triangles,
                         delta_db=density_difference_db(map_a.density_W_m2, map_b.density_W_m2),
                         frequency_hz=frequency), ""
