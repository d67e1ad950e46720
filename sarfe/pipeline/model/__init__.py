"""Stage 2 of a case: the linear stage and the nonlinear model.

    stage            LinearStage record, linear_model_key
    linear_stage     build_linear_model: the path of the case's model →
      matrices_stage   M, K (D) as given
      fe_stage         mesh/generator → shells → supports → Craig–Bampton → loads, ERP map
      deck_stage       a Nastran/Abaqus deck (deck_model: reading, groups, overrides;
                       deck_checks: quality, supports, units; deck_springs: springs → contacts)
    case_mesh        the case's mesh (file or generator)
    groups           node groups, fixed nodes, per-triangle shell properties
    contact_pairs    contacts from the geometry: points, partner-surface normals, frames,
                     surface gaps, rows on the reduced coordinates (issue 29)
    contact_kinematics  points on the shells' faces by shape functions (±t/2), contact rows
    cutoff           the Craig–Bampton cutoff rule
    erp_map          radiating surface → normal-displacement map N, nodal areas
    nonlinear_model  damping, ContactSet, excitation harmonics on the kept DOFs
"""
