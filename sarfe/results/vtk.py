r"""ParaView files: ERP maps (VTU), collections (PVD) and operating-deflection animations.

All VTU files are unstructured grids of the surface triangles with undeformed point coordinates
[m], point data and a little field data (VTK's XML writer: appended raw binary, LZ4-compressed —
20× faster to write than base64 + zlib at ~10 % more bytes; ParaView, VTK and pyvista read it,
meshio 5 does not know the LZ4 compressor). A 5 mm door-trim map (34k points, 22 arrays, H = 15)
costs ≈ 10 ms for its arrays and ≈ 10 ms to write (benchmarks/results/outputs.md); a sweep's
series is built map by map, on worker processes when it is large (:func:`write_erp_sweep`).
PVD files are plain XML collections of VTU files referenced by *relative* file names, so a result
directory can be moved.

Standard ERP point arrays (:func:`erp_point_data`), n = number of mesh points:

    erp_density_W_m2                (n,)   Σ_k e_k,i, ERP density summed over harmonics [W/m²]
    erp_density_h<k>_W_m2           (n,)   e_k,i of harmonic k = 1 … H [W/m²]
    normal_velocity_amplitude_m_s   (n,)   √(Σ_k |v_n,k|²) [m/s], so erp_density = ½ρc·RLF·v²
    normal_displacement_amplitude_m (n,)   max_θ |w(θ) − w0| of the surface-normal displacement [m]
    displacement_amplitude_m        (n, 3) per component max_θ |u(θ) − u0| over one period [m]
                                           (zeros if the caller passes no nodal displacement)
    erp_level_db_m2                 (n,)   10 log10(erp_density / 1 pW/m²) [dB re 1 pW/m²], floored
                                           at the frame's maximum − 60 dB (silent points of the
                                           surface sit on the floor), so ParaView's automatic
                                           colour range shows the hot spots without tuning; NaN at
                                           the points off the ERP surface (ParaView's NaN colour,
                                           not the colour of silence). The active scalars of the
                                           file: what ParaView colours by when it opens it
    radiating                       (n,)   int8: 1 on the ERP surface (``erp.surface``), 0 elsewhere
    contact_marker                  (n,)   int: 0 = no contact, c+1 = node of contact c
                                           (ContactSet order; the last contact wins on shared nodes)
    node_id                         (n,)   int: the deck's GRID / node id of each point (deck
                                           models only)
    contact_peak_force_N            (n,)   peak contact force magnitude over the period at both nodes
                                           of each contact pair, 0 elsewhere (only when given)
    contact_relative_displacement_m (n,)   max_θ |r(θ) − r0| of the pair's relative displacement
                                           (normal and tangential rows), 0 elsewhere (only when given)

Non-radiating points get 0 in the ERP density arrays (no power: the sums stay right) and NaN in
``erp_level_db_m2``; threshold ``radiating`` to hide them. The contact arrays make parts visible
that rattle or rub without radiating (a clip behind the panel): colour by them, or threshold them.

Cell data ``part_id`` (n_tri,) int32: 1 + the index of the triangle's part in the field data
``part_names`` ("part_beam,part_plate"; 0: no part) — :func:`part_ids`: the element groups
``part_*`` (generated meshes) or ``pid_*`` (decks), else every element group. PVD times are written
with :data:`PVD_DIGITS` significant digits (30 Hz, not 29.999999999999996), more only where
that would merge two times.
"""
from __future__ import annotations

import errno
import os
import warnings
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from sarfe.util.workers import start_map

__all__ = ["write_erp_vtu", "write_pvd", "write_deflection_animation", "write_erp_sweep",
           "start_erp_sweep",
           "erp_point_data", "radiating_fields", "contact_markers", "period_samples",
           "excursion_amplitude",
           "contact_point_values", "erp_level_db_m2", "DB_MAP_RANGE", "part_ids",
           "MASKED_ARRAYS", "PVD_DIGITS"]

DB_MAP_RANGE = 60.0  # [dB] span of erp_level_db_m2 below its maximum
MASKED_ARRAYS = ("erp_level_db_m2",)   # NaN kept where point data "radiating" is 0
PVD_DIGITS = 10      # significant digits of a PVD time (a frequency [Hz], a time [s])
DEFAULT_SCALARS = "erp_level_db_m2"   # the array ParaView colours an ERP map by when opened


