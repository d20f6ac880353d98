#!/usr/bin/env python3
"""Experiment: how much of the smoothed-ANP step would a Gershgorin bound on the *assembled*
volumetric operator recover?  Regular box, 4x4x4 cubes x 6 tets, E = 1 MPa, nu = 0.4999, at rest.
Compares, as fractions of 2/omega_max (dense eigenproblem):
  A  the solver's nodal bound (absolute-value rows, deviatoric + volumetric)
  B  deviatoric absolute rows + block-Gershgorin rows of the assembled volumetric operator
  C  block-Gershgorin rows of the whole assembled stiffness
  D  deviatoric absolute rows + the rest operator's rows weighted by V^(-1/2) (what the solver
     now computes as its ANP blocks' second form, with a perturbation term at a deformed state)
for plain ANP (s = 0) and s = 1, 2 smoothing passes.

Why B can be much tighter than A: the volumetric rows of A bound each tet's volume rate by
sum_b |d_b| |v_b| and so cannot see that the rates cancel (sum_e d_a^e = 0 at an interior node);
Gershgorin on the assembled operator k G^T S^s V S^s G does.  A is what the solver computes every
step; B and C are rigorous too (block Gershgorin: x^T K x <= sum_b (sum_c |K_bc|_2) |x_b|^2), but
need the operator assembled, whose stencil is 2(s + 1) rings of nodes.  Only the state at rest is
measured here (the current cofactors enter G; see design.md, the stable step).

Usage: python3 bench/anp_step_bound_experiment.py [PERTURBATION]   (interior nodes moved by up to
PERTURBATION of a cell, seeded; 0 by default).  numpy only; ~3 s."""
import itertools
import sys

import numpy as np

n, L = 4, 0.04
h = L / n
E, nu, rho = 1e6, 0.4999, 1000.0
mu = E / (2 * (1 + nu))
lam = E * nu / ((1 + nu) * (1 - 2 * nu))
k = lam + 2 * mu / 3

perturb = float(sys.argv[1]) if len(sys.argv) > 1 else 0.0
idx = lambda i, j, k: (i * (n + 1) + j) * (n + 1) + k
X = np.array([[i * h, j * h, k * h] for i in range(n + 1) for j in range(n + 1) for k in range(n + 1)])
rng = np.random.default_rng(11)
for a in range(len(X)):
    if all(0 < c < L - 1e-12 for c in X[a]):
        X[a] += perturb * h * rng.uniform(-1, 1, 3)
tets = []
for i, j, l in itertools.product(range(n), repeat=3):
    for perm in itertools.permutations(range(3)):
        v = [i, j, l]
        t = [idx(*v)]
        for ax in perm:
            v[ax] += 1
            t.append(idx(*v))
        Dm = (X[t[1:]] - X[t[0]]).T
        if np.linalg.det(Dm) < 0:
            t[1], t[2] = t[2], t[1]
        tets.append(t)
tets = np.array(tets)
N, T = len(X), len(tets)
ndof = 3 * N

grads, vols = [], []
for t in tets:
    Dm = (X[t[1:]] - X[t[0]]).T
    V = np.linalg.det(Dm) / 6
    assert V > 0
    inv = np.linalg.inv(Dm)
    g = np.zeros((4, 3))
    g[1:] = inv
    g[0] = -inv.sum(axis=0)
    grads.append(g)
    vols.append(V)
grads, vols = np.array(grads), np.array(vols)

mass = np.zeros(N)
for e, t in enumerate(tets):
    mass[t] += rho * vols[e] / 4
Vn = np.zeros(N)
for e, t in enumerate(tets):
    Vn[t] += vols[e] / 4

# Deviatoric stiffness (small strain, isochoric part 2 mu dev eps).
Kdev = np.zeros((ndof, ndof))
m = np.array([1, 1, 1, 0, 0, 0.0])
D = 2 * mu * (np.diag([1, 1, 1, 0.5, 0.5, 0.5]) - np.outer(m, m) / 3)
for e, t in enumerate(tets):
    B = np.zeros((6, 12))
    for a in range(4):
        gx, gy, gz = grads[e, a]
        B[:, 3 * a : 3 * a + 3] = [[gx, 0, 0], [0, gy, 0], [0, 0, gz], [0, gz, gy], [gz, 0, gx], [gy, gx, 0]]
    ke = vols[e] * B.T @ D @ B
    dofs = np.array([[3 * a, 3 * a + 1, 3 * a + 2] for a in t]).ravel()
    Kdev[np.ix_(dofs, dofs)] += ke


