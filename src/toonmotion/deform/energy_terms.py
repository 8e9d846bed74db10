"""Eq. 3.8's terms as sparse rows over a mesh's vertices (thesis 3.4.3): the RSI Laplacians of the
outline (``E1``, eq. 3.3), the mean value coordinates of the inner vertices (``E2``, eq. 3.6), the
edges (``E3``, eq. 3.7, per edge or per triangle), the anchors (``E4``) and the mesh's signed area
as a Hermitian form. Points are complex numbers ``x + iy``. Each mesh's rows are built once and
kept while the mesh lives (:func:`every_row`); :class:`~toonmotion.deform.joint_solve.JointSolver`
takes the rows of its free vertices."""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from toonmotion.geometry.coordinates import (
    as_complex,
    mean_value_weights,
    rsi_laplacian_coefficients,
)
from toonmotion.shape.mesh import Mesh, unique_edges


@dataclass(frozen=True, eq=False)
class EveryRow:
    """Eq. 3.8's rows with every vertex free: a solver for any joint area takes its rows from
    these (the rows of a free vertex, or of a triangle or edge touching one, do not depend on
    which others are free), so a widened joint area costs a factorisation, not a rebuild."""

    laplacian: sp.csr_matrix  # E1, a row per outline vertex, loop by loop
    laplacian_vertex: NDArray[np.int64]
    mean_value: sp.csr_matrix  # E2, a row per inner vertex
    mean_value_vertex: NDArray[np.int64]
    triangle_edges: NDArray[np.int64]  # (3t, 2): E3 rigid, three rows per triangle
    triangle_edge_rows: sp.csr_matrix
    edges: NDArray[np.int64]  # (e, 2): E3 length, a row per edge
    edge_rows: sp.csr_matrix


# Each mesh's rows, kept while the mesh lives.
_EVERY_ROW: weakref.WeakKeyDictionary[Mesh, EveryRow] = weakref.WeakKeyDictionary()


def every_row(mesh):
    """The mesh's :class:`EveryRow`, built on first use and kept while the mesh lives."""
    if mesh not in _EVERY_ROW:
        every = np.ones(len(mesh.V), bool)
        inner = np.arange(mesh.n_outline, len(mesh.V))
        triangle_edges, triangle_rows, _ = triangle_edge_rows(mesh, every)
        edges, rows = edge_rows(mesh, every)
        _EVERY_ROW[mesh] = EveryRow(
            laplacian_rows(mesh, as_complex(mesh.V), every).tocsr(),
            np.concatenate(mesh.boundary) if mesh.boundary else np.zeros(0, np.int64),
            mean_value_rows(mesh, every).tocsr(), inner,
            triangle_edges, triangle_rows.tocsr(), edges, rows.tocsr())
    return _EVERY_ROW[mesh]


def anchor_rows(anchors, n):
    """E4 rows: one per anchored point, its barycentric combination of its triangle's corners."""
    a = len(anchors.corners)
    rows = np.repeat(np.arange(a), 3)
    return sp.csr_matrix((anchors.barycentric.ravel().astype(complex), (rows, anchors.corners.ravel())),
                         shape=(a, n))


def area_form(F, n):
    """``M``, ``(n, n)`` Hermitian, with ``Re(z^H M z) / 2`` the total signed area of triangles
    ``F`` (as :func:`~toonmotion.geometry.polygon.triangle_areas`, positive counter-clockwise
    on screen): each corner's gradient is ``i/2 (next corner - previous corner)``."""
    F = np.asarray(F)
    rows = np.concatenate([F.ravel(), F.ravel()])
    cols = np.concatenate([np.roll(F, -1, axis=1).ravel(), np.roll(F, 1, axis=1).ravel()])
    vals = np.concatenate([np.full(F.size, 0.5j), np.full(F.size, -0.5j)])
    return sp.csr_matrix((vals, (rows, cols)), shape=(n, n))


def laplacian_rows(mesh, rest, free):
    """E1 rows: one per free outline vertex, ``u - (u_prev + u_next)/2 - c (u_next - u_prev)``."""
    rows, cols, vals = [], [], []
    count = 0
    for loop in mesh.boundary:
        prev, after = np.roll(loop, 1), np.roll(loop, -1)
        keep = free[loop]
        c = rsi_laplacian_coefficients(mesh.V[prev[keep]], mesh.V[loop[keep]], mesh.V[after[keep]])
        k = int(keep.sum())
        r = np.arange(count, count + k)
        rows += [r, r, r]
        cols += [loop[keep], prev[keep], after[keep]]
        vals += [np.ones(k, complex), -0.5 + c, -0.5 - c]
        count += k
    return sparse_rows(rows, cols, vals, count, len(mesh.V))


def mean_value_rows(mesh, free):
    """E2 rows: one per free inner vertex, ``u_i - sum_j w_ij u_j``."""
    inner = free.copy()
    inner[: mesh.n_outline] = False
    r, c, w = mean_value_weights(mesh.V, mesh.F)
    keep = inner[r]
    index = np.cumsum(inner) - 1
    ids = np.flatnonzero(inner)
    rows = [index[ids], index[r[keep]]]
    cols = [ids, c[keep]]
    vals = [np.ones(len(ids), complex), -w[keep].astype(complex)]
    return sparse_rows(rows, cols, vals, len(ids), len(mesh.V))


def edge_rows(mesh, free):
    """E3 rows: one per edge touching a free vertex, ``u_i - u_j``."""
    edges = unique_edges(mesh.F)
    edges = edges[free[edges[:, 0]] | free[edges[:, 1]]]
    k = np.arange(len(edges))
    A = sparse_rows([k, k], [edges[:, 0], edges[:, 1]], [np.ones(len(k), complex), -np.ones(len(k), complex)],
                len(edges), len(mesh.V))
    return edges, A


def triangle_edge_rows(mesh, free):
    """E3 rows, rigid form: three per triangle touching a free vertex, one for each edge."""
    triangles = np.flatnonzero(free[mesh.F].any(axis=1))
    F = mesh.F[triangles]
    edges = np.stack([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]], axis=1).reshape(-1, 2)
    k = np.arange(len(edges))
    A = sparse_rows([k, k], [edges[:, 0], edges[:, 1]], [np.ones(len(k), complex), -np.ones(len(k), complex)],
                len(edges), len(mesh.V))
    return edges, A, F


def sparse_rows(rows, cols, vals, shape0, shape1):
    if not rows:
        return sp.csr_matrix((shape0, shape1), dtype=complex)
    return sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(shape0, shape1)
    )

