r"""``response.h5``: everything needed to re-plot a run without re-solving.

Layout (n_f frequency points, H harmonics, N samples per period, n_rows contact rows r = G u,
n_c contacts, n_e excitation DOFs, n_r radiating nodes). Harmonic axes follow the sarfe Fourier
convention (``/`` attribute ``fourier_convention``): index 0 = static term u0, 2k−1 = cos kθ,
2k = sin kθ, θ = ωt; time axes hold the record's N_rec samples θ_j = 2πj/N_rec, j = 0 … N_rec−1
(N_rec = :func:`record_samples`, the ``record_samples_per_period`` attribute; not the solve's N).

    /                               attrs: format="sarfe-response", format_version=3, harmonics=H,
                                    samples_per_period=N (the solve's AFT samples),
                                    record_samples_per_period=N_rec, record_decimation=N/N_rec,
                                    fourier_convention, units, sarfe_version,
                                    created_utc, + caller attributes (case name, model key, …)
    /frequency_hz                   (n_f,)  excitation (fundamental) frequency ω/2π [Hz]
    /omega_rad_s                    (n_f,)  ω [rad/s]
    /status/converged               (n_f,)  int8, 1 = Newton converged
    /status/stable                  (n_f,)  int8, 1 stable, 0 unstable, −1 not assessed (Floquet)
    /status/floquet_exponent_1_s    (n_f,)  leading real part of the Floquet exponents [1/s] (NaN = n/a)
    /status/iterations              (n_f,)  int, Newton iterations
    /status/residual_norm           (n_f,)  relative residual (to the excitation norm)
    /status/friction_passes         (n_f,)  int
    /status/reason                  (n_f,)  str, solver message
    /contacts/names, kind           (n_c,)  str
    /contacts/normal_row            (n_c,)  int, row of r holding the normal gap closure w (−1 none)
    /contacts/tangent_rows          (n_c, 2) int, rows of the tangential displacements (−1 none)
    /contacts/gap_m, normal_stiffness_N_m, tangential_stiffness_N_m, friction_coefficient,
              normal_load_N         (n_c,)
    /contacts/displacement_m        (n_f, 2H+1, n_rows) harmonics of the relative displacements r [m]
    /contacts/force_N               (n_f, 2H+1, n_rows) harmonics of the contact forces λ [N]
    /contacts/force_time_N          (n_f, N_rec, n_rows) λ(θ_j) over one period [N]: the solve's
                                    AFT samples, every (N/N_rec)-th (a decimation, exact values)
    /contacts/force_peak_N          (n_f, N_rec, n_rows) per bin j (the N/N_rec AFT samples from
                                    θ_j on) the force of largest magnitude, signed [N]: its
                                    maximum over j is the full-N peak (impact) force exactly
                                    (N_rec = N: a hard link to force_time_N)
    /contacts/state                 (n_f, N_rec, n_c) int8 per bin the highest state reached:
                                    0 open throughout, 1 closed/stick at some time, 2 slipped
    /excitation/dofs                (n_e,)  kept-DOF indices that carry excitation
    /excitation/force_N             (2H+1, n_e) force harmonics f̃_e at those DOFs [N]
    /excitation/displacement_m      (n_f, 2H+1, n_e) response harmonics at those DOFs [m]
    /reduction/boundary_dofs        (n_b,)  physical DOFs kept as Craig–Bampton boundary DOFs
    /reduction/mode_frequencies_hz  (n_m,)  fixed-interface mode frequencies [Hz]
    /displacement_m                 (n_f, 2H+1, n_dof) all kept DOFs [m] (only if requested)
    /erp/radiating_nodes            (n_r,)  mesh point indices of the radiating nodes
    /erp/harmonic_frequencies_hz    (n_f, H) k ω/2π [Hz]
    /erp/power_W, level_db, level_a_db             (n_f, H)   per harmonic [W], [dB re 1 pW], [dB(A)]
    /erp/power_total_W, level_total_db, level_total_a_db  (n_f,)
    /erp/level_dba, level_total_dba                 the *_a_db datasets again (hard links), named
                                                    by their unit dB(A)
    /erp/density_total_W_m2         (n_m, n_r) ERP density summed over harmonics [W/m²] at the
                                    points /erp/density_point_index (n_m,) (all n_f points, or
                                    the mapped ones of an FE sweep: the record stays ∝ points ×
                                    contacts × H, not × mesh; format_version 2)
    /erp/density_W_m2               (n_f, H, n_r) per harmonic (only if requested)
    /<group>/<name>                 caller-supplied extra groups (e.g. /linear/... of the linear
                                    baseline), each array with its own ``units`` attribute if given

Levels of zero power are stored as −inf. Datasets with a unit carry a ``units`` attribute.

**The record's time grid** (issue 30 item 3: the file ∝ points × contacts × H, never × N). A
sweep raises N for hard contacts up to ``sarfe.hbm.continuation.most_samples`` (N × rows ≤ 2^17:
N = 32768 for a stiff lumped rattle), which would make the time histories — not the harmonics —
the bulk of the file (670 MB for 1280 points). The time axes therefore hold N_rec =
:func:`record_samples` (H, N, N_case) = min(N, max(N_case, 64, 2^⌈log₂ 16H⌉)) samples: the
case's own N before the sweep raised it (``solver.samples_per_period``; a run that did not raise
N stores exactly what it solved), and at least the solver's default N for H
(``sarfe.case.config.default_samples_per_period``): 16 samples per period of the highest
harmonic, 8× the 2H+1 that the harmonics need. Above it, the stored force is a *decimation* (every (N/N_rec)-th AFT sample), not a
synthesis of the harmonics: a synthesis would only repeat /contacts/force_N (stored exactly) with
Gibbs ripple (negative "contact forces" while open), while the AFT samples are the nonlinear law's
own values. What a decimation misses — the short impact peak between two stored samples, a
contact closing for less than a bin — is kept by the per-bin extremes force_peak_N and state.
What a user loses: the force's shape inside a bin (N/N_rec AFT samples), i.e. the contact's
time resolution beyond 16 samples per period of the H-th harmonic; not the harmonics, not the
peak force, not whether/when (to a bin, 2π/N_rec) the contact closed or slipped.
"""
from __future__ import annotations

