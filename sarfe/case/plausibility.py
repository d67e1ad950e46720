"""Numbers a case file can hold that the schema cannot judge: non-finite values anywhere, and
signs and orders of magnitude that betray a unit mistake (moduli in MPa/GPa, densities in t/mm³,
element sizes in mm, frequencies beyond hearing). The bounds are shared by the case keys, mesh
files and decks (:mod:`sarfe.pipeline.model.case_mesh`, :mod:`sarfe.pipeline.model.deck_checks`).

    check_finite(data, source, lines)    CaseError at the first NaN or ±inf
    check_plausible(case, data)          CaseError at the first implausible value, naming its unit
"""
from __future__ import annotations

import math

from sarfe.case.errors import CaseError, line_of


def check_finite(data, source=None, lines=None, path=()):
    """Raise CaseError at the first NaN or ±inf anywhere in the case (YAML ``.nan``, ``.inf``):
    no key of a case takes a non-finite number, and the schema's range checks let NaN through."""
    if isinstance(data, float) and not math.isfinite(data):
        text = ".nan" if math.isnan(data) else ("-.inf" if data < 0 else ".inf")
        raise CaseError(f"must be a finite number, got {text}", path, source,
                        line_of(lines or {}, path))
    if isinstance(data, dict):
        for key, value in data.items():
            check_finite(value, source, lines, path + (key,))
    elif isinstance(data, list):
        for index, value in enumerate(data):
            check_finite(value, source, lines, path + (index,))


# Bounds outside which a value is a unit mistake rather than a material or a load; each message
# says which unit the key is in.
AUDIBLE_LIMIT_HZ = 20e3
# unit plausibility bounds, shared by the case keys, mesh files and decks (module docstring):
# below them a value in SI is almost surely in another unit system
MIN_E_PA, MIN_RHO_KG_M3, MAX_MESH_SIZE_M = 1e5, 1.0, 1.0
SPAN_RANGE_M = (5e-3, 20.0)       # a trim part's overall size [m]
THICKNESS_RANGE = (1e-4, 0.1)     # a shell's thickness / the model size


def check_plausible(case, data):
    """Signs and orders of magnitude that the schema cannot judge (negative excitation amplitudes,
    moduli in MPa/GPa, densities in t/mm³ or g/cm³, frequencies beyond hearing)."""
    exc = data["excitation"]
    for i, load in enumerate(exc.get("forces", [])):
        if load["force_N"] < 0:
            raise case.error(f"must be >= 0 (an amplitude), got {load['force_N']:g}; reverse the "
                             "direction or set phase_deg: 180", ("excitation", "forces", i, "force_N"))
    base = exc.get("base_acceleration")
    if base is not None and base["amplitude_m_s2"] < 0:
        raise case.error(f"must be >= 0 (an amplitude), got {base['amplitude_m_s2']:g}; reverse the "
                         "direction or set phase_deg: 180",
                         ("excitation", "base_acceleration", "amplitude_m_s2"))
    frequencies = list(exc.get("frequency_hz", [])) + [exc["sweep"][k] for k in ("start_hz", "end_hz")
                                                      if "sweep" in exc]
    for key in ("frequency_hz", "sweep"):
        if key in exc and max(frequencies) > AUDIBLE_LIMIT_HZ:
            raise case.error(f"{max(frequencies):g} Hz is above the audible range (≤ "
                             f"{AUDIBLE_LIMIT_HZ:g} Hz) that squeak and rattle noise is judged in; "
                             "frequencies are in Hz", ("excitation", key))
    fe = data["model"].get("fe")
    if fe is None:
        return
    for name, material in fe.get("materials", {}).items():
        p = ("model", "fe", "materials", name)
        if material["E_Pa"] < MIN_E_PA:
            raise case.error(f"{material['E_Pa']:g} Pa is far too soft for a panel material — "
                             "given in MPa or GPa? E_Pa is in pascals (steel 2.1e+11)", p + ("E_Pa",))
        if material["rho_kg_m3"] < MIN_RHO_KG_M3:
            raise case.error(f"{material['rho_kg_m3']:g} kg/m³ is lighter than air — given in t/mm³ "
                             "or g/cm³? rho_kg_m3 is in kg/m³ (steel 7850)", p + ("rho_kg_m3",))
    generator = fe.get("generator")
    if generator is not None and generator["mesh_size_m"] >= MAX_MESH_SIZE_M:
        raise case.error(f"{generator['mesh_size_m']:g} m elements are larger than a panel — given in "
                         "mm? mesh_size_m is in metres", ("model", "fe", "generator", "mesh_size_m"))


__all__ = ["check_finite", "check_plausible", "AUDIBLE_LIMIT_HZ", "MIN_E_PA", "MIN_RHO_KG_M3",
           "MAX_MESH_SIZE_M", "SPAN_RANGE_M", "THICKNESS_RANGE"]