# G: nodal velocity -> nodal Jdot (plain ANP): (G x)_a = (1/V_a) sum_{e at a} (1/4) sum_b d_b . x_b,
# for the volume-rate vectors dd of every tet's nodes (d_b = V0 cof F grad N_b).
def volume_rate_map(dd):
    Gm = np.zeros((N, ndof))
    for e, t in enumerate(tets):
        for a in t:
            for bi, b in enumerate(t):
                Gm[a, 3 * b : 3 * b + 3] += dd[e, bi] / 4 / Vn[a]
    return Gm


d = vols[:, None, None] * grads  # d_b = V0 grad N_b at rest
G = volume_rate_map(d)
S = np.zeros((N, N))
for e, t in enumerate(tets):
    for a in t:
        for b in t:
            S[a, b] += vols[e] / 16 / Vn[a]


def block_gershgorin(K):
    r = np.zeros(N)
    for b in range(N):
        for c in range(N):
            blk = K[3 * b : 3 * b + 3, 3 * c : 3 * c + 3]
            if np.any(blk):
                r[b] += np.linalg.norm(blk, 2)
    return r


# The solver's absolute-value rows (design.md section 5).
dn = np.linalg.norm(d, axis=2)
t_e = dn.sum(axis=1)
Mdev = 4 * mu / 3
R0 = np.zeros(N)
for e, t in enumerate(tets):
    R0[t] += t_e[e]


# The solver's volumetric rows for volume-rate vectors dd (d_b at the current state, or a change
# of them): k R0_a / (16 V_a) per node of each tet, times the tet's t / t0 and each |dd_b|.
def abs_vol_rows(dd):
    nn = np.linalg.norm(dd, axis=2)
    te = nn.sum(axis=1)
    rows = np.zeros(N)
    for e, t in enumerate(tets):
        Q = (te[e] / t_e[e]) * sum(k * R0[a] / (16 * Vn[a]) for a in t)
        for bi, b in enumerate(t):
            rows[b] += nn[e, bi] * Q
    return rows


beta_dev = np.zeros(N)
for e, t in enumerate(tets):
    for bi, b in enumerate(t):
        beta_dev[b] += dn[e, bi] * Mdev * t_e[e] / vols[e]
beta_vol = abs_vol_rows(d)

Minv = np.repeat(1 / mass, 3)
rdev_assembled = block_gershgorin(Kdev)
print(f"box {n}^3 x 6 tets, nu = {nu}, interior nodes moved by up to {100 * perturb:.0f} % of a cell")
for s in (0, 1, 2):
    Ss = np.linalg.matrix_power(S, s)
    Kvol = k * G.T @ Ss.T @ np.diag(Vn) @ Ss @ G
    K = Kdev + Kvol
    w2 = np.linalg.eigvals((Minv[:, None] * K)).real.max()
    exact = 2 / np.sqrt(w2)
    rvol = block_gershgorin(Kvol)
    A = 2 / np.sqrt(((beta_dev + beta_vol) / mass).max())
    B = 2 / np.sqrt(((beta_dev + rvol) / mass).max())
    C = 2 / np.sqrt(((rdev_assembled + rvol) / mass).max())
    print(
        f"s = {s}: 2/omega_max = {exact:.4e} s; A (solver's rows) {A / exact:.3f}, "
        f"B (dev rows + assembled vol Gershgorin) {B / exact:.3f}, C (assembled Gershgorin) {C / exact:.3f}"
    )

