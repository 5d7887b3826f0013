"""Meshes and the fields on them: size fields and remeshing under a vertex cap, the adapter
that owns every mesh change, the transfer of u and z onto a new mesh, resolution warnings."""
