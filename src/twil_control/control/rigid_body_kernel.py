"""Mass matrix and inverse dynamics of a floating-base tree of revolute joints, compiled (numba).

The cart controller needs, every 1 kHz update, the whole robot's mass matrix (its base block
gives K5..K8) and the arm rows of M vdot + C v - tau_g; called from Python, neither Drake nor
Pinocchio fits that budget (docs/formulas.md). One kinematics pass feeds the composite-rigid-body
algorithm and recursive Newton-Euler inside the update's one compiled call. The model it takes,
the algorithms and the coordinates: docs/formulas.md, "The rigid-body kernel"; the arrays'
layout: the TREE_* and work columns below. world/platform_dynamics.py extracts the tree from
Drake; tests/test_rigid_body_kernel.py checks both results against Drake's.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = [
    "TREE_PARENT",
    "TREE_Q",
    "TREE_V",
    "TREE_R",
    "TREE_P",
    "TREE_AXIS",
    "TREE_MASS",
    "TREE_COM",
    "TREE_INERTIA",
    "TREE_WIDTH",
    "WORK_WIDTH",
    "kinematics",
    "mass_matrix",
    "inverse_dynamics",
    "dynamics",
    "work_array",
]

# tree columns, one row per node: parent node (-1 for the base), the index of its first position
# and first velocity in q and v, the pose of F in the parent node's frame (R row-major, p), the
# joint axis, and the node's spatial inertia about its frame's origin in its frame (mass, centre
# of mass, rotational inertia row-major). extra (nv + 3): each velocity's reflected inertia, then
# the gravity vector (world). work (n_nodes x WORK_WIDTH): written by `kinematics`, read by the
# other two.
TREE_PARENT, TREE_Q, TREE_V = 0, 1, 2
TREE_R, TREE_P, TREE_AXIS = 3, 12, 15
TREE_MASS, TREE_COM, TREE_INERTIA = 18, 19, 22
TREE_WIDTH = 31

# work columns: the node's pose in the world (R row-major, p), its joint's motion subspace in
# world Plücker coordinates (revolute nodes), its spatial velocity, its spatial inertia and
# that of its subtree (m, h, I_O row-major), its spatial acceleration, and the spatial force
# across its joint; then scratch (no allocation inside the kernels)
_R, _P, _S, _V, _I, _IC, _A, _F = 0, 9, 12, 18, 24, 37, 50, 56
_TMP = 62  # 12 columns of scratch (row 0 only)
WORK_WIDTH = 74


def work_array(n_nodes: int) -> np.ndarray:
    return np.zeros((n_nodes, WORK_WIDTH))


@njit(cache=True, nogil=True)
def _cross(ax, ay, az, bx, by, bz):
    return ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx


@njit(cache=True, nogil=True)
def _inertia_times(w, k, vec, o, out, oo):
    """out[oo:oo+6] = I vec[o:o+6], I the spatial inertia at w[k, _I or _IC...] (column k
    given as the start of (m, h, I_O)): n = I_O w + h x v, f = m v - h x w."""
    m = w[k]
    hx, hy, hz = w[k + 1], w[k + 2], w[k + 3]
    wx, wy, wz = vec[o], vec[o + 1], vec[o + 2]
    vx, vy, vz = vec[o + 3], vec[o + 4], vec[o + 5]
    cx, cy, cz = _cross(hx, hy, hz, vx, vy, vz)
    dx, dy, dz = _cross(hx, hy, hz, wx, wy, wz)
    out[oo] = w[k + 4] * wx + w[k + 5] * wy + w[k + 6] * wz + cx
    out[oo + 1] = w[k + 7] * wx + w[k + 8] * wy + w[k + 9] * wz + cy
    out[oo + 2] = w[k + 10] * wx + w[k + 11] * wy + w[k + 12] * wz + cz
    out[oo + 3] = m * vx - dx
    out[oo + 4] = m * vy - dy
    out[oo + 5] = m * vz - dz


@njit(cache=True, nogil=True)
def kinematics(tree, x, nq, work):
    """Poses, motion subspaces, spatial velocities and world-origin spatial inertias of every
    node for the state x = [q (nq), v], and the composite inertias of the subtrees."""
    n = tree.shape[0]
    for k in range(n):
        row = work[k]
        t = tree[k]
        if k == 0:
            # the floating base: R_WB from the quaternion (normalised, as Drake does), p_WB
            i = int(t[TREE_Q])
            qw, qx, qy, qz = x[i], x[i + 1], x[i + 2], x[i + 3]
            s = 1.0 / (qw * qw + qx * qx + qy * qy + qz * qz)
            row[_R] = 1.0 - 2.0 * s * (qy * qy + qz * qz)
            row[_R + 1] = 2.0 * s * (qx * qy - qw * qz)
            row[_R + 2] = 2.0 * s * (qx * qz + qw * qy)
            row[_R + 3] = 2.0 * s * (qx * qy + qw * qz)
            row[_R + 4] = 1.0 - 2.0 * s * (qx * qx + qz * qz)
            row[_R + 5] = 2.0 * s * (qy * qz - qw * qx)
            row[_R + 6] = 2.0 * s * (qx * qz - qw * qy)
            row[_R + 7] = 2.0 * s * (qy * qz + qw * qx)
            row[_R + 8] = 1.0 - 2.0 * s * (qx * qx + qy * qy)
            row[_P], row[_P + 1], row[_P + 2] = x[i + 4], x[i + 5], x[i + 6]
            j = nq + int(t[TREE_V])
            wx, wy, wz = x[j], x[j + 1], x[j + 2]
            # velocity of the body point at the world origin: v_B + p_B x w
            cx, cy, cz = _cross(row[_P], row[_P + 1], row[_P + 2], wx, wy, wz)
            row[_V], row[_V + 1], row[_V + 2] = wx, wy, wz
            row[_V + 3], row[_V + 4], row[_V + 5] = x[j + 3] + cx, x[j + 4] + cy, x[j + 5] + cz
        else:
            par = work[int(t[TREE_PARENT])]
            # R_WF = R_WP R_PF (into R_WM's slots first), p_WF = p_WP + R_WP p_PF
            for a in range(3):
                p0, p1, p2 = par[_R + 3 * a], par[_R + 3 * a + 1], par[_R + 3 * a + 2]
                for b in range(3):
                    row[_R + 3 * a + b] = p0 * t[TREE_R + b] + p1 * t[TREE_R + 3 + b] + p2 * t[TREE_R + 6 + b]
                row[_P + a] = par[_P + a] + p0 * t[TREE_P] + p1 * t[TREE_P + 1] + p2 * t[TREE_P + 2]
            # the axis in the world, through the joint's origin: S = [a; p x a]
            ux, uy, uz = t[TREE_AXIS], t[TREE_AXIS + 1], t[TREE_AXIS + 2]
            ax = row[_R] * ux + row[_R + 1] * uy + row[_R + 2] * uz
            ay = row[_R + 3] * ux + row[_R + 4] * uy + row[_R + 5] * uz
            az = row[_R + 6] * ux + row[_R + 7] * uy + row[_R + 8] * uz
            px, py, pz = _cross(row[_P], row[_P + 1], row[_P + 2], ax, ay, az)
            row[_S], row[_S + 1], row[_S + 2], row[_S + 3], row[_S + 4], row[_S + 5] = ax, ay, az, px, py, pz
            # R_FM = exp(q [axis]x) (Rodrigues), R_WM = R_WF R_FM, row by row in place
            q = x[int(t[TREE_Q])]
            c, s = math.cos(q), math.sin(q)
            C = 1.0 - c
            m00, m01, m02 = c + C * ux * ux, C * ux * uy - s * uz, C * ux * uz + s * uy
            m10, m11, m12 = C * uy * ux + s * uz, c + C * uy * uy, C * uy * uz - s * ux
            m20, m21, m22 = C * uz * ux - s * uy, C * uz * uy + s * ux, c + C * uz * uz
            for a in range(3):
                f0, f1, f2 = row[_R + 3 * a], row[_R + 3 * a + 1], row[_R + 3 * a + 2]
                row[_R + 3 * a] = f0 * m00 + f1 * m10 + f2 * m20
                row[_R + 3 * a + 1] = f0 * m01 + f1 * m11 + f2 * m21
                row[_R + 3 * a + 2] = f0 * m02 + f1 * m12 + f2 * m22
            qd = x[nq + int(t[TREE_V])]
            for a in range(6):
                row[_V + a] = par[_V + a] + row[_S + a] * qd
        # the node's spatial inertia about the world origin, world axes:
        # I_O = R I_Mo R^T - m [cb]x^T [cb]x + m [c]x^T [c]x, cb = R c_M, c = p + cb
        m = t[TREE_MASS]
        R = row[_R : _R + 9]
        cbx = R[0] * t[TREE_COM] + R[1] * t[TREE_COM + 1] + R[2] * t[TREE_COM + 2]
        cby = R[3] * t[TREE_COM] + R[4] * t[TREE_COM + 1] + R[5] * t[TREE_COM + 2]
        cbz = R[6] * t[TREE_COM] + R[7] * t[TREE_COM + 1] + R[8] * t[TREE_COM + 2]
        cx, cy, cz = row[_P] + cbx, row[_P + 1] + cby, row[_P + 2] + cbz
        row[_I] = m
        row[_I + 1], row[_I + 2], row[_I + 3] = m * cx, m * cy, m * cz
        for a in range(3):
            for b in range(a, 3):
                acc = 0.0
                for e in range(3):
                    RI = (
                        R[3 * a] * t[TREE_INERTIA + e]
                        + R[3 * a + 1] * t[TREE_INERTIA + 3 + e]
                        + R[3 * a + 2] * t[TREE_INERTIA + 6 + e]
                    )
                    acc += RI * R[3 * b + e]
                row[_I + 4 + 3 * a + b] = acc
        cc = cx * cx + cy * cy + cz * cz
        cb2 = cbx * cbx + cby * cby + cbz * cbz
        row[_I + 4] += m * (cc - cx * cx - cb2 + cbx * cbx)
        row[_I + 8] += m * (cc - cy * cy - cb2 + cby * cby)
        row[_I + 12] += m * (cc - cz * cz - cb2 + cbz * cbz)
        row[_I + 5] += m * (-cx * cy + cbx * cby)
        row[_I + 6] += m * (-cx * cz + cbx * cbz)
        row[_I + 9] += m * (-cy * cz + cby * cbz)
        row[_I + 7] = row[_I + 5]
        row[_I + 10] = row[_I + 6]
        row[_I + 11] = row[_I + 9]
        for a in range(13):
            row[_IC + a] = row[_I + a]
    for k in range(n - 1, 0, -1):  # composite inertias: children after parents
        par = work[int(tree[k, TREE_PARENT])]
        for a in range(13):
            par[_IC + a] += work[k, _IC + a]


@njit(cache=True, nogil=True)
def _base_subspace(work, col, out):
    """Column `col` (0..5) of the base's motion subspace in world Plücker coordinates: for the
    angular velocity e_i, [e_i; p_B x e_i]; for the origin's velocity e_i, [0; e_i]."""
    for a in range(6):
        out[a] = 0.0
    out[col] = 1.0
    px, py, pz = work[0, _P], work[0, _P + 1], work[0, _P + 2]
    if col == 0:
        out[4], out[5] = pz, -py
    elif col == 1:
        out[3], out[5] = -pz, px
    elif col == 2:
        out[3], out[4] = py, -px