def part_ids(n_triangles: int, element_groups: dict) -> tuple:
    """(ids (n_tri,) int32, names): the part of every triangle, 1 + its index in ``names``, 0
    for none. Parts are the element groups ``part_*`` (generated meshes) or ``pid_*`` (a deck's
    shell properties), else all element groups; sorted by name, a later one wins a triangle in
    two. ``element_groups`` {name: triangle indices}."""
    names = sorted(g for g in element_groups if g.startswith(("part_", "pid_"))) or \
        sorted(element_groups)
    ids = np.zeros(int(n_triangles), dtype=np.int32)
    for k, name in enumerate(names):
        ids[np.asarray(element_groups[name], dtype=int)] = k + 1
    return ids, tuple(names)


def erp_level_db_m2(density_W_m2, reference_W_m2: float = 1e-12,
                    span_db: float = DB_MAP_RANGE) -> np.ndarray:
    """10 log10(e / e_ref) [dB re 1 pW/m²] of densities e [W/m²], floored at max − ``span_db``;
    a frame with no radiating power at all gives zeros (the files hold no −∞)."""
    e = np.asarray(density_W_m2, dtype=float)
    with np.errstate(divide="ignore"):
        level = 10.0 * np.log10(np.clip(e, 0.0, None) / reference_W_m2)
    finite = level[np.isfinite(level)]
    if finite.size == 0:
        return np.zeros_like(e)
    floor = finite.max() - span_db
    return np.where(np.isfinite(level), np.maximum(level, floor), floor)


def contact_point_values(n_points: int, nodes_a, nodes_b, values) -> np.ndarray:
    """(n_points,) array holding ``values`` (n_p,) at both nodes of each contact pair (node b = −1
    for ground is skipped); where pairs share a node the larger value wins; 0 elsewhere."""
    out = np.zeros(int(n_points))
    values = np.asarray(values, dtype=float)
    for nodes in (np.asarray(nodes_a, dtype=int), np.asarray(nodes_b, dtype=int)):
        keep = nodes >= 0
        np.maximum.at(out, nodes[keep], np.nan_to_num(values[keep]))
    return out


def period_samples(harmonics, n_samples: int) -> np.ndarray:
    """u(θ_j) = U0 + Σ_k U_kc cos kθ_j + U_ks sin kθ_j at θ_j = 2πj/n_samples; (2H+1, ...) → (n_samples, ...).

    Direct evaluation (any n_samples ≥ 1, unlike an FFT that needs n_samples ≥ 2H+1).
    """
    U = np.asarray(harmonics, dtype=float)
    H = (U.shape[0] - 1) // 2
    theta = 2.0 * np.pi * np.arange(int(n_samples)) / int(n_samples)
    k = np.arange(1, H + 1)
    phi = np.empty((theta.size, 2 * H + 1))
    phi[:, 0] = 1.0
    phi[:, 1::2] = np.cos(np.outer(theta, k))
    phi[:, 2::2] = np.sin(np.outer(theta, k))
    return np.tensordot(phi, U, axes=(1, 0))


EXCURSION_BLOCK = 256   # entries per block of :func:`excursion_amplitude` (its samples stay in cache)


