#!/usr/bin/env python3
# Reference for tests/ellipse_onset.rs (docs/VALIDATION.md, "Ellipses with a > b"): buckling
# coefficients k_b = N_cr b²/D of an isotropic plate clamped along x²/a² + y²/b² = 1 under
# in-plane forces N_x = −λ·nx, N_y = −λ·ny, by Rayleigh–Ritz with
# w = (1 − ξ² − η²)²·P_m(ξ)·P_n(η) (ξ = x/a, η = y/b, Legendre P, m + n ≤ M), exact quadrature.
# The quarter model's symmetry admits the (0, 0) class only (even in x and y).
# Needs numpy and scipy. `python3 ellipse_ritz.py 16 20` prints the table for M = 16, 20.
import sys
import numpy as np
from numpy.polynomial import legendre as L
from scipy.linalg import eigh


def legendre_vals(k, t):
    """Value, 1st and 2nd derivative of P_k at t."""
    c = np.zeros(k + 1); c[k] = 1.0
    return L.legval(t, c), L.legval(t, L.legder(c, 1)), L.legval(t, L.legder(c, 2))


def quad_disk(M):
    deg = 2 * (M + 4) + 2
    nr = deg // 2 + 4
    nth = deg + 6
    t, wt = np.polynomial.legendre.leggauss(nr)
    r = 0.5 * (t + 1.0); wr = 0.5 * wt * r
    th = 2 * np.pi * np.arange(nth) / nth; wth = np.full(nth, 2 * np.pi / nth)
    R, TH = np.meshgrid(r, th, indexing="ij")
    W = np.outer(wr, wth)
    return (R * np.cos(TH)).ravel(), (R * np.sin(TH)).ravel(), W.ravel()


def buckle(alpha, nx, ny, M=16, nu=0.3, classes=((0, 0), (1, 0), (0, 1), (1, 1)), full=False):
    """alpha = a/b. Returns dict class -> lowest lam*b^2/D (b = semi-axis along y)."""
    a, b = alpha, 1.0
    xi, eta, wq = quad_disk(M)
    wq = wq * a * b  # dA = a b dxi deta
    s = 1 - xi**2 - eta**2
    g = s**2
    gx = -4 * xi * s; gy = -4 * eta * s
    gxx = -4 * s + 8 * xi**2; gyy = -4 * s + 8 * eta**2; gxy = 8 * xi * eta
    PX = [legendre_vals(k, xi) for k in range(M + 1)]
    PY = [legendre_vals(k, eta) for k in range(M + 1)]
    out = {}
    for (px, py) in classes:
        idx = [(m, n) for m in range(M + 1) for n in range(M + 1 - m)
               if m % 2 == px and n % 2 == py]
        nb = len(idx)
        Wx = np.empty((nb, xi.size)); Wy = np.empty_like(Wx)
        Wxx = np.empty_like(Wx); Wyy = np.empty_like(Wx); Wxy = np.empty_like(Wx)
        for j, (m, n) in enumerate(idx):
            f, fx, fxx = PX[m]; h, hy, hyy = PY[n]
            phi = f * h; phx = fx * h; phy = f * hy
            phxx = fxx * h; phyy = f * hyy; phxy = fx * hy
            w_xi = gx * phi + g * phx
            w_eta = gy * phi + g * phy
            w_xixi = gxx * phi + 2 * gx * phx + g * phxx
            w_etaeta = gyy * phi + 2 * gy * phy + g * phyy
            w_xieta = gxy * phi + gx * phy + gy * phx + g * phxy
            # physical derivatives
            Wx[j] = w_xi / a; Wy[j] = w_eta / b
            Wxx[j] = w_xixi / a**2; Wyy[j] = w_etaeta / b**2; Wxy[j] = w_xieta / (a * b)
        lap = Wxx + Wyy
        K = (lap * wq) @ lap.T - (1 - nu) * ((Wxx * wq) @ Wyy.T + (Wyy * wq) @ Wxx.T
                                             - 2 * (Wxy * wq) @ Wxy.T)
        G = nx * (Wx * wq) @ Wx.T + ny * (Wy * wq) @ Wy.T
        K = 0.5 * (K + K.T); G = 0.5 * (G + G.T)
        # K is SPD; G may be indefinite (ny<0 allowed). lam_min = 1/max eig(G, K)
        try:
            mu = eigh(G, K, eigvals_only=True)
        except np.linalg.LinAlgError:
            # K numerically singular at high order: restrict to its well-conditioned subspace
            d, V = np.linalg.eigh(K)
            keep = d > 1e-12 * d.max()
            T = V[:, keep] / np.sqrt(d[keep])
            mu = np.linalg.eigvalsh(T.T @ G @ T)
        mu_max = mu[-1]
        out[(px, py)] = 1.0 / mu_max if mu_max > 0 else np.inf
        if full:
            out[(px, py)] = np.sort(1.0 / mu[mu > 0])[:3]
    return out


LOADS = {"uniaxial_x": (1.0, 0.0), "hydrostatic": (1.0, 1.0), "uniaxial_y": (0.0, 1.0)}
CLASSNAME = {(0, 0): "SS(sym-x,sym-y)", (1, 0): "AS(odd-x)", (0, 1): "SA(odd-y)", (1, 1): "AA"}

if __name__ == "__main__":
    nu = 0.3
    ratios = [1 / 3, 1 / 2, 1.0, 2.0, 3.0]
    Ms = [int(s) for s in sys.argv[1:]] or [8, 12, 16, 20, 24]
    for load, (nx, ny) in LOADS.items():
        print(f"\n=== load {load}: N_x = -lam*{nx}, N_y = -lam*{ny}   (lam*b^2/D) ===")
        for al in ratios:
            for M in Ms:
                res = buckle(al, nx, ny, M=M, nu=nu)
                k = min(res.values()); cls = min(res, key=res.get)
                det = "  ".join(f"{CLASSNAME[c]}={v:.6f}" for c, v in res.items())
                print(f"a/b={al:.4f} M={M:2d}  lam_min={k:.8f} [{CLASSNAME[cls]}]  | {det}")
