"""The model, each owning its mathematics: elastic models (mode III, plane strain and stress,
3D), crack models (AT2, AT1, PF-CZM), load kinds (displacement, traction, pressure),
tension/compression splits, and the initial cracks (distance, optimal profile, direction)."""
