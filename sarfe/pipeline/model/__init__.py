"""Stage 2 of a case: the linear stage (mesh or deck → reduced model) and the nonlinear model."""
