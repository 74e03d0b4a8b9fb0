"""DBSCAN clustering of detections, vectorised with a k-d tree and a sparse connected-components pass."""

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
    import scipy.sparse  # imported when first needed: a faster start
    graph = scipy.sparse.coo_matrix((np.ones(len(cc)), (cc[:, 0], cc[:, 1])), shape=(n, n))
    import scipy.sparse.csgraph  # imported when first needed: a faster start
    _, comp = scipy.sparse.csgraph.connected_components(graph, directed=False)
    labels = np.where(core, comp, -1)
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
