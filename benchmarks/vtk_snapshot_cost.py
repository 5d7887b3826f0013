#!/usr/bin/env python3
"""One 3D VTK snapshot written both ways in one process: ``output.vtk_format = "vertices"``
(compressed binary, ngfrac.io.vtu) and NGSolve's subdivided ASCII output, on a unit cube of
~100,000 tetrahedra with u (P1), z and the derived fields' kind of expressions::

    NGFRAC_THREADS=1 python benchmarks/vtk_snapshot_cost.py

(docs/benchmarks.md, "VTK snapshots in 3D")."""
import os, time, tempfile, numpy as np, ngsolve as ngs
from netgen.occ import Box, Pnt, OCCGeometry
from ngfrac.io.output import VTKSeries
ngs.SetNumThreads(1)
t0 = time.perf_counter()
mesh = ngs.Mesh(OCCGeometry(Box(Pnt(0,0,0), Pnt(1,1,1))).GenerateMesh(maxh=0.037))
print("mesh", mesh.nv, mesh.ne, f"{time.perf_counter()-t0:.1f}s", flush=True)
u = ngs.GridFunction(ngs.VectorH1(mesh, order=1)); u.Set(ngs.CF((ngs.x*ngs.y, ngs.y**2, ngs.z)))
z = ngs.GridFunction(ngs.H1(mesh, order=1)); z.Set(ngs.x**2)
e = ngs.Sym(ngs.grad(u)); s = 2*e + ngs.Trace(e)*ngs.Id(3)
fields = {"u": u, "z": z, "energy_density": 0.5*(1-z)**2*ngs.InnerProduct(s, e),
          "stress": ngs.CF((s[0,0], s[1,1], s[2,2], s[0,1], s[1,2], s[0,2])),
          "von_mises": ngs.sqrt(1.5*ngs.InnerProduct(s - ngs.Trace(s)/3*ngs.Id(3), s - ngs.Trace(s)/3*ngs.Id(3)))}
with tempfile.TemporaryDirectory() as tmp:
    for layout in ("vertices", "subdivided", "vertices"):
        series = VTKSeries(os.path.join(tmp, layout), 0, layout=layout)
        c0, w0 = time.process_time(), time.perf_counter()
        path = series.write(mesh, fields, 0.0)
        print(layout, f"wall {time.perf_counter()-w0:.2f}s cpu {time.process_time()-c0:.2f}s size {os.path.getsize(path)/1e6:.1f} MB", flush=True)
