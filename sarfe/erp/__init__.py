"""sarfe.erp — equivalent radiated power per harmonic, A-weighting, radiating-surface geometry.

    equivalent_radiated_power(normal_displacement (2H+1, n) [m], omega [rad/s], nodal_areas (n,) [m²],
                              density=1.204, sound_speed=343.2, radiation_loss_factor=1.0,
                              reference_power=1e-12) -> ErpResult
    a_weighting_db(f), db_sum(levels), a_weighted_total_db(levels, f)
    baffled_radiated_power(points, areas, v̂, omega), radiation_efficiency(...)  (Rayleigh reference)
    nodal_areas(points, triangles), nodal_normals(points, triangles),
    normal_displacement(U (2H+1, n, 3), normals (n, 3)), nodal_translations(U (2H+1, n_dof), nodes)
    third_octave_levels(f_k (H,), P_k (H,)) -> ThirdOctaveSpectrum        (bands.py, IEC 61260-1)
    erp_contributions(names, v (S, H, n), areas, omega) -> ErpContributions  (contributions.py:
        partial ERP and coherent shares per source; contributions_from_gram(...) from area-weighted
        Gram matrices), ranking_lines(...)
    radiation_gram(erp_map (n_s, n), areas) -> Q = Nᵀ diag(A) N, harmonic_power_proxy(U, omega, Q)
        (reduced.py: the ERP of reduced coordinates as a quadratic form, once per model)
"""
from sarfe.erp.erp import (
    AIR_DENSITY,
    REFERENCE_POWER,
    SOUND_SPEED,
    ErpResult,
    equivalent_radiated_power,
    normal_velocity_amplitudes,
    power_level_db,
)
from sarfe.erp.bands import ThirdOctaveSpectrum, third_octave_levels
from sarfe.erp.contributions import ErpContributions, erp_contributions, ranking_lines
from sarfe.erp.rayleigh import baffled_radiated_power, radiation_efficiency
from sarfe.erp.surface import (
    nodal_areas,
    nodal_normals,
    nodal_translations,
    normal_displacement,
    triangle_area_vectors,
)
from sarfe.erp.weighting import a_weighted_levels_db, a_weighted_total_db, a_weighting_db, db_sum

__all__ = [
    "AIR_DENSITY", "SOUND_SPEED", "REFERENCE_POWER", "ErpResult", "equivalent_radiated_power",
    "normal_velocity_amplitudes", "power_level_db", "nodal_areas", "nodal_normals",
    "nodal_translations", "normal_displacement", "triangle_area_vectors", "a_weighting_db",
    "db_sum", "a_weighted_levels_db", "a_weighted_total_db", "baffled_radiated_power",
    "radiation_efficiency", "ThirdOctaveSpectrum", "third_octave_levels", "ErpContributions",
    "erp_contributions", "ranking_lines",
]
