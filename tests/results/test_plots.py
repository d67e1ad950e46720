"""PNG plots are written, non-empty and valid PNG; unstable points styled differently."""
import numpy as np

from sarfe.erp import equivalent_radiated_power
from sarfe.results import plot_contact_forces, plot_erp_spectrum, plot_erp_sweep
from sarfe.results.plots import _categories

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def check_png(path):
    data = path.read_bytes()
    assert data[:8] == PNG_MAGIC and len(data) > 5000


def test_erp_sweep_plot(tmp_path):
    f = np.linspace(50, 150, 30)
    level = 60 + 10 * np.exp(-((f - 100) / 15) ** 2)
    stable = [not (90 < x < 105) for x in f]
    stable[0] = None
    level_a = level - 19.0
    level_a[3] = -np.inf
    check_png(plot_erp_sweep(tmp_path / "plots" / "erp_sweep.png", f, level, stable=stable,
                             level_a_db=level_a, title="sweep", linear_level_db=level + 3))
    check_png(plot_erp_sweep(tmp_path / "single.png", [100.0], [55.0]))
    np.testing.assert_array_equal(_categories([True, False, None, np.nan], 4), [1, 0, -1, -1])


def test_contact_force_and_spectrum_plots(tmp_path):
    theta = 2 * np.pi * np.arange(64) / 64
    force = np.column_stack([np.maximum(0, np.cos(theta)) * 20, 5 * np.sin(theta)])
    check_png(plot_contact_forces(tmp_path / "forces.png", force, names=["clip", "pad"],
                                  omega=2 * np.pi * 80))
    check_png(plot_contact_forces(tmp_path / "forces_phase.png", force[:, 0]))
    W = np.zeros((7, 3))
    W[1], W[4] = 1e-5, 1e-6          # harmonic 3 silent → −inf level, no bar
    erp = equivalent_radiated_power(W, 2 * np.pi * 100, np.full(3, 0.01))
    assert erp.level_db[2] == -np.inf
    check_png(plot_erp_spectrum(tmp_path / "spectrum.png", erp.frequencies_hz, erp.level_db,
                                erp.level_a_db, title="harmonics"))
    check_png(plot_erp_spectrum(tmp_path / "spectrum_db.png", erp.frequencies_hz, erp.level_db))


def test_sweep_branches_folds_jumps_and_silent_points(tmp_path):
    """A continuation through a fold (x turns back twice) gives three monotone branches sharing the
    fold points; a jump of 15 dB between neighbours is left open; −190 dB points are not drawn."""
    from matplotlib.figure import Figure

    from sarfe.results.plots import branch_ids, jump_starts

    x = np.array([1.0, 2.0, 3.0, 2.5, 2.0, 2.6, 3.5, 4.0])
    assert list(branch_ids(x)) == [0, 0, 0, 1, 1, 2, 2, 2]
    y = np.array([60.0, 61.0, 62.0, 63.0, 64.0, 79.0, 80.0, 81.0])
    assert list(np.flatnonzero(jump_starts(y))) == [5]
    levels = np.array([60.0, 61.0, -190.0, 62.0, 63.0])
    path = plot_erp_sweep(tmp_path / "silent.png", [1, 2, 3, 4, 5], levels,
                          converged=[True, True, True, True, False], target_dba=55.0)
    check_png(path)
    # the lines drawn never reach below the plotted range (no line to the floor)
    from sarfe.results import plots

    fig = Figure()
    ax = fig.add_subplot()
    plots._plot_branches(ax, np.arange(5.0), np.where(levels > -100, levels, np.nan),
                         np.ones(5, int), "C0")
    for line in ax.get_lines():
        ydata = np.asarray(line.get_ydata(), float)
        assert np.nanmin(ydata) >= 60.0
