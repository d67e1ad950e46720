r"""Equivalent radiated power (ERP) of a vibrating surface, per harmonic of a periodic response.

ERP assumes every surface element radiates like a piece of an infinite baffled piston (radiation
efficiency σ = 1, scaled by a radiation loss factor RLF), so the acoustic power is

    P = ½ ρ c · RLF · Σ_i A_i |v_n,i|²

with v_n,i the complex amplitude of the surface-normal velocity at radiating node i and A_i its
nodal area [m²]. For a periodic response with harmonics k = 1 … H (Fourier convention of
:mod:`sarfe.hbm.harmonics`, coefficients [w0, w1c, w1s, …, wHc, wHs]) of the normal displacement
w_i(θ), θ = ωt, the harmonic-k velocity amplitude is

    |v_n,i,k| = k ω √(w_kc,i² + w_ks,i²)                                      [m/s]

and, harmonics being orthogonal over a period, the powers add:

    e_k,i = ½ ρ c · RLF · |v_n,i,k|²          ERP density of harmonic k at node i [W/m²]
    P_k   = Σ_i e_k,i A_i                      ERP of harmonic k [W]
    P     = Σ_k P_k                            total ERP [W]
    L_k   = 10 log10(P_k / P_ref)              ERP level [dB re 1 pW], P_ref = 1e-12 W
    L     = 10 log10(P / P_ref)
    L_A,k = L_k + A(k ω / 2π),  L_A = 10 log10 Σ_k 10^(L_A,k / 10)   (IEC 61672-1 A-weighting)

The static term w0 does not radiate. A zero power gives a level of −inf dB (no floor is applied;
the JSON writer turns it into null). Nodal areas are lumped: each triangle gives one third of its
area to each of its three vertices (:func:`sarfe.erp.surface.nodal_areas`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sarfe.erp.weighting import a_weighting_db, db_sum

__all__ = [
    "AIR_DENSITY",
    "SOUND_SPEED",
    "REFERENCE_POWER",
    "ErpResult",
    "equivalent_radiated_power",
    "normal_velocity_amplitudes",
    "power_level_db",
]

AIR_DENSITY = 1.204     # [kg/m³] air at 20 °C, 101.325 kPa
SOUND_SPEED = 343.2     # [m/s] air at 20 °C
REFERENCE_POWER = 1e-12  # [W] reference sound power, levels in dB re 1 pW


@dataclass(frozen=True)
class ErpResult:
    """ERP of one periodic solution (see module docstring for the equations).

    H harmonics, n radiating nodes; SI units; levels in dB re ``reference_power``.
    """

    frequencies_hz: np.ndarray   # (H,) [Hz] f_k = k ω / 2π
    density: np.ndarray          # (H, n) [W/m²] e_k,i
    density_total: np.ndarray    # (n,) [W/m²] Σ_k e_k,i
    power: np.ndarray            # (H,) [W] P_k
    power_total: float           # [W] P
    level_db: np.ndarray         # (H,) [dB re 1 pW] L_k (−inf where P_k = 0)
    level_total_db: float        # [dB re 1 pW] L
    level_a_db: np.ndarray       # (H,) [dB(A)] L_k + A(f_k)
    level_total_a_db: float      # [dB(A)] A-weighted total
    reference_power: float = REFERENCE_POWER  # [W]

    @property
    def harmonics(self) -> int:
        return int(self.frequencies_hz.shape[0])

    def summary(self) -> dict:
        """Plain-Python dict of the scalar and per-harmonic results (for summary.json)."""
        return {
            "frequencies_hz": self.frequencies_hz.tolist(),
            "power_W": self.power.tolist(),
            "power_total_W": float(self.power_total),
            "level_db": self.level_db.tolist(),
            "level_total_db": float(self.level_total_db),
            "level_a_db": self.level_a_db.tolist(),
            "level_total_a_db": float(self.level_total_a_db),
            "reference_power_W": float(self.reference_power),
        }


def power_level_db(power, reference_power: float = REFERENCE_POWER) -> np.ndarray:
    """Sound power level 10 log10(P / P_ref) [dB re P_ref]; P = 0 gives −inf (no warning)."""
    power = np.asarray(power, dtype=float)
    if np.any(power < 0):
        raise ValueError("power must be >= 0")
    with np.errstate(divide="ignore"):
        return 10.0 * np.log10(power / reference_power)


def _harmonic_count(W) -> int:
    """H of normal displacement harmonics W (2H+1, ...) [m]; ValueError unless 2H+1 ≥ 3 rows."""
    if W.ndim < 1 or W.shape[0] < 3 or W.shape[0] % 2 == 0:
        raise ValueError(
            f"normal_displacement must have 2H+1 >= 3 rows (odd), got shape {W.shape}")
    return (W.shape[0] - 1) // 2


def normal_velocity_amplitudes(normal_displacement, omega: float) -> np.ndarray:
    """|v_n,k| = k ω √(w_kc² + w_ks²) [m/s], shape (H, ...) from coefficients (2H+1, ...) [m]."""
    W = np.asarray(normal_displacement, dtype=float)
    H = _harmonic_count(W)
    k = np.arange(1, H + 1).reshape((H,) + (1,) * (W.ndim - 1))
    return k * float(omega) * np.hypot(W[1::2], W[2::2])


def equivalent_radiated_power(
    normal_displacement,
    omega: float,
    nodal_areas,
    density: float = AIR_DENSITY,
    sound_speed: float = SOUND_SPEED,
    radiation_loss_factor: float = 1.0,
    reference_power: float = REFERENCE_POWER,
) -> ErpResult:
    """ERP per harmonic of the surface-normal displacement harmonics at the radiating nodes.

    Parameters
    ----------
    normal_displacement : (2H+1, n) [m]  harmonic coefficients W of w_i(θ) (sarfe convention:
        [w0, w1c, w1s, …, wHc, wHs]); w = u · n_i with n_i the unit surface normal at node i.
    omega : [rad/s]  fundamental angular frequency ω (> 0).
    nodal_areas : (n,) [m²]  lumped nodal areas A_i (1/3 of each adjacent triangle).
    density : [kg/m³]  fluid density ρ (air 1.204).
    sound_speed : [m/s]  speed of sound c (air 343.2).
    radiation_loss_factor : [-]  RLF scaling the ideal (σ = 1) radiation, default 1.
    reference_power : [W]  P_ref of the levels, default 1e-12 W.

    Returns
    -------
    ErpResult with e_k,i = ½ρc·RLF·(kω)²(w_kc,i² + w_ks,i²), P_k = Σ_i e_k,i A_i, levels in dB.
    """
    omega = float(omega)
    if not np.isfinite(omega) or omega <= 0:
        raise ValueError(f"omega must be > 0 [rad/s], got {omega!r}")
    W = np.asarray(normal_displacement, dtype=float)
    if W.ndim != 2:
        raise ValueError(f"normal_displacement must be (2H+1, n_nodes), got shape {W.shape}")
    areas = np.asarray(nodal_areas, dtype=float)
    if areas.shape != (W.shape[1],):
        raise ValueError(
            f"nodal_areas must have shape ({W.shape[1]},) to match normal_displacement, "
            f"got {areas.shape}")
    if np.any(areas < 0) or not np.all(np.isfinite(areas)):
        raise ValueError("nodal_areas must be finite and >= 0")
    for name, value in (("density", density), ("sound_speed", sound_speed),
                        ("reference_power", reference_power)):
        if not np.isfinite(value) or value <= 0:
            raise ValueError(f"{name} must be > 0, got {value!r}")
    if not np.isfinite(radiation_loss_factor) or radiation_loss_factor < 0:
        raise ValueError(f"radiation_loss_factor must be >= 0, got {radiation_loss_factor!r}")

    H = _harmonic_count(W)
    # e_k,i = ½ρc·RLF (kω)² (w_kc² + w_ks²): |v_n,k|² without its square root
    # (:func:`normal_velocity_amplitudes` squared), one pass over the (H, n) field
    scale = 0.5 * density * sound_speed * radiation_loss_factor \
        * (np.arange(1, H + 1) * omega) ** 2
    erp_density = W[1::2] ** 2
    erp_density += W[2::2] ** 2
    erp_density *= scale[:, None]
    power = erp_density @ areas                                            # (H,)
    power_total = float(power.sum())
    frequencies = np.arange(1, H + 1) * omega / (2.0 * np.pi)
    level = power_level_db(power, reference_power)
    level_a = level + a_weighting_db(frequencies)
    return ErpResult(
        frequencies_hz=frequencies,
        density=erp_density,
        density_total=erp_density.sum(axis=0),
        power=power,
        power_total=power_total,
        level_db=level,
        level_total_db=float(power_level_db(power_total, reference_power)),
        level_a_db=level_a,
        level_total_a_db=float(db_sum(level_a)),
        reference_power=float(reference_power),
    )
