"""sarfe.results — result writers; each a plain function writing into a given path/directory.

File layouts and array names are documented in the modules: summary.py (summary.json),
response_h5.py (response.h5), vtk.py (VTU/PVD arrays), plots.py (PNGs), console.py (what
``sarfe solve`` prints: the 80-column summary and the --quiet line).

    write_summary_json(path, summary: dict) -> Path            strict JSON, NaN/inf → null + note
    console_table(rows: list[dict], columns=None, formats=None, headers=None, max_rows=None) -> str
    write_response_h5(path, solutions, *, contacts=None, excitation=None, excitation_dofs=None,
                      boundary_dofs=None, mode_frequencies_hz=None, erp=None, radiating_nodes=None,
                      store_displacement=False, store_erp_density_per_harmonic=False,
                      density_points=None, base_samples_per_period=None, extra_groups=None,
                      attributes=None) -> Path
    read_response_h5(path) -> dict
    record_samples(H, N, base_samples=None) -> int   N_rec, response.h5's stored time samples
    write_erp_vtu(path, points, triangles, point_data: dict, field_data=None, active_vectors=None,
                  parts=None) -> Path
    part_ids(n_triangles, element_groups) -> (ids (n_tri,) int32, names)   (cell data part_id)
    erp_point_data(n_points, erp, normal_displacement, omega, displacement=None,
                   radiating_nodes=None, contact_marker=None) -> dict
    contact_markers(n_points, contact_nodes) -> (n_points,) int32
    write_pvd(path, [(time_or_frequency, vtu_filename), ...]) -> Path
    write_erp_sweep(directory, points, triangles, point_data_per_frequency (list | j → dict),
                    frequencies_hz, basename="erp", workers=1, parts=None) -> Path (.pvd)
    start_erp_sweep(...same...) -> writer; writer.finish() -> Path (.pvd)   (the maps written on
                    the workers while the caller writes the other files)
    write_deflection_animation(directory, points, triangles, displacement_harmonics (2H+1, n, 3),
                               n_frames=24, omega=None, basename="deflection", point_data=None) -> Path (.pvd)
    plot_erp_sweep(path, frequencies_hz, level_db, stable=None, level_a_db=None, title=None,
                   linear_level_db=None, dynamic_range_db=80.0) -> Path
    plot_contact_forces(path, force_time (N, n), names=None, omega=None, title=None) -> Path
    plot_erp_spectrum(path, frequencies_hz (H,), level_db (H,), level_a_db=None, title=None) -> Path
    plot_friction(path, friction_time (N, n), state (N, n), names=None, omega=None) -> Path
    plot_third_octave(path, nominal_hz, level_dba, linear_level_dba=None, ...) -> Path
    plot_contributions(path, names, level_dba, share_a, title=None, part_level_dba=None) -> Path
    plot_audibility(path, band_hz, spl_db, background_db, threshold_in_quiet_db,
                    masked_threshold_db, title=None) -> Path
    write_report_html(path, summary, images={key: png}, notes=None) -> Path   (report.py, jinja2)
    render_surface(path, points, triangles, values, label, ...) -> (Path, renderer)  (render.py;
    start_render(jobs) / finish_render(run) render in a child while the caller goes on)

Each writer's module (and its library: matplotlib, h5py, jinja2, pyvista) is imported on first
use (:mod:`sarfe.util.lazy`), so a run that writes no PNG never imports matplotlib.
"""
from sarfe.util.lazy import lazy_exports

_EXPORTS = {
    "plot_contact_forces": ".plots", "plot_contributions": ".plots", "plot_erp_spectrum": ".plots",
    "plot_erp_sweep": ".plots", "plot_friction": ".plots", "plot_third_octave": ".plots",
    "plot_audibility": ".plots",
    "write_report_html": ".report",
    "read_response_h5": ".response_h5", "write_response_h5": ".response_h5",
    "record_samples": ".record_grid",
    "console_table": ".summary", "to_jsonable": ".summary", "write_summary_json": ".summary",
    "contact_markers": ".vtk", "erp_point_data": ".vtk", "period_samples": ".vtk",
    "write_deflection_animation": ".vtk", "write_erp_sweep": ".vtk", "write_erp_vtu": ".vtk",
    "write_pvd": ".vtk", "part_ids": ".vtk", "start_erp_sweep": ".vtk",
}
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)

__all__ = [
    "write_summary_json", "console_table", "to_jsonable", "write_response_h5", "read_response_h5",
    "record_samples",
    "write_erp_vtu", "erp_point_data", "contact_markers", "write_pvd", "write_erp_sweep",
    "start_erp_sweep", "part_ids",
    "write_deflection_animation", "period_samples", "plot_erp_sweep", "plot_contact_forces",
    "plot_erp_spectrum", "plot_friction", "plot_third_octave", "plot_contributions",
    "plot_audibility",
    "write_report_html",
]
