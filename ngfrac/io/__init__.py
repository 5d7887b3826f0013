"""Writing and reading runs: the run folder and its writers (history CSV, VTK, HDF5 results),
checkpoints, and plots."""
