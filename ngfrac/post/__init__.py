"""What a run is measured by: energies, reactions, the crack set and its tip, the crack path,
branching, derived fields for VTK."""