def excursion_amplitude(harmonics, n_samples: int) -> np.ndarray:
    """max_j |u(θ_j) − U0| over θ_j = 2πj/n_samples of harmonics (2H+1, ...) → (...) [their unit].

    u(θ_j) − U0 = Σ_k U_kc cos kθ_j + U_ks sin kθ_j is the same sampling as
    :func:`period_samples` without the mean. With n_samples a multiple of 4 the grid maps onto
    itself under θ → −θ, θ → π ± θ, and split into the even/odd orders' cosine and sine parts
    (EC, ES, OC, OS at θ ∈ [0, π/2]) the four samples of an orbit are

        u(±θ) − U0 = (EC + OC) ± (ES + OS),      u(π ± θ) − U0 = (EC − OC) ± (ES − OS),

    so max_j |u(θ_j) − U0| = max over the n/4 + 1 samples of θ ∈ [0, π/2] of
    max(|EC + OC| + |ES + OS|, |EC − OC| + |ES − OS|): a quarter of the products of sampling
    the whole period. Evaluated block by block over the trailing entries (EXCURSION_BLOCK at a
    time: the samples stay in cache). Other n_samples: the whole grid. Equal to
    ``np.abs(period_samples(U, n) - U[0]).max(axis=0)`` to round-off.
    """
    U = np.asarray(harmonics, dtype=float)
    H = (U.shape[0] - 1) // 2
    if H == 0:                                            # a constant: no excursion
        return np.zeros(U.shape[1:])
    n = int(n_samples)
    if n % 4:
        return _excursion_whole_grid(U, n)
    theta = 2.0 * np.pi * np.arange(n // 4 + 1) / n                       # [0, π/2]
    odd, even = np.arange(1, H + 1, 2), np.arange(2, H + 1, 2)
    flat = U.reshape(U.shape[0], -1)
    # harmonic k: cos at row 2k − 1, sin at 2k → odd k: rows 1, 5, …; even k: rows 3, 7, …
    parts = [(np.cos(np.outer(theta, even)), flat[3::4]),
             (np.sin(np.outer(theta, even)), flat[4::4]),
             (np.cos(np.outer(theta, odd)), flat[1::4]),
             (np.sin(np.outer(theta, odd)), flat[2::4])]
    out = np.empty(flat.shape[1])
    for start in range(0, out.size, EXCURSION_BLOCK):                     # blocks of entries
        block = slice(start, start + EXCURSION_BLOCK)
        ec, es, oc, os_ = (phi @ rows[:, block] for phi, rows in parts)   # (n/4 + 1, ≤ block)
        plus, plus_sin = ec + oc, es + os_
        ec -= oc
        es -= os_
        for a in (plus, plus_sin, ec, es):
            np.abs(a, out=a)
        plus += plus_sin
        ec += es
        np.maximum(plus, ec, out=plus)
        plus.max(axis=0, out=out[block])
    return out.reshape(U.shape[1:])


def _excursion_whole_grid(U, n_samples):
    """:func:`excursion_amplitude` sampled over the whole period (n_samples not a multiple of 4)."""
    H = (U.shape[0] - 1) // 2
    theta = 2.0 * np.pi * np.arange(int(n_samples)) / int(n_samples)
    k = np.arange(1, H + 1)
    phi = np.empty((theta.size, 2 * H))
    phi[:, 0::2] = np.cos(np.outer(theta, k))
    phi[:, 1::2] = np.sin(np.outer(theta, k))
    oscillating = U[1:].reshape(2 * H, -1)                                   # (2H, m)
    out = np.empty(oscillating.shape[1])
    for start in range(0, out.size, EXCURSION_BLOCK):                     # blocks of entries
        block = phi @ oscillating[:, start:start + EXCURSION_BLOCK]           # (n_samples, ≤ block)
        np.abs(block, out=block)
        block.max(axis=0, out=out[start:start + EXCURSION_BLOCK])
    return out.reshape(U.shape[1:])


def _check_mesh(points, triangles):
    points = np.asarray(points, dtype=float)
    triangles = np.asarray(triangles, dtype=np.int64)
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError(f"points must be (n, 3) [m], got {points.shape}")
    if triangles.ndim != 2 or triangles.shape[1] != 3:
        raise ValueError(f"triangles must be (n_tri, 3), got {triangles.shape}")
    if triangles.size and (triangles.min() < 0 or triangles.max() >= points.shape[0]):
        raise ValueError("triangles refer to points that do not exist")
    return points, triangles


def write_erp_vtu(path, points, triangles, point_data: dict, field_data: dict | None = None,
                  active_vectors: str | None = None, parts=None) -> Path:
    """Write one VTU: ``points`` (n, 3) [m], ``triangles`` (n_tri, 3) int, ``point_data``
    {name: (n,) or (n, m) array}. Names are kept as given (see the module docstring for the
    standard ERP names, built by :func:`erp_point_data`). Integer arrays stay integer (int32),
    booleans become int8; non-finite float values (NaN/inf, e.g. of a point that did not
    converge) are written as 0 with a RuntimeWarning, so files never hold NaN — except in the
    :data:`MASKED_ARRAYS` at points whose ``radiating`` is 0 (off the ERP surface).
    ``parts`` (ids (n_tri,), names) of :func:`part_ids`: cell data ``part_id`` and field data
    ``part_names``. ``erp_level_db_m2``, when given, is the active scalars (what ParaView colours
    by first).
    ``field_data`` {name: scalar | array | str} is stored as VTK field data (e.g. the frequency);
    ``active_vectors`` names a (n, 3) array ParaView offers first (e.g. to Warp By Vector).
    Written by VTK's XML writer, appended raw binary with LZ4 compression. Returns the path.
    """
    import pyvista as pv
    from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridWriter

    points, triangles = _check_mesh(points, triangles)
    grid = pv.UnstructuredGrid({pv.CellType.TRIANGLE: triangles}, points)
    off_surface = (np.asarray(point_data["radiating"]) == 0) if "radiating" in point_data \
        else np.zeros(points.shape[0], bool)
    for name, values in point_data.items():
        arr = np.asarray(values)
        if arr.shape[:1] != (points.shape[0],) or arr.ndim > 2:
            raise ValueError(f"point_data[{name!r}] must be (n,) or (n, m) with n = "
                             f"{points.shape[0]}, got {arr.shape}")
        if arr.dtype.kind == "b":
            arr = arr.astype(np.int8)
        elif arr.dtype.kind in "iu":
            arr = np.asarray(arr, dtype=np.int32)           # (no copy when already int32)
        else:
            arr = np.asarray(arr, dtype=np.float64)         # (no copy when already float)
            bad = ~np.isfinite(arr)
            if name in MASKED_ARRAYS:
                bad &= ~(off_surface & np.isnan(arr))
            if np.any(bad):  # e.g. a point that did not converge: keep the run's files readable
                warnings.warn(f"point_data[{name!r}]: {int(bad.sum())} non-finite values written as 0",
                              RuntimeWarning, stacklevel=2)
                arr = np.where(bad, 0.0, arr)
        grid.point_data[str(name)] = arr
    if parts is not None:
        ids, names = parts
        if np.shape(ids) != (triangles.shape[0],):
            raise ValueError(f"part ids must be (n_tri,) = ({triangles.shape[0]},), got "
                             f"{np.shape(ids)}")
        grid.cell_data["part_id"] = np.asarray(ids, dtype=np.int32)
        grid.field_data["part_names"] = [",".join(names)]
    if DEFAULT_SCALARS in grid.point_data:
        grid.point_data.active_scalars_name = DEFAULT_SCALARS
    for name, value in (field_data or {}).items():
        grid.field_data[str(name)] = [value] if isinstance(value, str) else np.atleast_1d(value)
    if active_vectors is not None:
        grid.point_data.active_vectors_name = active_vectors
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    writer = vtkXMLUnstructuredGridWriter()
    writer.SetInputData(grid)
    writer.SetFileName(str(path))
    writer.SetDataModeToAppended()
    writer.EncodeAppendedDataOff()          # raw bytes, no base64
    writer.SetCompressorTypeToLZ4()
    if not _write_quietly(writer):
        raise _write_error(path, writer.GetErrorCode())
    return path


def _write_quietly(writer) -> bool:
    """``writer.Write()`` with VTK's own error output off (its log line and the error window
    that pyvista forwards to logging: 20 lines for a full disk); the failure is raised by the
    caller as one OSError."""
    from vtkmodules.vtkCommonCore import vtkObject

    display = vtkObject.GetGlobalWarningDisplay()
    vtkObject.GlobalWarningDisplayOff()
    try:
        return bool(writer.Write())
    finally:
        vtkObject.SetGlobalWarningDisplay(display)


def _write_error(path: Path, code: int) -> OSError:
    """The OSError of a failed VTK write of ``path`` with the errno of its cause: VTK's error
    code is the system's errno below vtkErrorCode.FirstVTKErrorCode (ENOSPC for a full disk);
    its own OutOfDiskSpaceError is ENOSPC; else the error that opening the file for appending
    gives (read-only, permission), else EIO."""
    from vtkmodules.vtkCommonMisc import vtkErrorCode

    number = code if 0 < code < vtkErrorCode.FirstVTKErrorCode else (
        errno.ENOSPC if code == vtkErrorCode.OutOfDiskSpaceError else None)
    if number is None:
        try:
            with open(path, "ab"):
                number = errno.EIO
        except OSError as exc:
            number = exc.errno or errno.EIO
    return OSError(number, os.strerror(number), str(path))


def write_pvd(path, entries) -> Path:
    """Write a ParaView collection: ``entries`` = [(time_or_frequency, vtu_filename), …].

    Filenames are stored relative to the PVD's directory (they should live in it or below).
    ParaView shows the value as "time": a phase/time for animations, a frequency [Hz] for sweeps;
    written with :data:`PVD_DIGITS` significant digits (more only if that would merge two).
    """
    path = Path(path)
    entries = list(entries)
    values = [float(value) for value, _ in entries]
    digits = PVD_DIGITS
    while digits < 17 and (len({f"{v:.{digits}g}" for v in values}) < len(set(values))):
        digits += 1
    lines = ['<?xml version="1.0"?>',
             '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
             "  <Collection>"]
    for value, (_, filename) in zip(values, entries):
        rel = os.path.relpath(Path(path.parent, filename), path.parent).replace(os.sep, "/")
        lines.append(f'    <DataSet timestep="{value:.{digits}g}" group="" part="0" '
                     f"file={quoteattr(rel)}/>")
    lines += ["  </Collection>", "</VTKFile>", ""]
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines), encoding="utf-8")
    return path


