"""k-nearest-neighbour queries on a point set that grows one point at a time (an RRT tree).

A k-d tree cannot take insertions, so :class:`GrowingNearest` keeps a :class:`scipy.spatial.cKDTree` of a
snapshot and scans the points added since then by brute force, rebuilding the snapshot when that buffer
passes ``rebuild_every`` points. A query costs one tree query plus a scan of at most ``rebuild_every``
points; the rebuilds cost ``O(n log n)`` each, ``n / rebuild_every`` times in all.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from oceanloc._typing import FloatArray, IntArray

if TYPE_CHECKING:
    from scipy.spatial import cKDTree


class GrowingNearest:
    """k nearest neighbours among points added so far.

    Parameters
    ----------
    capacity : int
        Maximum number of points.
    rebuild_every : int
        Size of the brute-force buffer that triggers a k-d tree rebuild.
    """

    def __init__(self, capacity: int, rebuild_every: int = 2048) -> None:
        self._points = np.empty((max(capacity, 1), 2))
        self._n = 0
        self._tree: cKDTree | None = None
        self._n_tree = 0
        self._rebuild_every = rebuild_every

    def __len__(self) -> int:
        return self._n

    @property
    def points_m(self) -> FloatArray:
        """``(n, 2)`` the points added so far (a view)."""
        return self._points[: self._n]

    def add(self, x_m: float, y_m: float) -> int:
        """Add a point; returns its index."""
        if self._n == self._points.shape[0]:
            grown = np.empty((2 * self._points.shape[0], 2))
            grown[: self._n] = self._points[: self._n]
            self._points = grown
        i = self._n
        self._points[i, 0] = x_m
        self._points[i, 1] = y_m
        self._n += 1
        return i

    def query(self, x_m: float, y_m: float, k: int, exclude: int = -1) -> tuple[FloatArray, IntArray]:
        """Distances and indices of the ``k`` nearest points, ascending; ``exclude`` is left out."""
        if self._n - self._n_tree > self._rebuild_every:
            from scipy.spatial import cKDTree

            self._tree = cKDTree(self._points[: self._n])
            self._n_tree = self._n
        kk = k + (1 if exclude >= 0 else 0)
        dists: list[FloatArray] = []
        idxs: list[IntArray] = []
        if self._tree is not None and self._n_tree:
            m = min(kk, self._n_tree)
            d, i = self._tree.query((x_m, y_m), k=m)
            dists.append(np.atleast_1d(d))
            idxs.append(np.atleast_1d(i))
        if self._n > self._n_tree:
            buf = self._points[self._n_tree : self._n]
            d = np.hypot(buf[:, 0] - x_m, buf[:, 1] - y_m)
            part = np.argpartition(d, kk - 1)[:kk] if d.size > kk else np.arange(d.size)
            dists.append(d[part])
            idxs.append(part + self._n_tree)
        d = np.concatenate(dists)
        i = np.concatenate(idxs)
        if exclude >= 0:
            keep = i != exclude
            d, i = d[keep], i[keep]
        order = np.argsort(d, kind="stable")[:k]
        return d[order], i[order]
