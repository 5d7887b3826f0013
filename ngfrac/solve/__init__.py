"""Solving in time: the stepper of the paper's semi-implicit scheme, its u- and z-sub-problems,
time-step control, linear solvers, Lagrange-node values and thread control."""
