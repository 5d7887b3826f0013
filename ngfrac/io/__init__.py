"""Writing and reading runs: the run folder and its writers (history CSV, VTK, HDF5 results,
checkpoints, plots), the HDF5 layer that results and checkpoints share, and plots."""
