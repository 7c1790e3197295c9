"""Exact Hessian-vector products of Eq. 16 (:func:`latentoc.gpdm.objective.evaluate`), from the
factors the value and gradient already computed: no new Cholesky factor, two N x N products
K^-1 dK K^-1 per kernel, the rest O(N^2 (d + D)).

The gradient is g = J^T G: J the kernel matrix's derivative in the variables, G = dL/dK =
1/2 (c K^-1 - B B^T), B = K^-1 T. Its derivative along a direction u is J^T dG + dJ^T G with

* dK = E o S (+ the linear and noise parts), S = dln s1 - s2/2 (dln s2 R2 + dR2), E the RBF part,
  dR2_ij = 2 (x_i - x_j) . (dx_i - dx_j);
* dB = -K^-1 dK B + K^-1 dT; the profiled W (w_d^2 = N / (q_d + 1/kappa^2)) adds B diag(dw / w),
  dw_d / w_d = b_d^T dK b_d / (2 N) (b_d the columns of B); the dynamics' targets dT = dX_out;
* dG = -c/2 K^-1 dK K^-1 - 1/2 (dB B^T + B dB^T).

The RBF parts of J^T dG and dJ^T G share one Hadamard product (dG + G o S) o E.
"""

from __future__ import annotations

import numpy as np

from latentoc.gpdm.objective import Evaluation, KernelTerm, rbf_point_grad

__all__ = ["hessian_vector"]


def _rbf_direction(t: KernelTerm, dX: np.ndarray, l1: float, l2: float) -> tuple[np.ndarray, np.ndarray]:
    """S = dE / E and a = x_i . dx_i along (dX, dln s1, dln s2)."""
    a = np.sum(t.X * dX, axis=1)
    S = t.X @ dX.T
    S += S.T
    S *= -1.0
    S += a[:, None]
    S += a[None, :]
    S *= 2.0  # dR2
    S += l2 * t.R2
    S *= -0.5 * t.s2
    S += l1
    return S, a


def _dG(t: KernelTerm, dK: np.ndarray, dT: np.ndarray | None, profiled_n: int | None) -> tuple[np.ndarray, np.ndarray]:
    """dG = -c/2 K^-1 dK K^-1 - 1/2 (dB B^T + B dB^T) and dB (module doc)."""
    C = dK @ t.B
    dB = t.P @ C
    dB *= -1.0
    if dT is not None:
        dB += t.P @ dT
    if profiled_n is not None:  # d ln w_d = b_d^T dK b_d / (2N)
        dB += t.B * (np.sum(t.B * C, axis=0) / (2.0 * profiled_n))[None, :]
    dG = t.P @ dK @ t.P
    dG *= -0.5 * t.c
    BdB = dB @ t.B.T
    dG -= 0.5 * BdB
    dG -= 0.5 * BdB.T
    return dG, dB