def contact_markers(n_points: int, contact_nodes) -> np.ndarray:
    """(n_points,) int32 marker: 0 everywhere, c+1 on the nodes ``contact_nodes[c]`` of contact c."""
    marker = np.zeros(int(n_points), dtype=np.int32)
    for c, nodes in enumerate(contact_nodes):
        marker[np.asarray(nodes, dtype=int)] = c + 1
    return marker


def radiating_fields(erp, normal_displacement, omega: float) -> np.ndarray:
    """(H + 2, n_r) the per-point map fields of the radiating nodes that :func:`erp_point_data`
    scatters into the mesh: rows 0 … H−1 the ERP density e_k of ``erp`` [W/m²], H the normal
    velocity amplitude √(Σ_k (kω)² (w_kc² + w_ks²)) [m/s], H+1 the normal excursion
    max_θ |w(θ) − w0| [m] (:func:`excursion_amplitude`, max(64, 16H) samples) of the normal
    displacement harmonics W (2H+1, n_r) [m] at ω [rad/s]. Computed where the point's W is (a
    record worker), it replaces W and the density in what travels to the map writer: 17 rows
    instead of 46 at H = 15."""
    density = np.asarray(erp.density, dtype=float)
    W = np.asarray(normal_displacement, dtype=float)
    H = density.shape[0]
    fields = np.empty((H + 2, density.shape[1]))
    fields[:H] = density
    # √(Σ_k |v_k|²) = √(Σ_k (kω)² (w_kc² + w_ks²))  [m/s]  (sarfe.erp.normal_velocity_amplitudes)
    speed_sq = (np.arange(1, H + 1) * float(omega)) ** 2
    fields[H] = np.sqrt(speed_sq @ (W[1::2] ** 2 + W[2::2] ** 2))
    fields[H + 1] = excursion_amplitude(W, max(64, 16 * H))
    return fields


