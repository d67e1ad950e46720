"""Numbers a case file can hold that the schema cannot judge: non-finite values anywhere, and
signs and orders of magnitude that betray a unit mistake (moduli in MPa/GPa, densities in t/mm³,
element sizes in mm, frequencies beyond hearing), or that no squeak-and-rattle input has.

    check_finite(data, source, lines)    CaseError at the first NaN or ±inf
    check_plausible(case, data)          CaseError at the first implausible value, naming its unit
    plausibility_warnings(config)        one-line warnings: accepted, but far outside practice

This module is THE place of the plausibility bounds: the case keys, the schema (ν), mesh files
and decks (:mod:`sarfe.pipeline.model.case_mesh`, :mod:`sarfe.pipeline.model.deck_checks`) read the
same constants, so a value refused (or warned about) in the YAML is refused (warned about) in a
deck alike.
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
# Poisson's ratio, both ends excluded: ν → 0.5 is incompressible (the bulk modulus
# E / (3 (1 − 2ν)) infinite: a solid's stiffness singular, a shell's membrane locked), ν ≤ −1 has
# no positive shear modulus. The schema (MATERIAL.nu) and the deck reader use the same range.
POISSON_RANGE = (-1.0, 0.5)

# Warning bounds (accepted, with one line saying why it looks wrong):
# dry friction between interior materials (PP, ABS, PVC, felt, leather, EPDM on glass or paint) is
# μ ≈ 0.1 … 1.5; above 2 it is rather a percentage (35 for 0.35) or a typing slip
MAX_FRICTION_COEFFICIENT = 2.0
# squeak-and-rattle shaker tests and road-load inputs of trim parts run at 0.1 … 5 g; 50 g is a
# shock test, not a rattle input (or mm/s² given as m/s²)
STANDARD_GRAVITY_M_S2 = 9.80665
MAX_BASE_ACCELERATION_M_S2 = 50 * STANDARD_GRAVITY_M_S2
# a contact's static overclosure under its own preload, δ = preload_N / normal_stiffness_N_m: a
# penalty spring stands for a stiff contact, its deflection is µm … 0.1 mm; more than 1 mm means
# the parts are pressed through each other (a stiffness given in N/mm: 1000 N/mm = 1e6 N/m)
MAX_PRELOAD_OVERCLOSURE_M = 1e-3


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


def plausibility_warnings(config) -> list:
    """One-line warnings for values a case accepts but no squeak-and-rattle input has (bounds
    above): μ > :data:`MAX_FRICTION_COEFFICIENT`, a base acceleration above
    :data:`MAX_BASE_ACCELERATION_M_S2` (50 g), a preload pressing a contact's penalty spring more
    than :data:`MAX_PRELOAD_OVERCLOSURE_M` into the part. ``config``: the typed
    :class:`sarfe.case.config.CaseConfig`."""
    warnings = []
    for contact in config.contacts:
        where = f"contacts[{contact.index}] ({contact.name})"
        mu = contact.params.get("friction_coefficient")
        if mu is not None and mu > MAX_FRICTION_COEFFICIENT:
            warnings.append(f"{where}: friction_coefficient = {mu:g} is above "
                            f"{MAX_FRICTION_COEFFICIENT:g}, beyond dry friction of interior "
                            "materials (0.1 … 1.5): μ is a ratio, not a percentage (0.35, not 35)")
        stiffness = contact.params.get("normal_stiffness_N_m")
        if contact.preload_N and stiffness:
            overclosure = contact.preload_N / stiffness
            if overclosure > MAX_PRELOAD_OVERCLOSURE_M:
                warnings.append(
                    f"{where}: preload_N / normal_stiffness_N_m = {contact.preload_N:g} N / "
                    f"{stiffness:g} N/m presses the contact {overclosure * 1e3:.4g} mm into the "
                    f"part (more than {MAX_PRELOAD_OVERCLOSURE_M * 1e3:g} mm): "
                    "normal_stiffness_N_m is in N/m (1000 N/mm = 1e6 N/m)")
    base = config.excitation.base_acceleration
    if base is not None and base.amplitude_m_s2 > MAX_BASE_ACCELERATION_M_S2:
        warnings.append(f"excitation.base_acceleration.amplitude_m_s2 = {base.amplitude_m_s2:g} "
                        f"m/s² is {base.amplitude_m_s2 / STANDARD_GRAVITY_M_S2:.3g} g, above the "
                        f"{MAX_BASE_ACCELERATION_M_S2 / STANDARD_GRAVITY_M_S2:g} g of any squeak "
                        "and rattle test (shaker and road inputs: 0.1 … 5 g); the amplitude is "
                        "in m/s² (1 g = 9.81)")
    return warnings


__all__ = ["check_finite", "check_plausible", "plausibility_warnings", "AUDIBLE_LIMIT_HZ",
           "MIN_E_PA", "MIN_RHO_KG_M3", "MAX_MESH_SIZE_M", "SPAN_RANGE_M", "THICKNESS_RANGE",
           "POISSON_RANGE", "MAX_FRICTION_COEFFICIENT", "STANDARD_GRAVITY_M_S2",
           "MAX_BASE_ACCELERATION_M_S2", "MAX_PRELOAD_OVERCLOSURE_M"]
