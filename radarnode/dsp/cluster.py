"""DBSCAN clustering of detections, vectorised with a k-d tree and a connected-components pass over its edges."""

from __future__ import annotations

import numpy as np

from radarnode.errors import ConfigError


def dbscan(points: np.ndarray, eps: float, min_samples: int = 1) -> np.ndarray:
    """Density-based clustering (Ester et al., 1996).

    Parameters
    ----------
    points : array, shape (n, d)
        Already scaled so that one ``eps`` is the neighbourhood in every dimension.
    eps : float
    min_samples : int
        Neighbours (the point included) that make a core point.

    Returns
    -------
    labels : int array, shape (n,); -1 marks noise, clusters are numbered 0.. in order of first point.
    """
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2:
        raise ConfigError(f"dbscan points: shape {pts.shape} is not allowed; expected (n, d)")
    if not eps > 0 or min_samples < 1:
        raise ConfigError(f"dbscan: eps={eps!r}, min_samples={min_samples!r} are not allowed; expected > 0 and >= 1")
    n = pts.shape[0]
    if n == 0:
        return np.zeros(0, dtype=np.int64)
    import scipy.spatial  # imported when first needed: a faster start
    tree = scipy.spatial.cKDTree(pts)
    pairs = tree.query_pairs(eps, output_type="ndarray")
    counts = np.bincount(pairs.ravel(), minlength=n) + 1
    core = counts >= min_samples
    # core-core edges make clusters; a border point joins the cluster of one core neighbour
    cc = pairs[core[pairs[:, 0]] & core[pairs[:, 1]]]
    labels = np.where(core, components(n, cc), -1)
    border = pairs[core[pairs[:, 0]] ^ core[pairs[:, 1]]]
    if border.size:
        a = np.where(core[border[:, 0]], border[:, 0], border[:, 1])
        b = np.where(core[border[:, 0]], border[:, 1], border[:, 0])
        labels[b] = labels[a]
    # renumber 0.. in order of first appearance
    valid = labels >= 0
    _, first, inverse = np.unique(labels[valid], return_index=True, return_inverse=True)
    order = np.argsort(np.argsort(first))
    out = np.full(n, -1, dtype=np.int64)
    out[valid] = order[inverse]
    return out


def components(n: int, edges: np.ndarray) -> np.ndarray:
    """Connected components of the undirected graph of ``n`` nodes and ``edges`` (k, 2): each node's label is the
    smallest node index of its component.

    Label propagation over all edges at once (each end takes the smaller label of the two), with pointer jumping
    (a label takes its own node's label) so that a long chain — guardrail posts one after the other — settles in
    a few passes; it stops when no edge joins two labels. A few numpy passes over the edges: for the few hundred
    edges of a radar cycle, a tenth of building a sparse matrix for scipy's connected_components.
    """
    labels = np.arange(n)
    if len(edges) == 0:
        return labels
    i, j = edges[:, 0], edges[:, 1]
    while True:
        low = np.minimum(labels[i], labels[j])
        new = labels.copy()
        np.minimum.at(new, i, low)
        np.minimum.at(new, j, low)
        while True:                       # pointer jumping to the fixed point: new[k] is a root
            jumped = new[new]
            if np.array_equal(jumped, new):
                break
            new = jumped
        if np.array_equal(new, labels):
            return labels
        labels = new