def erp_point_data(n_points: int, erp, normal_displacement, omega: float, displacement=None,
                   radiating_nodes=None, contact_marker=None, node_ids=None,
                   contact_force=None, contact_displacement=None, fields=None) -> dict:
    """The standard ERP arrays (module docstring) for :func:`write_erp_vtu`.

    n_points : number of mesh points n.
    erp : :class:`sarfe.erp.ErpResult` of the radiating nodes (density (H, n_r); only its
        density_total and reference_power when ``fields`` are given).
    normal_displacement : (2H+1, n_r) [m] harmonics W used for ``erp`` (unused with ``fields``).
    omega : [rad/s].
    displacement : (2H+1, n, 3) [m] nodal translation harmonics of all points, or None (then
        ``displacement_amplitude_m`` is all zeros; ``normal_displacement_amplitude_m`` is always set).
    radiating_nodes : (n_r,) point indices of the radiating nodes (default: all n points).
    contact_marker : (n,) int, e.g. from :func:`contact_markers` (default zeros).
    node_ids : (n,) int deck ids of the points, written as ``node_id`` (default: not written).
    contact_force, contact_displacement : optional (n,) [N], [m] from :func:`contact_point_values`.
    fields : (H + 2, n_r) :func:`radiating_fields` of (erp, W, ω) when computed beforehand.
    """
    n = int(n_points)
    nodes = np.arange(n) if radiating_nodes is None else np.asarray(radiating_nodes, dtype=int)
    if fields is None:
        fields = radiating_fields(erp, normal_displacement, omega)
    fields = np.asarray(fields, dtype=float)
    if fields.shape[1] != nodes.size:
        raise ValueError(f"erp has {fields.shape[1]} radiating nodes, radiating_nodes {nodes.size}")
    H = fields.shape[0] - 2
    if H != np.size(erp.frequencies_hz):
        raise ValueError(f"fields must be (H + 2, n_r) with H = {np.size(erp.frequencies_hz)} "
                         f"(radiating_fields), got {fields.shape}")
    # every radiating-node field scattered into one (H + 3, n) block, zero at the other points:
    # rows 0 … H−1 e_k, then Σ_k e_k, the velocity amplitude, the normal excursion
    full = np.zeros((H + 3, n))
    full[:H, nodes] = fields[:H]
    full[H, nodes] = erp.density_total
    full[H + 1:, nodes] = fields[H:]
    radiating = np.zeros(n, dtype=np.int8)
    radiating[nodes] = 1
    level = erp_level_db_m2(full[H], float(getattr(erp, "reference_power", 1e-12)))
    level[radiating == 0] = np.nan          # off the ERP surface: no level, not a silent one
    data = {"erp_density_W_m2": full[H], "erp_level_db_m2": level, "radiating": radiating}
    for k in range(H):
        data[f"erp_density_h{k + 1}_W_m2"] = full[k]
    data["normal_velocity_amplitude_m_s"] = full[H + 1]
    data["normal_displacement_amplitude_m"] = full[H + 2]
    if displacement is None:
        data["displacement_amplitude_m"] = np.zeros((n, 3))
    else:
        U = np.asarray(displacement, dtype=float)
        if U.shape[1:] != (n, 3):
            raise ValueError(f"displacement must be (2H+1, {n}, 3), got {U.shape}")
        H_u = (U.shape[0] - 1) // 2
        data["displacement_amplitude_m"] = excursion_amplitude(U, max(64, 16 * H_u))
    data["contact_marker"] = (np.zeros(n, dtype=np.int32) if contact_marker is None
                              else np.asarray(contact_marker, dtype=np.int32))
    if node_ids is not None:
        data["node_id"] = np.asarray(node_ids, dtype=np.int64)
    if contact_force is not None:
        data["contact_peak_force_N"] = np.asarray(contact_force, dtype=float)
    if contact_displacement is not None:
        data["contact_relative_displacement_m"] = np.asarray(contact_displacement, dtype=float)
    return data


