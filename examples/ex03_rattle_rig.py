r"""Example 3 — the rattle rig: a steel striker hits an ABS plate that radiates.

Physics (cases/rattle_rig.yaml, SI units): a steel cantilever strip (200 × 20 × 1.5 mm) carries a
striker 0.5 mm above a clamped ABS plate (150 × 150 × 2.5 mm); a 0.05 N harmonic force near the
strip's first bending resonance (≈ 31 Hz) makes the striker hit the plate through a penalty
contact (k_n = 2·10⁵ N/m, λ = k_n max(0, w − g)); 2 % modal damping. Shell FE (10 mm), Craig–
Bampton, harmonic balance with H = 10, N = 256 at 32 Hz, against Newmark time integration of the
same reduced model (:mod:`case_point`).

The numbers at 32 Hz: the striker's first-harmonic gap amplitude |ŵ₁| ≈ 0.534 mm — above the
0.5 mm gap, so it hits — and the plate's radiated level L_WA ≈ 75.5 dB(A) (equivalent radiated
power, σ = 1). Time integration gives the same striker motion to 0.3 % and a level about 0.9 dB
lower: the impact's high harmonics, cut at H = 10 in the harmonic balance, carry the A-weighted
level at 32 Hz.
"""
from case_point import solve_point

FREQUENCY_HZ = 32.0


def rattle_point(steps_per_period=512):
    return solve_point("rattle_rig.yaml", FREQUENCY_HZ, steps_per_period)


if __name__ == "__main__":
    p = rattle_point()
    print(f"rattle rig at {p.frequency_hz:g} Hz: striker |ŵ₁| = {p.gap_amplitude_m['tip'] * 1e3:.4f} mm "
          f"(time integration {p.time_gap_amplitude_m['tip'] * 1e3:.4f} mm), peak impact force "
          f"{p.peak_normal_force_N['tip']:.2f} N; L_WA = {p.level_dba:.2f} dB(A) "
          f"(time integration {p.time_level_dba:.2f} dB(A))")
