"""Meshes: domains (rectangle, box, CAD shapes) and their Netgen geometry, size fields and remeshing under a vertex cap,
the adapter that owns every mesh change, and the transfer of u and z onto a new mesh."""