def write_erp_sweep(directory, points, triangles, point_data_per_frequency, frequencies_hz,
                    basename: str = "erp", workers: int = 1, parts=None) -> Path:
    """One VTU per frequency point (``<basename>_0000.vtu`` …, in sweep order) plus
    ``<basename>.pvd``. Each VTU carries field data ``frequency_hz`` and ``point_index`` (and
    ``parts``, :func:`part_ids`, as cell data ``part_id``).

    ``point_data_per_frequency``: the point data of each frequency — a sequence of dicts, or a
    function j → dict called when file j is written (so the arrays of all points never coexist).
    ``workers`` > 1 writes the files on that many processes forked from this one
    (:func:`sarfe.util.workers.map_points`; the function's inputs are shared, each worker builds and
    writes whole files, nothing but None comes back): the same files, each written once.

    The PVD "time" is the frequency [Hz] when all frequencies differ; a continuation that turns
    back through a fold visits a frequency more than once, and then the time is the point index
    0, 1, … (ParaView sorts and merges equal times). Returns the PVD path.
    """
    return start_erp_sweep(directory, points, triangles, point_data_per_frequency,
                           frequencies_hz, basename, workers, parts=parts).finish()


class ErpSweepWriter:
    """The maps of :func:`start_erp_sweep` being written: ``finish()`` waits for them and writes
    the PVD (returns its path), ``cancel()`` stops the workers."""

    def __init__(self, pending, pvd, entries):
        self.pending, self.pvd, self.entries = pending, pvd, entries

    def finish(self) -> Path:
        self.pending.result()
        return write_pvd(self.pvd, self.entries)

    def cancel(self):
        self.pending.cancel()


