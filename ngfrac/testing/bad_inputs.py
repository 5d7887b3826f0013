"""Bad scene inputs, each with the one-line message it must give (tests/scene/test_checks.py
checks them on the API, tests/io/test_cli.py on the command line)."""
from __future__ import annotations

import copy
from pathlib import Path

from ngfrac.io.output import to_toml
from ngfrac.scene import apply_overrides
from .scenes import demo_data

SLIT = [[0.0, 0.5], [0.3, 0.5]]
BOX_CRACK = [[0.0, 0.5, 0.0], [0.3, 0.5, 0.0], [0.3, 0.5, 0.1], [0.0, 0.5, 0.1]]

BAD_2D = {
    # name: (cracks, fragment of the one-line message)
    "repeated point": ([[[0.0, 0.5], [0.3, 0.5], [0.3, 0.5]]],
                       r"cracks\[0\]: point 2 repeats point 1 \(0.3, 0.5\).*zero-length segment"),
    "zero-length crack": ([[[0.2, 0.5], [0.2, 0.5]]], r"cracks\[0\]: point 1 repeats point 0"),
    "zero-length segment": ([[[0.0, 0.5], [0.3, 0.5], [0.3, 0.5 + 1e-13]]],
                            r"cracks\[0\]: point 2 is 1e-13 from point 1.*zero-length segment"),
    "point visited twice": ([[[0.0, 0.5], [0.3, 0.5], [0.3, 0.6], [0.3, 0.5]]],
                            r"cracks\[0\]: point 3 repeats point 1.*visit a point twice"),
    "runs back on itself": ([[[0.0, 0.5], [0.3, 0.5], [0.1, 0.5]]],
                            r"cracks\[0\]: the polyline runs back on itself at point 1"),
    "self-intersecting": ([[[0.0, 0.5], [0.3, 0.5], [0.3, 0.7], [0.1, 0.3]]],
                          r"cracks\[0\]: segments 0 and 2 of the polyline cross or touch near \(0.2, 0.5\)"),
    "cracks cross": ([SLIT, [[0.2, 0.3], [0.2, 0.8]]],
                     r"cracks\[0\] and cracks\[1\] cross or touch near \(0.2, 0.5\)"),
    "cracks touch": ([SLIT, [[0.3, 0.5], [0.5, 0.8]]],
                     r"cracks\[0\] and cracks\[1\] cross or touch near \(0.3, 0.5\)"),
    "on the boundary": ([[[0.0, 0.0], [0.5, 0.0]]],
                        r"cracks\[0\]: segment 0 lies on the boundary 'bottom'"),
    "on the boundary, second crack": ([SLIT, [[1.0, 0.2], [1.0, 0.4], [0.8, 0.4]]],
                                      r"cracks\[1\]: segment 0 lies on the boundary 'right'"),
    "outside": ([[[0.0, 0.5], [1.3, 0.5]]], r"cracks\[0\].points: point \[1.3, 0.5\] lies outside"),
}

BAD_3D = {
    "repeated corner (closed by hand)": ([BOX_CRACK + [BOX_CRACK[0]]],
                                         r"cracks\[0\]: corner 4 repeats corner 0.*list each corner once"),
    "non-planar": ([[[0.0, 0.5, 0.0], [0.3, 0.5, 0.0], [0.3, 0.6, 0.1], [0.0, 0.5, 0.1]]],
                   r"cracks\[0\].points = .*must be planar"),
    "no area": ([[[0.0, 0.5, 0.0], [0.3, 0.5, 0.0], [0.6, 0.5, 0.0]]], r"cracks\[0\].points = .*no area"),
    "self-intersecting": ([[[0.0, 0.5, 0.0], [0.3, 0.5, 0.0], [0.0, 0.5, 0.1], [0.2, 0.5, 0.1]]],
                          r"cracks\[0\]: edges 1 and 3 of the polygon cross or touch"),
    "on a face": ([[[0.0, 0.0, 0.0], [0.3, 0.0, 0.0], [0.3, 0.0, 0.1], [0.0, 0.0, 0.1]]],
                  r"cracks\[0\]: the polygon lies on the boundary 'bottom'"),
    "outside": ([[[0.0, 0.5, 0.0], [1.3, 0.5, 0.0], [0.3, 0.5, 0.1]]],
                r"cracks\[0\].points: point \[1.3, 0.5, 0.0\] lies outside"),
    "cracks cross": ([BOX_CRACK, [[0.2, 0.3, 0.05], [0.2, 0.7, 0.05], [0.2, 0.7, 0.08], [0.2, 0.3, 0.08]]],
                     r"cracks\[0\] and cracks\[1\] cross or touch near \(0.2, 0.5, 0.05\)"),
    "cracks share an edge": ([BOX_CRACK, [[0.3, 0.5, 0.0], [0.5, 0.5, 0.0], [0.5, 0.5, 0.1],
                                          [0.3, 0.5, 0.1]]],
                             r"cracks\[0\] and cracks\[1\] cross or touch"),
}

BAD_EXPRESSIONS = {
    "load nan": ("loads.0.value=\"sqrt(-1)*t\"",
                 r"loads\[0\].value = 'sqrt\(-1\)\*t' is nan at \(x, y, t\) = \(0, 1, 0\) on boundary 'top'"),
    "load inf on its boundary": ("loads.1.value=\"1/(x - 0.5)\"",
                                 r"loads\[1\].value = '1/\(x - 0.5\)' is inf at \(x, y, t\) = \(0.5, 0, 0\)"),
    "load overflows late": ("loads.0.value=\"exp(3e4*t)\"",  # finite up to t = 0.0236
                            r"loads\[0\].value = 'exp\(3e4\*t\)' is inf at \(x, y, t\) = \(0, 1, 0.024\)"),
    "constant division by zero": ("loads.0.value=\"1/0\"", r"loads\[0\].value = '1/0' is inf"),
    "body force": ("material.body_force=\"log(x - 0.5)\"",
                   r"material.body_force = 'log\(x - 0.5\)' is nan at \(x, y, t\) = \(0, 0, 0\) in the domain"),
    "gamma": ("material.gamma=\"1/x\"", r"material.gamma = '1/x' is inf at \(x, y\) = \(0, 0\)"),
}


def bad_scene_file(case: str, folder: Path) -> tuple[Path, str]:
    """A scene file (in ``folder``) with the bad input ``case`` of any table, and the regular
    expression its message must match."""
    if case in BAD_EXPRESSIONS:
        override, match = BAD_EXPRESSIONS[case]
        data = apply_overrides(demo_data(), ["time.t_end=0.03", override])
    else:
        name, (cracks, match) = ("box3d", BAD_3D[case[3:]]) if case.startswith("3d ") else \
            ("mode3_slit", BAD_2D[case])
        data = copy.deepcopy(demo_data(name))
        data["cracks"] = [{"points": c} for c in cracks]
    path = folder / (case.replace(" ", "_").replace(",", "").replace("(", "").replace(")", "") + ".toml")
    path.write_text(to_toml(data))
    return path, match


ALL_CASES = [*BAD_2D, *(f"3d {c}" for c in BAD_3D), *BAD_EXPRESSIONS]