@njit(cache=True, nogil=True)
def mass_matrix(tree, extra, work, M):
    """The mass matrix (composite rigid bodies) at the state of the last `kinematics`."""
    n = tree.shape[0]
    F = work[0, _TMP : _TMP + 6]
    S = work[0, _TMP + 6 : _TMP + 12]
    for i in range(n):
        wi = work[i]
        ncols = 6 if i == 0 else 1
        vi = int(tree[i, TREE_V])
        for ci in range(ncols):
            if i == 0:
                _base_subspace(work, ci, S)
            else:
                for a in range(6):
                    S[a] = wi[_S + a]
            _inertia_times(wi, _IC, S, 0, F, 0)
            # down the chain of ancestors: M[j, i] = S_j^T F
            j = i
            while j >= 0:
                wj = work[j]
                vj = int(tree[j, TREE_V])
                if j == 0:
                    for cj in range(6):
                        _base_subspace(work, cj, S)
                        val = 0.0
                        for a in range(6):
                            val += S[a] * F[a]
                        M[vj + cj, vi + ci] = val
                        M[vi + ci, vj + cj] = val
                else:
                    val = 0.0
                    for a in range(6):
                        val += wj[_S + a] * F[a]
                    M[vj, vi + ci] = val
                    M[vi + ci, vj] = val
                j = int(tree[j, TREE_PARENT])
    for k in range(M.shape[0]):
        M[k, k] += extra[k]


