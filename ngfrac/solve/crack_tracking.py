"""The crack of the current z, followed from step to step: where it started and its tip."""
from __future__ import annotations

import numpy as np

from ..physics.crack_models import CrackModel
from ..post.crackset import CrackSet, NodeGraph, find_crack
from ..post.diagnostics import element_diameters
from ..mesh.fields import MeshFields


class CrackTracker:
    """Finds the crack set of z (:func:`ngfrac.post.crackset.find_crack`) on the current
    fields and keeps what later steps need: the nucleus (with no initial crack, where z first
    reached 1/2) and the previous tip (a tip never moves back along the crack).

    Parameters
    ----------
    polylines : list of point arrays
        The initial cracks.
    start_tip : numpy.ndarray or None
        The interior end of the first initial crack.
    crack_model : CrackModel
    epsilon : float
    h_band : float or None
        The band's element size of an adaptive run; None: the largest element of the mesh.
    """

    def __init__(self, polylines: list, start_tip: np.ndarray | None, crack_model: CrackModel,
                 epsilon: float, h_band: float | None) -> None:
        self.polylines, self.start_tip = polylines, start_tip
        self.half_width, self.epsilon, self.h_band = crack_model.half_width(epsilon), epsilon, h_band
        self.nucleus: np.ndarray | None = None
        self.previous_tip: np.ndarray | None = None
        self._fields: MeshFields | None = None
        self._graph: NodeGraph | None = None
        self._sizes: np.ndarray | None = None
        self._cache: tuple[bytes, CrackSet] | None = None

    def element_sizes(self, fields: MeshFields) -> np.ndarray:
        """The element diameters of the fields' mesh (cached per mesh)."""
        self._use(fields)
        if self._sizes is None:
            self._sizes = element_diameters(fields.mesh)
        return self._sizes

    def _use(self, fields: MeshFields) -> None:
        if fields is not self._fields:
            self._fields, self._graph, self._sizes, self._cache = fields, None, None, None

    def forget(self) -> None:
        """Drop the cached crack set (after z was set from outside, e.g. a restored state)."""
        self._cache = None

    def crack(self, fields: MeshFields) -> CrackSet:
        """The crack set of the current z (cached while z is unchanged)."""
        self._use(fields)
        values = fields.z_values()
        key = values.tobytes()
        if self._cache is not None and self._cache[0] == key:
            return self._cache[1]
        sizes = self.element_sizes(fields)
        if self._graph is None:
            self._graph = NodeGraph(fields.mesh, fields.nodes)
        near = self.h_band if self.h_band is not None else float(sizes.max())
        if not self.polylines and self.nucleus is None and values.size and values.max() >= 0.5:
            self.nucleus = fields.nodes.points[int(np.argmax(values))].copy()
        found = find_crack(self._graph, values, self.polylines, self.start_tip,
                           band=self.half_width + near, bin_width=2 * self.epsilon,
                           nucleus=self.nucleus, previous_tip=self.previous_tip)
        self._cache = (key, found)
        self.previous_tip = found.tip.copy()
        return found
