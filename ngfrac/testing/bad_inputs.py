"""Bad scene inputs, each with the one-line message it must give (tests/scene/test_checks.py
checks them on the API, tests/io/test_cli.py on the command line)."""
from __future__ import annotations

import copy
from pathlib import Path
from typing import Any, Callable

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


# -- CAD domains (geometry.kind = "occ"): the plate_hole demo with one thing wrong ---------------

def _plate(folder: Path) -> dict[str, Any]:
    return copy.deepcopy(demo_data("plate_hole"))


def _with_geometry(**geometry: Any) -> Callable[[Path], dict[str, Any]]:
    def make(folder: Path) -> dict[str, Any]:
        data = _plate(folder)
        data["geometry"].update(geometry)
        return data
    return make


def _from_file(name: str, text: str | None = None, shape: str = "", model: str = "",
               **geometry: Any) -> Callable[[Path], dict[str, Any]]:
    """The plate read from a file in ``folder``: ``text`` written as is, or a netgen.occ
    ``shape`` ("face": the unit square, "box": the unit cube, "two faces": the square and another
    one beside it) written as STEP, or no file."""
    def make(folder: Path) -> dict[str, Any]:
        path = folder / name
        if text is not None:
            path.write_text(text)
        elif shape:
            from netgen import occ

            square = occ.WorkPlane().Rectangle(1, 1).Face()
            part = {"face": square, "box": occ.Box(occ.Pnt(0, 0, 0), occ.Pnt(1, 1, 1)),
                    "two faces": occ.Glue([square, occ.WorkPlane().MoveTo(2, 0).Rectangle(1, 1).Face()])
                    }[shape]
            part.WriteStep(str(path))
        data = _plate(folder)
        data["geometry"] = {"kind": "occ", "file": str(path),
                            "boundaries": data["geometry"]["boundaries"][:2], **geometry}
        if model:
            data["model"] = {"kind": model}
            data["material"] = {"E": 1.0, "nu": 0.3, "gamma": 1.0}
            data["loads"] = [{"boundary": "top", "value": ["0", "t", "0"]},
                             {"boundary": "bottom", "value": ["0", "0", "0"]}]
        return data
    return make


def _with(key: str, value: Any) -> Callable[[Path], dict[str, Any]]:
    def make(folder: Path) -> dict[str, Any]:
        data = _plate(folder)
        data[key] = value
        return data
    return make


_HOLE = {"type": "circle", "center": [0.5, 0.5], "radius": 0.1, "op": "cut"}
_BOTTOM_AND_TOP = [{"name": "bottom", "normal": [0.0, -1.0]}, {"name": "top", "normal": [0.0, 1.0]}]
_Y_NORMALS_3D = [{"name": "bottom", "normal": [0, -1, 0]}, {"name": "top", "normal": [0, 1, 0]}]

