"""Direct against preconditioned CG for the u-step: time per solve as the dofs grow.

    NGFRAC_THREADS=1 python benchmarks/solver_crossover.py [--quick] [--no-3d]

The u-step of every time step solves ``((1-z)^2 + eta) sigma[u]:e[v]`` with new values of z.
What a step costs, as the stepper does it (:meth:`ngfrac.PhaseFieldStepper.solve_u`):

- direct (``sparsecholesky``, ``umfpack``): the numeric refactorization of the reassembled
  matrix (the symbolic analysis is done once per mesh) and one solve;
- ``cg``: the preconditioner's set-up after assembly (BDDC: a direct solve on the vertex
  dofs and the element-wise Schur complements) and the CG iterations to a relative residual of
  1e-10 (``tol`` of NGSolve's CGSolver, in the preconditioned norm).

The problem: plane strain (lam = 121.15, mu = 80.77, the SENT material) on the unit square with
a crack band z = exp(-d/eps), eps = 0.02, from (0, 0.5) to (0.5, 0.5), eta = 1e-6, bottom
fixed and top pulled; P2 on uniform meshes of decreasing size. In 3D: a unit cube with a
planar crack band z = exp(-d/eps) over x < 0.5 in the plane z = 0.5 (between the loaded
faces bottom, z = 0, and top), eps = 0.08, P2.
Assembly is the same for both and is not counted. The table prints the iterations too, with
and without the band (z = 0): the band's residual stiffness (a coefficient contrast of 1e6)
is what makes the u-equation ill-conditioned.
"""
from __future__ import annotations

import math
import sys
import time

import ngsolve as ngs
from ngsolve.krylovspace import CGSolver

import ngfrac

ngfrac.set_threads()  # NGFRAC_THREADS

LAM, MU, ETA = 121.15, 80.77, 1e-6


def elasticity(u, v):
    e, f = ngs.Sym(ngs.grad(u)), ngs.Sym(ngs.grad(v))
    return 2 * MU * ngs.InnerProduct(e, f) + LAM * ngs.Trace(e) * ngs.Trace(f)


def problem(dim: int, h: float, order: int, cracked: bool):
    """Mesh, space, z and the boundary values of one benchmark problem."""
    if dim == 2:
        from netgen.geom2d import unit_square
        mesh = ngs.Mesh(unit_square.GenerateMesh(maxh=h))
        eps = 0.02
        distance = ngs.sqrt((ngs.y - 0.5) ** 2 + ngs.IfPos(ngs.x - 0.5, (ngs.x - 0.5) ** 2, 0))
        pull = ngs.CF((0, 0.01 * ngs.y))
    else:
        from netgen.csg import unit_cube
        mesh = ngs.Mesh(unit_cube.GenerateMesh(maxh=h))
        eps = 0.08  # Netgen's unit cube: bottom z = 0, top z = 1
        distance = ngs.sqrt((ngs.z - 0.5) ** 2 + ngs.IfPos(ngs.x - 0.5, (ngs.x - 0.5) ** 2, 0))
        pull = ngs.CF((0, 0, 0.01 * ngs.z))
    fes = ngs.VectorH1(mesh, order=order, dirichlet="bottom|top")
    z = ngs.GridFunction(ngs.H1(mesh, order=min(order, 2)))
    if cracked:
        z.Set(ngs.exp(-distance / eps))
    return mesh, fes, z, pull


def time_solver(fes, z, pull, solver: str, repeats: int = 2) -> tuple[float, int]:
    """Seconds per u-solve after the first (refactorization or preconditioner set-up, plus
    the solve) and the CG iterations (0 for direct)."""
    u, v = fes.TnT()
    a = ngs.BilinearForm(fes, symmetric=True)
    a += ((1 - z) ** 2 + ETA) * elasticity(u, v) * ngs.dx
    pre = ngs.Preconditioner(a, "bddc") if solver == "cg" else None
    gfu = ngs.GridFunction(fes)
    gfu.Set(pull, ngs.BND)
    inverse, iterations, times = None, 0, []
    with ngs.TaskManager():
        for _ in range(repeats + 1):
            started = time.perf_counter()
            a.Assemble()  # updates a registered preconditioner, which is counted below
            assembled = time.perf_counter()
            if pre is None:
                matrix_only = 0.0
            else:  # what assembling without the preconditioner costs, to subtract it
                b = ngs.BilinearForm(fes, symmetric=True)
                b += ((1 - z) ** 2 + ETA) * elasticity(u, v) * ngs.dx
                t0 = time.perf_counter()
                b.Assemble()
                matrix_only = time.perf_counter() - t0
            residual = (-a.mat * gfu.vec).Evaluate()
            t1 = time.perf_counter()
            if solver == "cg":
                cg = CGSolver(a.mat, pre.mat, tol=1e-10, maxiter=10000)
                x = residual.CreateVector()
                x[:] = 0.0
                cg.Solve(rhs=residual, sol=x, initialize=False)
                iterations = cg.iterations
            else:
                if inverse is None:
                    inverse = a.mat.Inverse(fes.FreeDofs(), inverse=solver)
                else:
                    inverse.Update()
                x = (inverse * residual).Evaluate()
            t2 = time.perf_counter()
            times.append((assembled - started - matrix_only) + (t2 - t1))
    return min(times[1:]), iterations


def main(argv: list[str]) -> None:
    quick = "--quick" in argv
    cases = [(2, h) for h in ((0.04, 0.02) if quick else (0.04, 0.02, 0.01, 0.007))]
    if "--no-3d" not in argv:
        cases += [(3, h) for h in ((0.3,) if quick else (0.3, 0.2, 0.14, 0.1))]
    import os
    print(f"NGFRAC_THREADS={os.environ.get('NGFRAC_THREADS', '(unset)')}; NGSolve {ngs.__version__}")
    print("| dim | h | dofs of u | sparsecholesky s | umfpack s | CG+BDDC s | CG iterations "
          "(band / no band) | CG / direct |")
    print("|---|---|---|---|---|---|---|---|")
    for dim, h in cases:
        mesh, fes, z, pull = problem(dim, h, 2, cracked=True)
        direct, _ = time_solver(fes, z, pull, "sparsecholesky")
        # umfpack refactorizes slowly (5 s at 24k dofs): measured on the small cases only
        umf = time_solver(fes, z, pull, "umfpack")[0] if fes.ndof < 30000 else math.nan
        cg, iterations = time_solver(fes, z, pull, "cg")
        _, fes0, z0, pull0 = problem(dim, h, 2, cracked=False)
        _, sound = time_solver(fes0, z0, pull0, "cg", repeats=1)
        print(f"| {dim} | {h:g} | {fes.ndof} | {direct:.3f} | {umf:.3f} | {cg:.3f} | "
              f"{iterations} / {sound} | {cg / direct:.2f} |", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
