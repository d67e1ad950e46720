"""Which points of a run get an ERP map (``output.maps``): a sweep writes what a user opens —
the loudest point and a chosen few — not one VTU per point (issue 30).

    'loudest'         the loudest point only (default; summary.json ``worst.index``)
    {'every': N}      every N-th reported point in sweep order (0, N, 2N, …), and the loudest
    [f₁, f₂, …] [Hz]  the reported point nearest each frequency (a converged one when there is
                      one), and the loudest

One map is ``erp.vtu``; several are the collection ``erp/erp.pvd`` with ``erp/erp_NNNN.vtu``,
NNNN the point's index in summary.json ``points`` (:func:`sarfe.results.vtk.write_erp_sweep`).
"""
from __future__ import annotations

from collections.abc import Mapping

import numpy as np


def map_indices(maps, frequencies_hz, converged, loudest) -> list:
    """Sorted point indices to map (module docstring). ``frequencies_hz`` (n,) of the reported
    points, ``converged`` (n,) bool, ``loudest``: the loudest point's index (None: the first)."""
    n = len(frequencies_hz)
    if n == 0:
        return []
    loudest = 0 if loudest is None else int(loudest)
    chosen = {loudest}
    if isinstance(maps, Mapping):
        chosen |= set(range(0, n, int(maps["every"])))
    elif not isinstance(maps, str):
        f = np.asarray(frequencies_hz, dtype=float)
        ok = np.asarray(converged, dtype=bool)
        pool = np.flatnonzero(ok) if ok.any() else np.arange(n)
        for target in maps:
            chosen.add(int(pool[np.argmin(np.abs(f[pool] - float(target)))]))
    return sorted(chosen)


def maps_every_point(maps, count: int) -> bool:
    """True when ``maps`` selects every one of ``count`` points ({'every': 1}, or one point)."""
    return count <= 1 or (isinstance(maps, Mapping) and int(maps["every"]) == 1)


__all__ = ["map_indices", "maps_every_point"]
