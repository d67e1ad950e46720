r"""Sound power of a baffled vibrating surface from the Rayleigh integral — the reference ERP approximates.

For a plane surface in an infinite rigid baffle vibrating with complex normal-velocity amplitudes
v̂_i at nodes x_i with areas A_i (time factor e^{iωt}, wavenumber κ = ω/c), the radiated power is

    P = ½ Re(v̂ᴴ Z v̂),   Re Z_ij = ρ c κ² A_i A_j sin(κ r_ij) / (2π κ r_ij),   r_ij = |x_i − x_j|

(the real part of the Rayleigh radiation impedance; the diagonal takes its limit sin(0)/0 = 1, the
small-piston result ρ c A_i (κ a_i)² / 2 with π a_i² = A_i). ERP replaces Re Z by its high-frequency
limit ρ c diag(A_i), so the radiation efficiency

    σ = P / ERP = v̂ᴴ Re Z v̂ / (ρ c Σ_i A_i |v̂_i|²)

tends to 1 for κ L ≫ 1 and to κ² A / (2π) for a rigid piston of area A with κ L ≪ 1; ERP is thus
an upper-bound-like estimate at low frequency, which the radiation loss factor RLF can correct.

Dense O(n²) work (in row blocks of ``block`` nodes): meant for validation on small meshes.
"""
from __future__ import annotations

import numpy as np

from sarfe.erp.erp import AIR_DENSITY, SOUND_SPEED

__all__ = ["baffled_radiated_power", "radiation_efficiency"]


def baffled_radiated_power(points, nodal_areas, normal_velocity, omega: float,
                           density: float = AIR_DENSITY, sound_speed: float = SOUND_SPEED,
                           block: int = 2048) -> float:
    """P = ½ Re(v̂ᴴ Re Z v̂) [W] of a baffled plane surface (module docstring).

    points (n, 3) [m]; nodal_areas (n,) [m²]; normal_velocity (n,) complex amplitudes [m/s];
    omega [rad/s].
    """
    x = np.asarray(points, dtype=float)
    areas = np.asarray(nodal_areas, dtype=float)
    v = np.asarray(normal_velocity, dtype=complex)
    kappa = float(omega) / sound_speed
    q = areas * v                                                          # volume velocity
    total = 0.0
    for start in range(0, x.shape[0], int(block)):
        rows = slice(start, start + int(block))
        r = np.linalg.norm(x[rows, None, :] - x[None, :, :], axis=2)
        kernel = np.sinc(kappa * r / np.pi)                                 # sin(κr)/(κr)
        total += np.real(np.conj(q[rows]) @ (kernel @ q))
    return 0.5 * density * sound_speed * kappa**2 / (2.0 * np.pi) * total


def radiation_efficiency(points, nodal_areas, normal_velocity, omega: float,
                         density: float = AIR_DENSITY, sound_speed: float = SOUND_SPEED) -> float:
    """σ = P_Rayleigh / ERP for one harmonic (module docstring); normal_velocity complex (n,) [m/s]."""
    areas = np.asarray(nodal_areas, dtype=float)
    v = np.asarray(normal_velocity, dtype=complex)
    erp = 0.5 * density * sound_speed * np.sum(areas * np.abs(v) ** 2)
    return baffled_radiated_power(points, areas, v, omega, density, sound_speed) / erp