import datetime as _dt
from pathlib import Path

import h5py
import numpy as np

from sarfe import __version__
from sarfe.results.record_grid import (COMPRESS_MIN_ENTRIES, RECORD_MIN_SAMPLES,
                                       RECORD_SAMPLES_PER_HARMONIC, record_histories,
                                       record_samples)

__all__ = ["write_response_h5", "read_response_h5", "record_samples", "record_histories",
           "FOURIER_CONVENTION", "FORMAT_VERSION", "RECORD_SAMPLES_PER_HARMONIC",
           "RECORD_MIN_SAMPLES"]

FORMAT_VERSION = 3      # 2: /erp/density_total_W_m2 at /erp/density_point_index (issue 30)
#                         3: contact time histories at N_rec ≤ N, force_peak_N (issue 30 item 3)
FOURIER_CONVENTION = (
    "u(theta) = u0 + sum_{k=1..H} (u_kc cos k theta + u_ks sin k theta), theta = omega t; "
    "harmonic axis of length 2H+1 stores [u0, u1c, u1s, ..., uHc, uHs] (u0 not halved); "
    "time axis of length N_rec (attribute record_samples_per_period) stores "
    "theta_j = 2 pi j / N_rec, j = 0..N_rec-1"
)
UNITS = ("SI: m, N, s, Hz, rad/s, W, W/m^2; levels in dB re 1e-12 W, A-weighted per IEC 61672-1; "
         "dataset suffixes _m, _N, _hz, _rad_s, _W, _W_m2, _db, _1_s give the unit")

