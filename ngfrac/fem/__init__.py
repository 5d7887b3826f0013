"""Numerical utilities every layer may use: threads, sums over ranks, Lagrange-node values,
quadrature, element geometry, linear and Newton solvers. Nothing here knows fracture or scenes."""
