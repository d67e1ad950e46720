"""Read a sarfe solve result folder for ``sarfe compare``: summary.json, response.h5, the ERP maps.

A result is a folder ``sarfe solve`` wrote (marker ``.sarfe-result`` of kind ``solve``, or a
``summary.json`` of a result written before the marker). What a comparison needs from it:

* per frequency point j (``points[j]`` of summary.json): frequency f_j [Hz], total A-weighted ERP
  level L_A(f_j) [dB(A) re 1e-12 W], each contact's A-weighted contribution level [dB(A)], and
  the third-octave band levels [dB(A)] by nominal band frequency;
* the loudest point (``worst``): level, error bound [dB], frequency, ranking line;
* the sweep L_A(f) from response.h5 (``frequency_hz``, ``erp/level_total_a_db``) when it is there,
  else from summary.json;
* the ERP map of a point: node coordinates (n, 3) [m] and ERP density (n,) [W/m²] from
  ``erp/erp_<j:04d>.vtu`` (read with pyvista, imported when a map is asked for).

Anything else (a missing folder, a batch folder, no or unreadable summary.json) is a
:class:`~sarfe.case.errors.CaseError` of one line naming the folder.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np

from sarfe.case.errors import CaseError
from sarfe.results.folder import MARKER


@dataclass(frozen=True)
class Point:
    """One frequency point: ``frequency_hz``, ``level_dba`` (total ERP), ``contacts`` {name: dB(A)},
    ``bands`` {nominal Hz: dB(A)} (nonlinear third-octave levels), ``sources`` {name: dB(A)}
    (contribution levels incl. the excitation's own structure-borne share), ``converged``."""
    index: int
    frequency_hz: float
    level_dba: float
    contacts: dict
    bands: dict
    sources: dict
    converged: bool


@dataclass(frozen=True)
class Result:
    """A solve result: ``path``, ``case`` name, ``points`` (tuple of :class:`Point`), ``worst``
    (summary's loudest-point dict), ``sweep_hz``/``sweep_dba`` (the sweep, (m,) each),
    ``summary`` (the whole summary.json as read)."""
    path: Path
    case: str
    points: tuple
    worst: dict
    sweep_hz: np.ndarray
    sweep_dba: np.ndarray
    summary: dict

    @property
    def label(self) -> str:
        """Case name and folder name (the two differ for variants of one case)."""
        return self.case if self.case == self.path.name else f"{self.case} ({self.path.name})"


def level(value) -> float:
    """A dB value of summary.json as a float: null (the JSON of -inf, zero power) → -inf."""
    return -math.inf if value is None else float(value)


def _fail(path, problem: str):
    raise CaseError(problem, source=str(path))


def _marker(folder: Path) -> dict | None:
    try:
        return json.loads((folder / MARKER).read_text())
    except (OSError, ValueError):
        return None


def read_result(folder) -> Result:
    """Read the result folder ``folder`` (see the module docstring); CaseError if it is not one."""
    path = Path(folder)
    if not path.is_dir():
        _fail(path, "no such folder" if not path.exists() else "not a folder (a sarfe result "
              "folder is expected)")
    marker = _marker(path)
    if marker is not None and marker.get("kind") not in (None, "solve"):
        _fail(path, f"a sarfe {marker.get('kind')} folder, not a solve result (compare the "
              "variant folders of a batch: variant_outputs/<id>/)")
    summary_path = path / "summary.json"
    if not summary_path.is_file():
        _fail(path, "not a sarfe result (no summary.json)")
    try:
        summary = json.loads(summary_path.read_text())
    except (OSError, ValueError) as exc:
        _fail(summary_path, f"unreadable ({exc})")
    if not isinstance(summary, dict) or not isinstance(summary.get("points"), list) \
            or "case" not in summary:
        _fail(summary_path, "not a sarfe solve summary (no 'case' and 'points')")
    try:
        points = tuple(_point(j, p) for j, p in enumerate(summary["points"]))
    except (KeyError, TypeError, ValueError) as exc:
        _fail(summary_path, f"a point lacks {exc} (written by another sarfe version?)")
    if not points:
        _fail(summary_path, "holds no frequency point")
    sweep_hz, sweep_dba = _sweep(path / "response.h5", points)
    return Result(path=path, case=str(summary["case"]), points=points,
                  worst=summary.get("worst") or {}, sweep_hz=sweep_hz, sweep_dba=sweep_dba,
                  summary=summary)


def _point(j: int, p: dict) -> Point:
    bands = ((p.get("bands") or {}).get("nonlinear")) or {}
    sources = (p.get("contributions") or {}).get("sources") or []
    return Point(
        index=int(p.get("index", j)), frequency_hz=float(p["frequency_hz"]),
        level_dba=level(p["erp"]["level_dba"]),
        contacts={c["name"]: level(c.get("erp_level_dba")) for c in p.get("contacts") or []},
        bands={float(f): level(v) for f, v in zip(bands.get("nominal_hz") or [],
                                                   bands.get("level_dba") or [])},
        sources={s["name"]: level(s.get("level_dba")) for s in sources},
        converged=bool(p.get("converged", True)))


def _sweep(h5_path: Path, points) -> tuple[np.ndarray, np.ndarray]:
    """L_A(f) from response.h5 if readable, else from the summary's points."""
    if h5_path.is_file():
        try:
            with h5py.File(h5_path, "r") as f:
                return (np.asarray(f["frequency_hz"][()], float),
                        np.asarray(f["erp/level_total_a_db"][()], float))
        except (OSError, KeyError):
            pass
    return (np.array([p.frequency_hz for p in points]), np.array([p.level_dba for p in points]))


@dataclass(frozen=True)
class ErpMap:
    """ERP density of one point on the result's mesh: ``points_m`` (n, 3), ``triangles`` (t, 3)
    node indices, ``density_W_m2`` (n,) (0 at non-radiating nodes), ``frequency_hz``."""
    points_m: np.ndarray
    triangles: np.ndarray
    density_W_m2: np.ndarray
    frequency_hz: float


def read_erp_map(result: Result, point_index: int) -> ErpMap | None:
    """The ERP map of point ``point_index`` (``erp/erp_<j:04d>.vtu``), None when the result has no
    map of that point (``output.files`` without ``erp_vtu``) or it cannot be read."""
    vtu = result.path / "erp" / f"erp_{point_index:04d}.vtu"
    if not vtu.is_file():
        return None
    import pyvista   # heavy (VTK): only when a map is compared

    try:
        grid = pyvista.read(vtu)
        density = np.asarray(grid.point_data["erp_density_W_m2"], float)
    except (OSError, KeyError, ValueError):
        return None
    cells = grid.cells_dict
    quads = np.asarray(cells.get(9, np.empty((0, 4), int)))            # VTK_QUAD = 9: two triangles
    triangles = np.vstack([np.asarray(cells.get(5, np.empty((0, 3), int))).reshape(-1, 3),
                           quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])      # VTK_TRIANGLE = 5
    frequency = np.asarray(grid.field_data.get("frequency_hz", [np.nan]), float).ravel()[0]
    return ErpMap(points_m=np.asarray(grid.points, float), triangles=triangles,
                  density_W_m2=density, frequency_hz=float(frequency))
