"""solvers entities."""