# At a deformed state (the deformation of Anp.StableStepIsConservativeAndNotWasteful: 15 % shear,
# 20 % compression, a 0.2 mm ripple): the volumetric rows only, as step bounds relative to A's.
# A' is the solver's volumetric rows on the current areas (its t_e / t0_e factor); "assembled"
# is block Gershgorin on k G(x)^T S^s V S^s G(x) re-assembled at x; "perturbation" keeps the rest
# assembly and bounds the change:  x^T K x <= (1 + eta) x^T K0 x + (1 + 1/eta) k |dG x|^2_W,
# the second term with the solver's absolute-value rows on |d_b - d0_b| (rigorous for any eta).
u = np.column_stack([0.15 * X[:, 2] + 0.002 * np.sin(400 * X[:, 1]), 0.05 * X[:, 0], -0.2 * X[:, 2]])
x = X + u
dc = np.zeros((T, 4, 3))
for e, t in enumerate(tets):
    F = (x[t[1:]] - x[t[0]]).T @ np.linalg.inv((X[t[1:]] - X[t[0]]).T)
    cof = np.linalg.det(F) * np.linalg.inv(F).T
    for bi in range(4):
        dc[e, bi] = vols[e] * cof @ grads[e, bi]
Gc = volume_rate_map(dc)


rA = abs_vol_rows(dc)
rD = abs_vol_rows(dc - d)
print("deformed, volumetric rows only, step bound relative to A' (the solver's rows at x):")
for s in (0, 2):
    Ss = np.linalg.matrix_power(S, s)
    W = Ss.T @ np.diag(Vn) @ Ss
    r0 = block_gershgorin(k * G.T @ W @ G)
    rc = block_gershgorin(k * Gc.T @ W @ Gc)
    wA = (rA / mass).max()
    wc = (rc / mass).max()
    wp = min(((1 + eta) * r0 / mass + (1 + 1 / eta) * rD / mass).max() for eta in np.geomspace(1e-3, 1e3, 121))
    print(
        f"s = {s}: assembled at x {np.sqrt(wA / wc):.3f}, perturbation of the rest assembly {np.sqrt(wA / wp):.3f} "
        f"(|d - d0| / |d| = {np.linalg.norm(dc - d) / np.linalg.norm(dc):.3f})"
    )


# D: the rest operator's weighted rows plus a perturbation, computable from what the stress pass
# has.  |(S^s G x)_a| <= (S^s |G| |x|)_a entrywise (S >= 0, |G| the norms of the 3-vector blocks),
# so the volumetric form is <= |x|^T k Z^T V Z |x| with Z = S^s |G| (which keeps the cancellation
# inside each vector block: |G_aa| = 0 at an interior node); a nonnegative symmetric K^ then gives
# rows (K^ p)_b / p_b for any p > 0 (AM-GM; Collatz-Wielandt), here p = V_b^(-1/2), and
# Z^T V Z p = |G|^T V S^2s |G| p (S is V-self-adjoint).  At the rest state those rows are constants;
# at x the change dG enters as (1 + eta) rest rows + (1 + 1/eta) absolute rows on |d_b - d0_b|.
def weighted_rest_rows(s):
    Gn0 = np.linalg.norm(G.reshape(N, N, 3), axis=2)
    p = Vn**-0.5
    w = np.linalg.matrix_power(S, 2 * s) @ (Gn0 @ p)
    return k * (Gn0.T @ (Vn * w)) / p


print("D: rest rows weighted by V^(-1/2) (+ perturbation at x), the larger step of D and A:")
for s in (0, 1, 2):
    Ss = np.linalg.matrix_power(S, s)
    Kvol = k * G.T @ Ss.T @ np.diag(Vn) @ Ss @ G
    exact = 2 / np.sqrt(np.linalg.eigvals((Minv[:, None] * (Kdev + Kvol))).real.max())
    c = weighted_rest_rows(s)
    D_rest = 2 / np.sqrt(((beta_dev + c) / mass).max())
    A_rest = 2 / np.sqrt(((beta_dev + beta_vol) / mass).max())
    line = f"s = {s}: at rest D {D_rest / exact:.3f} of 2/omega_max (A {A_rest / exact:.3f})"
    if s in (0, 2):
        wA = (rA / mass).max()
        wD = min(((1 + eta) * c / mass + (1 + 1 / eta) * rD / mass).max() for eta in np.geomspace(1e-3, 1e3, 121))
        line += f"; deformed, volumetric rows, D's step relative to A' {np.sqrt(wA / wD):.3f}"
    print(line)