_STR = h5py.string_dtype("utf-8")




def _put(group, name, data, units=None, compress=False, text=False):
    """One dataset (``compress``: gzip when it has COMPRESS_MIN_ENTRIES entries or more — for
    arrays that shrink: contact forces over the period (zeros while open), contact states; a
    smooth field of doubles such as the ERP density shrinks ~13 % for 80× the write time)."""
    arr = np.asarray(data, dtype=str) if text else np.asarray(data)
    if arr.dtype.kind in "OUS":
        ds = group.create_dataset(name, data=np.asarray([str(s) for s in arr.ravel()], dtype=object)
                                  .reshape(arr.shape), dtype=_STR)
    elif compress and arr.size >= COMPRESS_MIN_ENTRIES:
        ds = group.create_dataset(name, data=arr, compression="gzip", compression_opts=4,
                                  shuffle=True)
    else:
        ds = group.create_dataset(name, data=arr)
    if units:
        ds.attrs["units"] = units
    return ds


def _stack(solutions, name, dtype=float):
    return np.stack([np.asarray(getattr(s, name), dtype=dtype) for s in solutions])


def write_response_h5(
    path,
    solutions,
    *,
    contacts=None,
    excitation=None,
    excitation_dofs=None,
    boundary_dofs=None,
    mode_frequencies_hz=None,
    erp=None,
    radiating_nodes=None,
    store_displacement: bool = False,
    store_erp_density_per_harmonic: bool = False,
    density_points=None,
    base_samples_per_period: int | None = None,
    extra_groups: dict | None = None,
    attributes: dict | None = None,
) -> Path:
    """Write the response of a sweep (or a single point) to ``path`` (layout: module docstring).

    Parameters
    ----------
    solutions : sequence of :class:`sarfe.hbm.HarmonicSolution` (same H and N), one per frequency
        point, in sweep order. Read attributes: omega, harmonics, samples_per_period, displacement,
        contact_displacement, contact_force, contact_force_time, contact_state, converged, reason,
        iterations, residual_norm, friction_passes, stable, floquet_exponent (missing → defaults).
    contacts : :class:`sarfe.hbm.contacts.ContactSet` or None (contact metadata).
    excitation : (2H+1, n_dof) [N] force harmonics on the kept DOFs, or None.
    excitation_dofs : DOF indices to store (default: columns of ``excitation`` that are nonzero).
    boundary_dofs, mode_frequencies_hz : reduction metadata (``ReducedModel`` fields) or None.
    erp : sequence of :class:`sarfe.erp.ErpResult` (one per solution) or None.
    radiating_nodes : (n_r,) mesh point indices the ERP densities refer to.
    store_displacement : also store all kept DOFs' harmonics (can be large).
    store_erp_density_per_harmonic : also store /erp/density_W_m2 (n_f, H, n_r).
    density_points : indices of the points whose ERP density is stored (default: all).
    base_samples_per_period : the case's N before a sweep raised it (bounds the stored time grid,
        :func:`record_samples`; None: only H does).
    extra_groups : {group: {name: array | (array, units)}}, e.g. the linear baseline.
    attributes : extra root attributes (str/number), e.g. {"case": name, "model_key": key}.
    """
    solutions = list(solutions)
    if not solutions:
        raise ValueError("solutions is empty: nothing to write")
    H = {int(s.harmonics) for s in solutions}
    N = {int(s.samples_per_period) for s in solutions}
    if len(H) != 1 or len(N) != 1:
        raise ValueError(f"all solutions must share H and N, got H={sorted(H)}, N={sorted(N)}")
    H, N = H.pop(), N.pop()
    N_rec = record_samples(H, N, base_samples_per_period)
    omega = np.array([float(s.omega) for s in solutions])
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with h5py.File(path, "w") as f:
        f.attrs["format"] = "sarfe-response"
        f.attrs["format_version"] = FORMAT_VERSION
        f.attrs["harmonics"] = H
        f.attrs["samples_per_period"] = N
        f.attrs["record_samples_per_period"] = N_rec
        f.attrs["record_decimation"] = N // N_rec
        f.attrs["fourier_convention"] = FOURIER_CONVENTION
        f.attrs["units"] = UNITS
        f.attrs["sarfe_version"] = __version__
        f.attrs["created_utc"] = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
        for key, value in (attributes or {}).items():
            f.attrs[str(key)] = value if isinstance(value, (int, float, np.number)) else str(value)
        _put(f, "frequency_hz", omega / (2 * np.pi), "Hz")
        _put(f, "omega_rad_s", omega, "rad/s")

        status = f.create_group("status")
        _put(status, "converged", [int(bool(getattr(s, "converged", True))) for s in solutions]
             ).attrs["dtype_note"] = "1 converged, 0 not"
        stable = [getattr(s, "stable", None) for s in solutions]
        _put(status, "stable", np.array([-1 if v is None else int(bool(v)) for v in stable], np.int8)
             ).attrs["dtype_note"] = "1 stable, 0 unstable, -1 not assessed"
        _put(status, "floquet_exponent_1_s",
             [np.nan if getattr(s, "floquet_exponent", None) is None else float(s.floquet_exponent)
              for s in solutions], "1/s")
        _put(status, "iterations", [int(getattr(s, "iterations", 0)) for s in solutions])
        _put(status, "residual_norm", [float(getattr(s, "residual_norm", np.nan)) for s in solutions])
        _put(status, "friction_passes", [int(getattr(s, "friction_passes", 0)) for s in solutions])
        _put(status, "reason", [str(getattr(s, "reason", "")) for s in solutions], text=True)

        group = f.create_group("contacts")
        if contacts is not None:
            _put(group, "names", list(contacts.names), text=True)
            _put(group, "kind", [str(k) for k in contacts.kind], text=True)
            _put(group, "normal_row", np.asarray(contacts.normal_row, dtype=np.int64))
            _put(group, "tangent_rows", np.asarray(contacts.tangent_rows, dtype=np.int64))
            _put(group, "gap_m", contacts.gap, "m")
            _put(group, "normal_stiffness_N_m", contacts.normal_stiffness, "N/m")
            _put(group, "tangential_stiffness_N_m", contacts.tangential_stiffness, "N/m")
            _put(group, "friction_coefficient", contacts.friction_coefficient, "1")
            _put(group, "normal_load_N", contacts.normal_load, "N")
        if getattr(solutions[0], "contact_displacement", None) is not None:
            _put(group, "displacement_m", _stack(solutions, "contact_displacement"), "m", True)
        if getattr(solutions[0], "contact_force", None) is not None:
            _put(group, "force_N", _stack(solutions, "contact_force"), "N", True)
        # reduced point by point: n_f × N × rows never held at once (module docstring)
        histories = [record_histories(getattr(s, "contact_force_time", None),
                                      getattr(s, "contact_state", None), N_rec) for s in solutions]
        if histories[0][0] is not None:
            _put(group, "force_time_N", np.stack([h[0] for h in histories]), "N", True
                 ).attrs["sampling"] = f"every {N // N_rec}-th of the solve's N = {N} AFT samples"
            if N_rec == N:     # bins of one sample: the same data (a hard link, no bytes)
                group["force_peak_N"] = group["force_time_N"]
            else:
                _put(group, "force_peak_N", np.stack([h[1] for h in histories]), "N", True
                     ).attrs["sampling"] = (f"per bin of {N // N_rec} AFT samples: the force of "
                                            "largest magnitude (signed)")
        if histories[0][2] is not None:
            ds = _put(group, "state", np.stack([h[2] for h in histories]), None, True)
            ds.attrs["dtype_note"] = "0 open/separated, 1 closed or stick, 2 slip"
            ds.attrs["sampling"] = (f"per bin of {N // N_rec} AFT samples: the highest state "
                                    "reached in the bin")

        group = f.create_group("excitation")
        if excitation is not None or excitation_dofs is not None:
            if excitation_dofs is None:
                excitation_dofs = np.flatnonzero(np.any(np.asarray(excitation) != 0, axis=0))
            dofs = np.asarray(excitation_dofs, dtype=np.int64)
            _put(group, "dofs", dofs)
            if excitation is not None:
                _put(group, "force_N", np.asarray(excitation, dtype=float)[:, dofs], "N")
            if getattr(solutions[0], "displacement", None) is not None:
                _put(group, "displacement_m",
                     np.stack([np.asarray(s.displacement, dtype=float)[:, dofs] for s in solutions]),
                     "m")
        if store_displacement:
            _put(f, "displacement_m", _stack(solutions, "displacement"), "m", True)

        group = f.create_group("reduction")
        if boundary_dofs is not None:
            _put(group, "boundary_dofs", np.asarray(boundary_dofs, dtype=np.int64))
        if mode_frequencies_hz is not None:
            _put(group, "mode_frequencies_hz", np.asarray(mode_frequencies_hz, dtype=float), "Hz")

        if erp is not None:
            erp = list(erp)
            if len(erp) != len(solutions):
                raise ValueError(f"erp has {len(erp)} entries for {len(solutions)} solutions")
            group = f.create_group("erp")
            if radiating_nodes is not None:
                _put(group, "radiating_nodes", np.asarray(radiating_nodes, dtype=np.int64))
            _put(group, "harmonic_frequencies_hz", _stack(erp, "frequencies_hz"), "Hz")
            _put(group, "power_W", _stack(erp, "power"), "W")
            _put(group, "level_db", _stack(erp, "level_db"), "dB re 1e-12 W")
            _put(group, "level_a_db", _stack(erp, "level_a_db"), "dB(A) re 1e-12 W")
            _put(group, "power_total_W", [e.power_total for e in erp], "W")
            _put(group, "level_total_db", [e.level_total_db for e in erp], "dB re 1e-12 W")
            _put(group, "level_total_a_db", [e.level_total_a_db for e in erp], "dB(A) re 1e-12 W")
            # the same datasets under names ending in their unit (hard links: one copy of the data;
            # the *_a_db names stay for existing scripts)
            group["level_dba"], group["level_total_dba"] = group["level_a_db"], group["level_total_a_db"]
            chosen = np.arange(len(erp)) if density_points is None else np.asarray(
                density_points, dtype=np.int64)
            _put(group, "density_point_index", chosen)
            _put(group, "density_total_W_m2", _stack([erp[int(j)] for j in chosen],
                                                     "density_total"), "W/m^2")
            if store_erp_density_per_harmonic:
                _put(group, "density_W_m2", _stack(erp, "density"), "W/m^2")

        for gname, members in (extra_groups or {}).items():
            group = f.require_group(gname)
            for name, value in members.items():
                units = None
                if isinstance(value, tuple) and len(value) == 2 and isinstance(value[1], str):
                    value, units = value
                _put(group, name, value, units, True)
    return path


def read_response_h5(path) -> dict:
    """Read a ``response.h5`` back into nested dicts of numpy arrays.

    Groups become dicts, datasets arrays (strings decoded to ``str`` arrays), and the root
    attributes are under ``"attrs"`` (e.g. ``data["attrs"]["harmonics"]``,
    ``data["contacts"]["force_time_N"]``).
    """
    def load(group):
        out = {}
        for name, item in group.items():
            if isinstance(item, h5py.Group):
                out[name] = load(item)
            elif h5py.check_string_dtype(item.dtype) is not None:
                out[name] = np.asarray(item.asstr()[()], dtype=str)
            else:
                out[name] = item[()]
        return out

    with h5py.File(path, "r") as f:
        data = load(f)
        data["attrs"] = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()}
    return data