BAD_CAD: dict[str, tuple[Callable[[Path], dict[str, Any]], str]] = {
    # name: (scene data in a folder, fragment of the one-line message)
    "cad file missing": (_from_file("missing.step"),
                         r"geometry.file = '.*missing.step': no CAD file"),
    "cad file unreadable": (_from_file("broken.step", text="not a STEP file\n"),
                            r"geometry.file = '.*broken.step': OCC cannot read it as a STEP file"),
    "cad file damaged brep": (_from_file("broken.brep", text="DBRep_DrawableShape\n"),
                              r"geometry.file = '.*broken.brep': OCC cannot read it as a BREP file"),
    "cad file of another type": (_from_file("part.stl", text="solid part\n"),
                                 r"'part.stl' is not a CAD file ngfrac reads; give a .brep"),
    "2d file for a 3d model": (_from_file("face.step", shape="face", model="elasticity_3d"),
                               r"geometry.file = '.*face.step' is 2D \(faces, no solid\) but "
                               r"model.kind = 'elasticity_3d' is 3D"),
    "3d solid for a 2d model": (_from_file("box.step", shape="box", boundaries=_Y_NORMALS_3D),
                                r"geometry.file = '.*box.step' is 3D \(a solid\) but "
                                r"model.kind = 'plane_strain' is 2D"),
    "2d selector on a 3d solid": (_from_file("box.step", shape="box", model="elasticity_3d"),
                                  r"geometry.boundaries\[0\].normal = \[0.0, -1.0\] has 2 "
                                  r"coordinates but the shape is 3D; give 3"),
    "selector matches nothing": (_with_geometry(boundaries=[*_BOTTOM_AND_TOP,
                                                            {"name": "hole", "point": [5.0, 5.0]}]),
                                 r"geometry.boundaries\[2\] \(name = 'hole', point = \[5.0, 5.0\]\) "
                                 r"matches no edge"),
    "two names claim one edge": (_with_geometry(boundaries=[*_BOTTOM_AND_TOP,
                                                            {"name": "base", "box": [[0, 0], [1, 0]]}]),
                                 r"geometry.boundaries\[0\] \('bottom'\) and geometry.boundaries\[2\] "
                                 r"\('base'\) claim the same edge"),
    "split point on no edge": (_with_geometry(split_points=[[0.5, 0.5]]),
                               r"geometry.split_points\[0\] = \[0.5, 0.5\] lies on no boundary edge"),
    "crack outside the plate": (_with("cracks", [{"points": [[0.0, 0.2], [1.3, 0.2]]}]),
                                r"cracks\[0\].points: point \[1.3, 0.2\] lies outside the domain"),
    "crack ends in the hole": (_with("cracks", [{"points": [[0.0, 0.5], [0.5, 0.5]]}]),
                               r"cracks\[0\].points: point \[0.5, 0.5\] lies outside the domain"),
    "crack crosses the hole": (_with("cracks", [{"points": [[0.0, 0.5], [0.8, 0.5]]}]),
                               r"cracks\[0\]: it leaves the domain near \(0.4.*\(a hole or notch"),
    "load on a missing boundary": (_with("loads", [{"boundary": "bottom", "value": ["0", "0"]},
                                                   {"boundary": "left", "value": ["t", "0"]}]),
                                   r"loads\[1\].boundary = 'left' is not a boundary of the "
                                   r"geometry; boundaries are bottom, .*hole"),
    "holes empty the plate": (_with_geometry(shapes=[
        {"type": "rectangle", "corner": [0.0, 0.0], "size": [1.0, 1.0]},
        {**_HOLE, "center": [0.25, 0.5], "radius": 0.75}, {**_HOLE, "center": [0.75, 0.5], "radius": 0.75}]),
        r"geometry.shapes\[2\] \(cut circle\) leaves nothing of the domain"),
    "cut leaves nothing": (_with_geometry(shapes=[
        {"type": "rectangle", "corner": [0.0, 0.0], "size": [1.0, 1.0]},
        {"type": "rectangle", "corner": [-1.0, -1.0], "size": [3.0, 3.0], "op": "cut"}]),
        r"geometry.shapes\[1\] \(cut rectangle\) leaves nothing of the domain"),
    "3d cut leaves nothing": (_with_geometry(shapes=[
        {"type": "box", "corner": [0.0, 0.0, 0.0], "size": [1.0, 1.0, 1.0]},
        {"type": "sphere", "center": [0.5, 0.5, 0.5], "radius": 2.0, "op": "cut"}], boundaries=[]),
        r"geometry.shapes\[1\] \(cut sphere\) leaves nothing of the domain"),
    "cut splits the plate": (_with_geometry(shapes=[
        {"type": "rectangle", "corner": [0.0, 0.0], "size": [1.0, 1.0]},
        {"type": "rectangle", "corner": [-0.5, 0.45], "size": [2.0, 0.1], "op": "cut"}]),
        r"geometry.shapes make 2 separate pieces \(a cut through the domain"),
    "a shape apart from the plate": (_with_geometry(shapes=[
        {"type": "rectangle", "corner": [0.0, 0.0], "size": [1.0, 1.0]},
        {"type": "circle", "center": [2.0, 0.5], "radius": 0.1}]),
        r"geometry.shapes make 2 separate pieces"),
    "3d solids apart": (_with_geometry(shapes=[
        {"type": "box", "corner": [0.0, 0.0, 0.0], "size": [1.0, 1.0, 1.0]},
        {"type": "sphere", "center": [3.0, 0.5, 0.5], "radius": 0.5}], boundaries=[]),
        r"geometry.shapes make 2 separate pieces"),
    "cad file of two parts": (_from_file("two.step", shape="two faces"),
                              r"geometry.file = '.*two.step' holds 2 separate pieces"),
}
"""Bad CAD inputs (issue #12, item 5): each is one line, exit 2, in ``ngfrac check`` and ``run``."""


def bad_scene_file(case: str, folder: Path) -> tuple[Path, str]:
    """A scene file (in ``folder``) with the bad input ``case`` of any table, and the regular
    expression its message must match."""
    if case in BAD_CAD:
        make, match = BAD_CAD[case]
        data = make(folder)
    elif case in BAD_EXPRESSIONS:
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


ALL_CASES = [*BAD_2D, *(f"3d {c}" for c in BAD_3D), *BAD_EXPRESSIONS, *BAD_CAD]
