"""Solving in time: the stepper of the paper's semi-implicit scheme, its u- and z-sub-problems,
time-step control, and the seam between one process and many."""