def start_erp_sweep(directory, points, triangles, point_data_per_frequency, frequencies_hz,
                    basename: str = "erp", workers: int = 1, parts=None) -> ErpSweepWriter:
    """:func:`write_erp_sweep` started on ``workers`` processes without waiting for them: this
    process writes the run's other files meanwhile and calls ``finish()`` (with ``workers`` ≤ 1
    the maps are written by ``finish()``)."""
    directory = Path(directory)
    frequencies = np.asarray(frequencies_hz, dtype=float)
    if callable(point_data_per_frequency):
        data_of = point_data_per_frequency
    else:
        data = list(point_data_per_frequency)
        if len(data) != frequencies.size:
            raise ValueError(f"{len(data)} point-data sets for {frequencies.size} frequencies")
        data_of = data.__getitem__
    names = [f"{basename}_{j:04d}.vtu" for j in range(frequencies.size)]

    def write(j):
        write_erp_vtu(directory / names[j], points, triangles, data_of(j),
                      field_data={"frequency_hz": float(frequencies[j]), "point_index": j},
                      parts=parts)

    import pyvista  # noqa: F401  (imported here once, inherited by forked workers)
    import vtkmodules.vtkIOXML  # noqa: F401

    directory.mkdir(parents=True, exist_ok=True)
    pending = start_map(write, range(frequencies.size), workers)
    unique = np.unique(frequencies).size == frequencies.size
    entries = [(f if unique else j, name) for j, (f, name) in enumerate(zip(frequencies, names))]
    return ErpSweepWriter(pending, directory / f"{basename}.pvd", entries)


def write_deflection_animation(directory, points, triangles, displacement_harmonics,
                               n_frames: int = 24, omega: float | None = None,
                               basename: str = "deflection", point_data=None) -> Path:
    """Operating deflection over one period as a PVD time series that ParaView plays.

    Frame j (``<basename>_<jjj>.vtu``) holds u(θ_j) = U0 + Σ_k U_kc cos kθ_j + U_ks sin kθ_j,
    θ_j = 2πj/n_frames, as the point vector ``displacement_m`` [m] (apply *Warp By Vector*; the
    coordinates stay undeformed), its norm ``displacement_magnitude_m`` [m] and the field value
    ``phase_rad`` = θ_j [rad]. The PVD time is
    t_j = θ_j/ω [s] when ``omega`` [rad/s] is given, else the period fraction j/n_frames.
    ``displacement_harmonics`` is (2H+1, n, 3) [m]; ``point_data`` adds constant arrays to every
    frame (e.g. ``contact_marker``). Returns ``<directory>/<basename>.pvd``.
    """
    points, triangles = _check_mesh(points, triangles)
    U = np.asarray(displacement_harmonics, dtype=float)
    if U.ndim != 3 or U.shape[1:] != (points.shape[0], 3) or U.shape[0] % 2 == 0:
        raise ValueError(f"displacement_harmonics must be (2H+1, {points.shape[0]}, 3), got {U.shape}")
    if int(n_frames) < 2:
        raise ValueError("n_frames must be >= 2")
    frames = period_samples(U, int(n_frames))                              # (n_frames, n, 3)
    directory = Path(directory)
    entries = []
    for j, u in enumerate(frames):
        name = f"{basename}_{j:03d}.vtu"
        data = dict(point_data or {})
        data["displacement_m"] = u
        data["displacement_magnitude_m"] = np.linalg.norm(u, axis=1)
        phase_rad = 2.0 * np.pi * j / int(n_frames)
        write_erp_vtu(directory / name, points, triangles, data, active_vectors="displacement_m",
                      field_data={"phase_rad": phase_rad})
        entries.append((phase_rad / omega if omega else j / int(n_frames), name))
    return write_pvd(directory / f"{basename}.pvd", entries)
