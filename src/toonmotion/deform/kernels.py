"""Stage two's iterations compiled with Numba: the loop of
:meth:`~toonmotion.deform.joint_solve.JointSolver.solve` for the rigid edge term, with no Python
between iterations.

Each iteration is the same arithmetic as the NumPy loop in ``joint_solve`` (which stays the
reference, and runs for the thesis' edge-length term): the local step (each joint triangle's
best rotation, eq. 3.8's energy), the right-hand side, two triangular solves with SuperLU's
factors, the area correction, and Anderson mixing. At the mesh sizes stage two works on (a few
hundred free vertices) an iteration costs tens of microseconds here against a few hundred in
NumPy and SciPy, whose per-call overhead is most of their time.

Compiled functions are cached on disk (Numba's ``cache=True``), so only the first use on a
machine compiles them (a few seconds); :func:`warm_up` loads them when a solver is built, so a
first pose pays no compilation.

Sparse matrices are passed as CSR or CSC triples ``(pointers, indices, values)``; complex
numbers are points ``x + iy`` as in ``joint_solve``.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _matvec(ptr, idx, val, x, out):
    """``out = A @ x`` for CSR ``A``."""
    for row in range(len(ptr) - 1):
        total = 0j
        for k in range(ptr[row], ptr[row + 1]):
            total += val[k] * x[idx[k]]
        out[row] = total


@njit(cache=True)
def _solve(factor, a, b, work_a, work_b, two):
    """``N^-1 a`` into ``a`` and, when ``two``, ``N^-1 b`` into ``b``, with SuperLU's factors
    ``Pr N Pc = L U``: ``factor`` is ``(L ptr, L rows, L values, U ptr, U rows, U values, U diagonal
    positions, perm_r, perm_c)``, L and U as CSC, L with a unit diagonal. Two right-hand sides go
    through the factors together: one pass over their entries, most of the cost, serves both."""
    lp, li, lv, up, ui, uv, ud, perm_r, perm_c = factor
    m = len(a)
    for i in range(m):
        work_a[perm_r[i]] = a[i]
        if two:
            work_b[perm_r[i]] = b[i]
    for j in range(m):  # L y = Pr a, column by column
        ya = work_a[j]
        yb = work_b[j] if two else 0j
        for k in range(lp[j], lp[j + 1]):
            r = li[k]
            if r != j:
                work_a[r] -= lv[k] * ya
                if two:
                    work_b[r] -= lv[k] * yb
    for j in range(m - 1, -1, -1):  # U w = y
        pivot = uv[ud[j]]
        wa = work_a[j] / pivot
        work_a[j] = wa
        wb = 0j
        if two:
            wb = work_b[j] / pivot
            work_b[j] = wb
        for k in range(up[j], up[j + 1]):
            r = ui[k]
            if r != j:
                work_a[r] -= uv[k] * wa
                if two:
                    work_b[r] -= uv[k] * wb
    for i in range(m):
        a[i] = work_a[perm_c[i]]
        if two:
            b[i] = work_b[perm_c[i]]


@njit(cache=True)
def _local(z, linear, anchors, anchor_target, anchor_weights, corners, rest, w3, targets, scratch):
    """The local step at ``z``: every joint triangle's rest edges turned by its best rotation into
    ``targets`` (``(3t,)``), and eq. 3.8's energy at ``z`` (plus the anchors' term, each anchor
    weighted by ``anchor_weights``: 0 for one let go)."""
    lp, li, lv = linear
    _matvec(lp, li, lv, z, scratch[0])
    energy = 0.0
    for v in scratch[0]:
        energy += v.real * v.real + v.imag * v.imag
    ap, ai, av = anchors
    if len(ap) > 1:
        off = scratch[1][: len(ap) - 1]
        _matvec(ap, ai, av, z, off)
        for k in range(len(off)):
            d = off[k] - anchor_target[k]
            energy += anchor_weights[k] * (d.real * d.real + d.imag * d.imag)
    edges = 0.0
    for t in range(len(corners)):
        c0, c1, c2 = z[corners[t, 0]], z[corners[t, 1]], z[corners[t, 2]]
        e0, e1, e2 = c0 - c1, c1 - c2, c2 - c0
        r0, r1, r2 = rest[t, 0], rest[t, 1], rest[t, 2]
        fit = np.conj(r0) * e0 + np.conj(r1) * e1 + np.conj(r2) * e2
        size = abs(fit)
        turn = fit / size if size > 1e-300 else 1.0 + 0j
        t0, t1, t2 = turn * r0, turn * r1, turn * r2
        targets[3 * t], targets[3 * t + 1], targets[3 * t + 2] = t0, t1, t2
        d0, d1, d2 = e0 - t0, e1 - t1, e2 - t2
        edges += (d0.real * d0.real + d0.imag * d0.imag + d1.real * d1.real + d1.imag * d1.imag
                  + d2.real * d2.real + d2.imag * d2.imag)
    return energy + w3 * edges


@njit(cache=True)
def _release(release, x, small):
    """``x`` (the normal matrix's solve) corrected in place for the anchors let go, by the
    Woodbury identity: ``x += Y S^-1 (C x)``; ``release`` is ``(C columns, C values, Y, S^-1)``
    (``JointSolver._release``), C with at most three entries a row."""
    cols, vals, Y, inverse = release
    r = cols.shape[0]
    for a in range(r):
        total = 0j
        for k in range(3):
            total += vals[a, k] * x[cols[a, k]]
        small[a] = total
    for a in range(r):
        total = 0j
        for b in range(r):
            total += inverse[a, b] * small[b]
        small[r + a] = total
    for i in range(len(x)):
        total = 0j
        for a in range(r):
            total += Y[i, a] * small[r + a]
        x[i] += total


@njit(cache=True)
def _moving_area(area_form, z, free, Mz):
    """The moving triangles' signed area at ``z`` (``Re(z^H M z) / 2``); ``Mz`` is filled."""
    mp, mi, mv = area_form
    _matvec(mp, mi, mv, z, Mz)
    total = 0.0
    for i in range(len(z)):
        total += (np.conj(z[i]) * Mz[i]).real
    return 0.5 * total


@njit(cache=True)
def _mix(x, step, df, dg, last_f, last_g, count, has_last, out):
    """Anderson's next point after ``x`` whose plain step is ``step`` (the NumPy loop's
    ``_Anderson.mix``): ``df``, ``dg`` hold the last ``count`` differences, oldest first. Returns
    the new count and whether a past step exists; ``out`` gets the point."""
    depth = df.shape[0]
    f = step - x
    if has_last:
        if count == depth:  # drop the oldest
            for k in range(depth - 1):
                df[k, :] = df[k + 1, :]
                dg[k, :] = dg[k + 1, :]
            count -= 1
        df[count, :] = f - last_f
        dg[count, :] = step - last_g
        count += 1
    last_f[:] = f
    last_g[:] = step
    out[:] = step
    if count == 0:
        return count, True
    gram = np.empty((count, count))
    right = np.empty(count)
    for a in range(count):
        right[a] = np.vdot(df[a], f).real
        for b in range(count):
            gram[a, b] = np.vdot(df[a], df[b]).real
        gram[a, a] *= 1 + 1e-10
    gamma = _small_solve(gram, right)
    if gamma is None:
        return 0, False
    for a in range(count):
        out[:] -= gamma[a] * dg[a]
    return count, True


@njit(cache=True)
def _small_solve(A, b):
    """``A^-1 b`` for a small dense system by elimination with partial pivoting; None when
    singular."""
    n = len(b)
    A, b = A.copy(), b.copy()
    scale = max(np.abs(A).max(), 1e-300)
    for col in range(n):
        pivot = col + np.argmax(np.abs(A[col:, col]))
        if abs(A[pivot, col]) <= 1e-14 * scale:
            return None
        if pivot != col:
            for k in range(n):
                A[col, k], A[pivot, k] = A[pivot, k], A[col, k]
            b[col], b[pivot] = b[pivot], b[col]
        for row in range(col + 1, n):
            factor = A[row, col] / A[col, col]
            A[row, col:] -= factor * A[col, col:]
            b[row] -= factor * b[col]
    x = np.empty(n)
    for row in range(n - 1, -1, -1):
        x[row] = (b[row] - np.dot(A[row, row + 1:], x[row + 1:])) / A[row, row]
    return x


@njit(cache=True)
def energy(z, linear, anchors, anchor_target, anchor_weights, corners, rest, w3):
    """Eq. 3.8 at ``z`` (plus the anchors' term): the local step's energy alone."""
    targets = np.empty(3 * len(corners), np.complex128)
    scratch = (np.empty(linear[0].shape[0] - 1, np.complex128),
               np.empty(max(anchors[0].shape[0] - 1, 1), np.complex128))
    return _local(z, linear, anchors, anchor_target, anchor_weights, corners, rest, w3, targets, scratch)


@njit(cache=True)
def iterate(z, free, base, linear, anchors, anchor_target, anchor_weights, corners, rest, w3,
            from_edges, factor, release, area_form, area, has_area, max_iterations, tolerance, floor, depth):
    """Stage two's iterations from ``z`` (modified in place): the NumPy loop of
    ``JointSolver.solve`` after its start: it has converged when a plain step changes the energy by
    at most ``tolerance`` of it plus ``floor``. ``release``: the anchors let go (:func:`_release`).
    Returns ``(iterations, energy, converged)``."""
    n, m = len(z), len(free)
    targets = np.empty(3 * len(corners), np.complex128)
    scratch = (np.empty(linear[0].shape[0] - 1, np.complex128),
               np.empty(max(anchors[0].shape[0] - 1, 1), np.complex128))
    energy = _local(z, linear, anchors, anchor_target, anchor_weights, corners, rest, w3, targets, scratch)
    rhs, step, direction = np.empty(m, np.complex128), np.empty(m, np.complex128), np.empty(m, np.complex128)
    work, work_b = np.empty(m, np.complex128), np.empty(m, np.complex128)
    Mz, moved = np.empty(n, np.complex128), np.empty(n, np.complex128)
    tried, tried_targets = np.empty(n, np.complex128), np.empty(len(targets), np.complex128)
    x, mixed = np.empty(m, np.complex128), np.empty(m, np.complex128)
    size = max(depth, 1)
    df, dg = np.empty((size, m), np.complex128), np.empty((size, m), np.complex128)
    last_f, last_g = np.empty(m, np.complex128), np.empty(m, np.complex128)
    count, has_last, mixing = 0, False, depth > 0
    ep, ei, ev = from_edges
    released = release[0].shape[0] > 0
    small = np.empty(2 * release[0].shape[0], np.complex128)
    iterations, converged = 0, False
    while iterations < max_iterations and not converged:
        iterations += 1
        # The global step: solve with the local step's targets, then keep the area.
        _matvec(ep, ei, ev, targets, rhs)
        rhs += base
        if has_area:  # the step and the correction's direction, N^-1 g, solved together
            _moving_area(area_form, z, free, Mz)
            step[:] = rhs
            for i in range(m):
                direction[i] = Mz[free[i]]
            _solve(factor, step, direction, work, work_b, True)
            if released:
                _release(release, step, small)
                _release(release, direction, small)
            moved[:] = z
            for i in range(m):
                moved[free[i]] = step[i]
            now = _moving_area(area_form, moved, free, Mz)
            slope = 0.0
            for i in range(m):
                slope += (np.conj(Mz[free[i]]) * direction[i]).real
            if slope > 1e-12 * max(abs(now), 1.0):
                step += ((area - now) / slope) * direction
        else:
            step[:] = rhs
            _solve(factor, step, direction, work, work_b, False)
            if released:
                _release(release, step, small)
        if depth > 0 and mixing:
            for i in range(m):
                x[i] = z[free[i]]
            count, has_last = _mix(x, step, df, dg, last_f, last_g, count, has_last, mixed)
            tried[:] = z
            for i in range(m):
                tried[free[i]] = mixed[i]
            tried_energy = _local(tried, linear, anchors, anchor_target, anchor_weights, corners, rest, w3,
                                  tried_targets, scratch)
            if tried_energy < energy:
                z[:] = tried
                targets[:] = tried_targets
                if energy - tried_energy <= tolerance * energy:
                    count, has_last, mixing = 0, False, False
                energy = tried_energy
                continue
            count, has_last, mixing = 0, False, False
        elif depth > 0:
            count, has_last, mixing = 0, False, True
        for i in range(m):
            z[free[i]] = step[i]
        new_energy = _local(z, linear, anchors, anchor_target, anchor_weights, corners, rest, w3, targets,
                            scratch)
        converged = abs(energy - new_energy) <= tolerance * energy + floor
        energy = new_energy
    return iterations, energy, converged


def csr(matrix):
    """A SciPy sparse matrix as the CSR triple the kernels take (int64 indices, complex values)."""
    matrix = matrix.tocsr()
    return (matrix.indptr.astype(np.int64), matrix.indices.astype(np.int64),
            matrix.data.astype(np.complex128))


def lu_factors(lu):
    """SciPy's ``splu`` result as the tuple :func:`_solve` takes."""
    L, U = lu.L.tocsc(), lu.U.tocsc()
    rows = U.indices.astype(np.int64)
    columns = np.repeat(np.arange(U.shape[1]), np.diff(U.indptr))
    on = np.flatnonzero(rows == columns)
    diagonal = np.empty(U.shape[0], np.int64)
    diagonal[columns[on]] = on
    return (L.indptr.astype(np.int64), L.indices.astype(np.int64), L.data.astype(np.complex128),
            U.indptr.astype(np.int64), rows, U.data.astype(np.complex128), diagonal,
            lu.perm_r.astype(np.int64), lu.perm_c.astype(np.int64))
