r"""The mesh-discretization part of a radiated level's error estimate.

Two meshes (h, r·h; ``mesh_richardson``): a level L_h and the same point re-solved on a mesh of
size r·h (r = MESH_RATIO = 2), with a discretization error ∝ h^p, give by Richardson extrapolation

    e_mesh(h) = |L_h − L_{rh}| / (r^p − 1)      [dB]                                  (1)

with p = MESH_ORDER = 1 stated, not fitted (the slowest convergence a consistent element gives).
With r = 2 this is the same number as Roache's two-grid GCI with his factor of safety Fs = 3 and
p = 2 (3·|ΔL|/(2² − 1)). Used where only two meshes are at hand (``sarfe study --knobs mesh``
ladders, the fallback of the three-mesh estimate).

Three meshes (h, r·h, r²·h; ``mesh_gci``, the ± of a solve): Roache's grid convergence index
(GCI; Roache 1998, the ASME procedure of Celik et al. 2008) with the observed order and the
handling of non-asymptotic data of Eça & Hoekstra (2014). With ε₂₁ = L_{rh} − L_h, ε₃₂ =
L_{r²h} − L_{rh} and the data range ΔM = max L − min L of the three levels:

    monotone (ε₃₂/ε₂₁ > 0):  p = ln(ε₃₂/ε₂₁) / ln r
        1 ≤ p ≤ 2     e = 1.25 · |ε₂₁| / (r^p − 1)          GCI, Fs = 1.25, observed p       (2)
        otherwise     e = 1.25 · ΔM                         not in the asymptotic range
    oscillatory (ε₃₂/ε₂₁ ≤ 0):  e = 3 · ΔM                  Fs = 3 on the data range

The observed p is trusted between the slowest order a consistent element gives (1) and the
order of the shell elements' displacement (2); outside that range the three levels are not in the
asymptotic range and their range ΔM is the measure (as in Eça & Hoekstra's procedure for data
that do not converge asymptotically), with Roache's Fs = 1.25 where they move one way and Fs = 3
where they oscillate. With r = MESH_GCI_RATIO = √2 (coarsest mesh 2h, as for (1)) the p < 1
branch joins (2) continuously: at p = 1, ΔM = |ε₂₁|(1 + √2) = |ε₂₁|/(√2 − 1). An observed p > 2
means the two finer levels agree better than the order allows; on the measured ladders that is
the mesh-to-mesh oscillation, not convergence.

Measured on the squeak rig at 50 Hz (12 → 4 mm) the level oscillates by ±0.15–0.3 dB from mesh to
mesh (where the nodes fall under the pad) around a slow trend: the two-mesh estimate (1) landed on
two levels that happened to agree at 10 mm (0.18 dB against a true 0.79; the whole ± 0.57 did not
cover it); the third mesh shows the oscillation and (2) covers every mesh of both ladders
(benchmarks/results/mesh_cover.md). The level is A-weighted and unweighted alike: the larger of
the two estimates is used.
"""
from __future__ import annotations

import math

MESH_RATIO = 2.0     # the coarser mesh's element size / the case's (1)
MESH_ORDER = 1.0     # stated order p of the level's mesh convergence (1)
MESH_GCI_RATIO = math.sqrt(2.0)   # refinement ratio r of the three meshes h, √2·h, 2·h (2)
MESH_ORDER_BOUNDS = (1.0, 2.0)    # observed p trusted in (2); outside: the data range
SAFETY_FACTOR = 1.25              # Roache's Fs for three meshes with the observed order (2)
SAFETY_FACTOR_OSCILLATING = 3.0   # Fs on the data range when the levels oscillate (2)


def mesh_richardson(level_db: float, coarse_level_db: float, order: float = MESH_ORDER,
                    ratio: float = MESH_RATIO) -> float:
    """(1): the estimated mesh error [dB] of ``level_db`` on a mesh of size h from
    ``coarse_level_db`` on ratio·h, with the error ∝ h^order; NaN when either is not finite."""
    if not (math.isfinite(level_db) and math.isfinite(coarse_level_db)):
        return float("nan")
    return abs(float(level_db) - float(coarse_level_db)) / (float(ratio) ** float(order) - 1.0)


def mesh_gci(levels_db, ratio: float = MESH_GCI_RATIO) -> dict:
    """(2): the mesh error [dB] of ``levels_db[0]`` (mesh h) from the levels on h, r·h, r²·h →
    {'mesh_db', 'convergence': 'monotone' | 'pre-asymptotic' | 'oscillatory' | 'converged',
    'order' (observed p, NaN when oscillatory), 'order_used' (p in (2), NaN where the data range is
    used), 'safety_factor', 'range_db' (ΔM)}; mesh_db NaN when a level is not finite."""
    L1, L2, L3 = (float(v) for v in levels_db)
    out = {"mesh_db": float("nan"), "convergence": None, "order": float("nan"),
           "order_used": float("nan"), "safety_factor": float("nan"), "range_db": float("nan")}
    if not all(math.isfinite(v) for v in (L1, L2, L3)):
        return out
    e21, e32 = L2 - L1, L3 - L2
    spread = max(L1, L2, L3) - min(L1, L2, L3)
    out["range_db"] = spread
    if spread == 0.0:
        return dict(out, mesh_db=0.0, convergence="converged", safety_factor=SAFETY_FACTOR)
    if e21 * e32 <= 0.0:
        return dict(out, mesh_db=SAFETY_FACTOR_OSCILLATING * spread, convergence="oscillatory",
                    safety_factor=SAFETY_FACTOR_OSCILLATING)
    p = math.log(e32 / e21) / math.log(ratio)
    low, high = MESH_ORDER_BOUNDS
    out.update(order=p, safety_factor=SAFETY_FACTOR)
    if not low <= p <= high:
        return dict(out, mesh_db=SAFETY_FACTOR * spread, convergence="pre-asymptotic")
    return dict(out, mesh_db=SAFETY_FACTOR * abs(e21) / (ratio ** p - 1.0),
                convergence="monotone", order_used=p)


__all__ = ["MESH_RATIO", "MESH_ORDER", "MESH_GCI_RATIO", "MESH_ORDER_BOUNDS", "SAFETY_FACTOR",
           "SAFETY_FACTOR_OSCILLATING", "mesh_richardson", "mesh_gci"]