def _term_hvp(t: KernelTerm, dX: np.ndarray, l1: float, l2: float, l_lin: float, l_noise: float,
              dT: np.ndarray | None, profiled_n: int | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The derivative of one kernel term's gradient along a direction: (points, [ln s1, ln s2, ln lin,
    ln noise] entries, dB)."""
    S, a = _rbf_direction(t, dX, l1, l2)
    dK = t.E * S
    if t.lin:
        XdX = dX @ t.X.T
        dK += t.lin * (XdX + XdX.T + l_lin * (t.X @ t.X.T))
    dK[np.diag_indices_from(dK)] -= l_noise / t.noise
    dG, dB = _dG(t, dK, dT, profiled_n)
    del dK
    M2 = t.G * S
    M2 += dG
    M2 *= t.E  # (dG + G o S) o E
    s2 = t.s2
    gX = rbf_point_grad(M2, t.X, s2) + rbf_point_grad(t.M, dX, s2) + l2 * rbf_point_grad(t.M, t.X, s2)
    MdX = t.M @ dX
    h = np.zeros(4)
    h[0] = np.sum(M2)
    h[1] = -0.5 * s2 * (float(np.sum(M2 * t.R2)) + 4.0 * (float(np.sum(a * np.sum(t.M, axis=1)))
                                                         - float(np.sum(t.X * MdX)))
                        + l2 * float(np.sum(t.M * t.R2)))
    h[3] = (np.trace(t.G) * l_noise - np.trace(dG)) / t.noise
    if t.lin:
        GX = t.G @ t.X
        dGX = dG @ t.X
        gX += 2.0 * t.lin * (dGX + l_lin * GX + t.G @ dX)
        h[2] = t.lin * (float(np.sum(t.X * dGX)) + l_lin * float(np.sum(t.X * GX)) + 2.0 * float(np.sum(dX * GX)))
    return gX, h, dB


def hessian_vector(ev: Evaluation, u: np.ndarray) -> np.ndarray:
    """The Hessian of Eq. 16 at ``ev`` times ``u`` (both packed as :func:`~latentoc.gpdm.objective.pack`)."""
    p = ev.problem
    N, d = p.N, p.latent_dim
    lam = float(p.dynamics_weight)
    u = np.asarray(u, dtype=float)
    dX = u[:N * d].reshape(N, d)
    la, lb = u[N * d:N * d + 4], u[N * d + 4:N * d + 7]

    hX, h, _ = _term_hvp(ev.obs, dX, lb[0], lb[1], 0.0, lb[2], None, N if ev.profiled else None)
    hb = h[[0, 1, 3]]
    gin, h, dB = _term_hvp(ev.dyn, dX[p.in_idx], la[0], la[1], la[2], la[3], dX[p.out_idx], None)
    hX[p.in_idx] += lam * gin
    hX[p.out_idx] += lam * dB
    ha = lam * h
    hX[p.first_idx] += dX[p.first_idx]
    theta = np.exp(ev.v[N * d:])
    prior = np.asarray(p.prior_rate, float) * theta * u[N * d:]  # d^2/dln theta^2 of b theta
    return np.concatenate([hX.ravel(), ha + prior[:4], hb + prior[4:]])


def _point_blocks(t: KernelTerm, profiled_n: int | None) -> tuple[dict[tuple[int, int], np.ndarray],
                                                                   list[np.ndarray], list[np.ndarray]]:
    """The kernel term's Hessian in its input points: block (a, b), a <= b (n x n), couples coordinate
    a of point i with coordinate b of point j. Also K^-1 U_a and U_a B, U_a the rows dK/dx_ia
    (:func:`hessian`)."""
    X, P, B, G, s2, lin, c = t.X, t.P, t.B, t.G, t.s2, t.lin, t.c
    n, d = X.shape
    Delta = [X[:, a][:, None] - X[:, a][None, :] for a in range(d)]
    Us = np.empty((d * n, n))  # U_a = dK_i./dx_ia by rows, stacked
    for a in range(d):
        u = Us[a * n:(a + 1) * n]
        np.multiply(t.E, Delta[a], out=u)
        u *= -s2
        if lin:
            u += lin * X[:, a][None, :]
    Zs, UBs = Us @ P, Us @ B
    Z = [Zs[a * n:(a + 1) * n] for a in range(d)]  # row i: (K^-1 u_ia)^T
    UB = [UBs[a * n:(a + 1) * n] for a in range(d)]
    UCs = UBs @ B.T
    UC = [UCs[a * n:(a + 1) * n] for a in range(d)]
    W = [uc.T - c * z.T for uc, z in zip(UC, Z)]  # (C U_b^T - c K^-1 U_b^T)
    G2 = -2.0 * G
    # G's contraction with the kernel's own second derivatives: 2 s2 M o (delta_ab - s2 Delta_a Delta_b) off
    # the diagonal, minus its row sums on it
    MD = [t.M * (-2.0 * s2 * s2) * D for D in Delta]
    M2 = (2.0 * s2) * t.M
    if lin:
        Glin = (2.0 * lin) * G
    F = [B * ub for ub in UB] if profiled_n is not None else []
    Fs = [(-2.0 / float(profiled_n)) * f for f in F] if F else []  # type: ignore[arg-type]
    tmp = np.empty((n, n))
    blocks = {}
    for a in range(d):
        ZU = Z[a] @ Us[a * n:].T  # K^-1 u_ia . u_jb for b >= a: one product
        for b in range(a, d):
            blk = Z[a] * W[b]
            blk += np.multiply(Z[b].T, UC[a], out=tmp)
            np.multiply(ZU[:, (b - a) * n:(b - a + 1) * n], G2, out=tmp)
            blk += tmp
            np.matmul(UB[a], UB[b].T, out=tmp)
            tmp *= P
            blk += tmp
            np.multiply(MD[a], Delta[b], out=tmp)
            if a == b:
                tmp += M2
            tmp[np.diag_indices(n)] -= np.sum(tmp, axis=1)
            blk += tmp
            if a == b and lin:
                blk += Glin
            if F:  # the profiled W
                blk += np.matmul(Fs[a], F[b].T, out=tmp)
            blocks[a, b] = blk
    return blocks, Z, UB


def _hyper_columns(t: KernelTerm, profiled_n: int | None) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """(points, hyper entries, dB) of the Hessian's columns for ln s1, ln s2, ln lin, ln noise of one term:
    :func:`_term_hvp` along each with dX = 0, where dK is E, -s2/2 R2 o E, lin X X^T and -I/noise; their
    dK B side by side take one product with K^-1, and K^-1 dK K^-1 comes from K^-1 K K^-1 = K^-1."""
    P, X, B, G, E, M, s2, lin = t.P, t.X, t.B, t.G, t.E, t.M, t.s2, t.lin
    c = B.shape[1]
    RE = t.R2 * E
    RE *= -0.5 * s2  # dK along ln s2
    P2 = P @ P
    PX = P @ X
    PXXP = lin * (PX @ PX.T)
    PdKP = (P - PXXP - P2 / t.noise, P @ RE @ P, PXXP, P2 / -t.noise)
    C = np.hstack([E @ B, RE @ B, lin * (X @ (X.T @ B)), B / -t.noise])  # dK B for the four
    dB = P @ C
    dB *= -1.0
    if profiled_n is not None:  # d ln w_d = b_d^T dK b_d / (2N)
        Bs = np.tile(B, 4)
        dB += Bs * (np.sum(Bs * C, axis=0) / (2.0 * profiled_n))[None, :]
    GX = G @ X if lin else None
    out = []
    for k in range(4):
        dBk = dB[:, k * c:(k + 1) * c]
        BdB = dBk @ B.T
        BdB *= 0.5
        dG = PdKP[k] * (-0.5 * t.c)
        dG -= BdB
        dG -= BdB.T
        M2 = dG * E  # (dG + G o S) o E, S = dK / E: 1 along ln s1, -s2/2 R2 along ln s2, else 0
        if k == 0:
            M2 += M
        elif k == 1:
            M2 += G * RE
        gX = rbf_point_grad(M2, X, s2)
        h = np.zeros(4)
        h[0] = np.sum(M2)
        h[1] = -0.5 * s2 * float(np.sum(M2 * t.R2))
        h[3] = -np.trace(dG) / t.noise
        if k == 1:
            gX += rbf_point_grad(M, X, s2)
            h[1] += -0.5 * s2 * float(np.sum(M * t.R2))
        elif k == 3:
            h[3] += np.trace(G) / t.noise
        if lin:
            dGX = dG @ X
            h[2] = lin * float(np.sum(X * dGX))
            if k == 2:
                dGX += GX
                h[2] += lin * float(np.sum(X * GX))
            gX += 2.0 * lin * dGX
        out.append((gX, h, dBk))
    return out


def _block(rows: slice | None, cols: slice | None, row_idx: np.ndarray,
           col_idx: np.ndarray) -> tuple[slice, slice] | tuple[np.ndarray, ...]:
    """The index of the block (rows, cols): two slices where both are ranges, else np.ix_ of the indices."""
    return (rows, cols) if rows is not None and cols is not None else np.ix_(row_idx, col_idx)


def hessian(ev: Evaluation, hyper: np.ndarray | None = None) -> np.ndarray:
    """The Hessian of Eq. 16 at ``ev`` (variables packed as :func:`~latentoc.gpdm.objective.pack`; of the
    seven log-hyperparameters only those ``hyper`` (a mask, default all) marks), assembled in
    O(N^3 d^2) from the factors the gradient computed.

    A point's derivative of K is rank two, dK = e_i u^T + u e_i^T (u the row dK_i./dx_ia), so the
    second derivative of c/2 ln|K| + 1/2 tr(K^-1 T T^T) in points (i, a) and (j, b) is
    -c (Pu)_j (Pv)_i + (Pu)_j (Cv)_i + (Pv)_i (Cu)_j - 2 G_ij u^T P v + P_ij u^T C v (P = K^-1,
    C = B B^T, v the row for (j, b)) plus G's contraction with the kernel's own second derivatives;
    the profiled W adds -(2/N) sum_d F_a F_b^T (F_a = B o U_a B), the dynamics' targets P and the
    cross terms -P_ij (U_a B)_ib - (Pu)_j B_ib. Checked against :func:`hessian_vector` in the tests.
    """
    p = ev.problem
    N, d = p.N, p.latent_dim
    n = N * d
    lam = float(p.dynamics_weight)
    keep = np.ones(7, dtype=bool) if hyper is None else np.asarray(hyper, dtype=bool)
    m = n + int(keep.sum())
    H = np.zeros((m, m))  # point i coordinate a at row i d + a, then the kept hyperparameters
    obs, _, _ = _point_blocks(ev.obs, N if ev.profiled else None)
    dyn, Z, UB = _point_blocks(ev.dyn, None)
    lamP, lamB = lam * ev.dyn.P, lam * ev.dyn.B

    def cross(a: int, b: int) -> np.ndarray:  # rows (in i, a), columns (out j, b), times lam
        out = lamP * UB[a][:, b][:, None]
        out += lamB[:, b][:, None] * Z[a]
        out *= -1.0
        return out

    for a in range(d):
        for b in range(a, d):
            C = obs.pop((a, b))  # the dynamics' blocks added at their rows of X
            dyn_ab = dyn.pop((a, b))
            dyn_ab *= lam
            C[_block(p.in_rows, p.in_rows, p.in_idx, p.in_idx)] += dyn_ab
            C[_block(p.in_rows, p.out_rows, p.in_idx, p.out_idx)] += cross(a, b)
            C[_block(p.out_rows, p.in_rows, p.out_idx, p.in_idx)] += cross(b, a).T
            if a == b:
                C[_block(p.out_rows, p.out_rows, p.out_idx, p.out_idx)] += lamP
                C[p.first_idx, p.first_idx] += 1.0  # the first points' N(0, I) prior
            H[a:n:d, b:n:d] = C
            if b != a:
                H[b:n:d, a:n:d] = C.T

    # hyperparameter columns: alpha (dynamics, weighted by lam), then beta
    cols = np.zeros((7, n + 7))
    for k, (gX, h, dB) in enumerate(_hyper_columns(ev.dyn, None)):
        cX = cols[k, :n].reshape(N, d)
        cX[p.in_idx] += lam * gX
        cX[p.out_idx] += lam * dB
        cols[k, n:n + 4] = lam * h
    beta_cols = _hyper_columns(ev.obs, N if ev.profiled else None)
    for k, (gX, h, _) in zip((4, 5, 6), (beta_cols[0], beta_cols[1], beta_cols[3])):
        cols[k, :n] = gX.ravel()
        cols[k, n + 4:] = h[[0, 1, 3]]
    theta = np.exp(ev.v[n:])
    cols[:, n:] += np.diag(np.asarray(p.prior_rate, float) * theta)
    cols = cols[keep][:, np.r_[np.ones(n, dtype=bool), keep]]
    H[n:, :] = cols
    H[:, n:] = cols.T
    return H