@njit(cache=True, nogil=True)
def inverse_dynamics(tree, extra, x, nq, vdot, work, tau):
    """tau = M vdot + C v - tau_g (recursive Newton-Euler, gravity as an upward acceleration of
    the base) at the state of the last `kinematics`."""
    n = tree.shape[0]
    nv = vdot.shape[0]
    g = extra[nv : nv + 3]
    IV = work[0, _TMP : _TMP + 6]
    for k in range(n):
        row = work[k]
        j = int(tree[k, TREE_V])
        if k == 0:
            # d/dt of the base's world-origin spatial velocity: [alpha; a_B + v_B x w + p_B x alpha]
            wx, wy, wz = vdot[j], vdot[j + 1], vdot[j + 2]
            w0, w1, w2 = x[nq + j], x[nq + j + 1], x[nq + j + 2]
            c0, c1, c2 = _cross(x[nq + j + 3], x[nq + j + 4], x[nq + j + 5], w0, w1, w2)
            d0, d1, d2 = _cross(row[_P], row[_P + 1], row[_P + 2], wx, wy, wz)
            row[_A], row[_A + 1], row[_A + 2] = wx, wy, wz
            row[_A + 3] = vdot[j + 3] + c0 + d0 - g[0]
            row[_A + 4] = vdot[j + 4] + c1 + d1 - g[1]
            row[_A + 5] = vdot[j + 5] + c2 + d2 - g[2]
        else:
            par = work[int(tree[k, TREE_PARENT])]
            qd, qdd = x[nq + j], vdot[j]
            # A = A_parent + S qdd + (V x S) qd
            Vw0, Vw1, Vw2 = row[_V], row[_V + 1], row[_V + 2]
            Vv0, Vv1, Vv2 = row[_V + 3], row[_V + 4], row[_V + 5]
            Sw0, Sw1, Sw2 = row[_S], row[_S + 1], row[_S + 2]
            Sv0, Sv1, Sv2 = row[_S + 3], row[_S + 4], row[_S + 5]
            a0, a1, a2 = _cross(Vw0, Vw1, Vw2, Sw0, Sw1, Sw2)
            b0, b1, b2 = _cross(Vw0, Vw1, Vw2, Sv0, Sv1, Sv2)
            e0, e1, e2 = _cross(Vv0, Vv1, Vv2, Sw0, Sw1, Sw2)
            row[_A] = par[_A] + Sw0 * qdd + a0 * qd
            row[_A + 1] = par[_A + 1] + Sw1 * qdd + a1 * qd
            row[_A + 2] = par[_A + 2] + Sw2 * qdd + a2 * qd
            row[_A + 3] = par[_A + 3] + Sv0 * qdd + (b0 + e0) * qd
            row[_A + 4] = par[_A + 4] + Sv1 * qdd + (b1 + e1) * qd
            row[_A + 5] = par[_A + 5] + Sv2 * qdd + (b2 + e2) * qd
        # f = I A + V x* (I V), V x* [n; f] = [w x n + v x f; w x f]
        _inertia_times(row, _I, row, _A, row, _F)
        _inertia_times(row, _I, row, _V, IV, 0)
        w0, w1, w2 = row[_V], row[_V + 1], row[_V + 2]
        c0, c1, c2 = _cross(w0, w1, w2, IV[0], IV[1], IV[2])
        d0, d1, d2 = _cross(row[_V + 3], row[_V + 4], row[_V + 5], IV[3], IV[4], IV[5])
        e0, e1, e2 = _cross(w0, w1, w2, IV[3], IV[4], IV[5])
        row[_F] += c0 + d0
        row[_F + 1] += c1 + d1
        row[_F + 2] += c2 + d2
        row[_F + 3] += e0
        row[_F + 4] += e1
        row[_F + 5] += e2
    for k in range(n - 1, 0, -1):
        row = work[k]
        par = work[int(tree[k, TREE_PARENT])]
        val = 0.0
        for a in range(6):
            val += row[_S + a] * row[_F + a]
            par[_F + a] += row[_F + a]
        j = int(tree[k, TREE_V])
        tau[j] = val + extra[j] * vdot[j]
    # the base: the moment about its origin, n - p_B x f, and the force
    row = work[0]
    j = int(tree[0, TREE_V])
    c0, c1, c2 = _cross(row[_P], row[_P + 1], row[_P + 2], row[_F + 3], row[_F + 4], row[_F + 5])
    tau[j] = row[_F] - c0 + extra[j] * vdot[j]
    tau[j + 1] = row[_F + 1] - c1 + extra[j + 1] * vdot[j + 1]
    tau[j + 2] = row[_F + 2] - c2 + extra[j + 2] * vdot[j + 2]
    for a in range(3):
        tau[j + 3 + a] = row[_F + 3 + a] + extra[j + 3 + a] * vdot[j + 3 + a]


@njit(cache=True, nogil=True)
def dynamics(tree, extra, x, vdot, work, M, tau):
    """M and tau = M vdot + C v - tau_g at the state x = [q, v] (one kinematics pass)."""
    nq = x.shape[0] - vdot.shape[0]
    kinematics(tree, x, nq, work)
    mass_matrix(tree, extra, work, M)
    inverse_dynamics(tree, extra, x, nq, vdot, work, tau)
