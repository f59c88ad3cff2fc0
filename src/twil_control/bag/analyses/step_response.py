"""Joint tracking against the ideal closed loop of computed torque, eq. (54).

Under computed torque with Kp = wn^2, Kd = 2 wn (zeta = 1) the joint error e = q_r - q obeys
e'' + 2 wn e' + wn^2 e = 0, so after a reference step at t_k it is
e(t) = (e0 + (e'0 + wn e0)(t - t_k)) exp(-wn (t - t_k)), with e0 and e'0 the error and its
rate at t_k: e0 (1 + wn t) exp(-wn t) from rest. The deviation of the measured error from
that curve is what the controller's model errors, delays and saturation cost.
"""

from __future__ import annotations

import numpy as np

from ...control.computed_torque import ideal_step_error
from ...control.trajectory import held_reference


def step_tracking(t, q, qd, cmd_t, cmd_q, cmd_qd=None, wn: float = 5.0) -> dict:
    """Per joint and per step: measured error, ideal error and their deviation.

    t (N,), q and qd (N, J) the joint states; cmd_t (K,) the reference times, cmd_q (K, J) the
    reference positions (cmd_qd (K, J) velocities, zero if None). Samples before the first
    reference are left out. Returns arrays over the kept samples: 't', 'error', 'ideal',
    'deviation' (N', J), 'e0' (K, J), 'step' (N',) index of the step each sample follows.
    """
    cmd_t = np.asarray(cmd_t, float)
    cmd_q = np.asarray(cmd_q, float)
    cmd_qd = np.zeros_like(cmd_q) if cmd_qd is None else np.asarray(cmd_qd, float)
    keep = t >= cmd_t[0] - 1e-9
    tk, qk, qdk = t[keep], q[keep], qd[keep]
    step = np.searchsorted(cmd_t, tk + 1e-9, side="right") - 1
    e0 = np.empty_like(cmd_q)
    ed0 = np.empty_like(cmd_q)
    for k, tc in enumerate(cmd_t):
        qc = np.array([np.interp(tc, t, q[:, j]) for j in range(q.shape[1])])
        qdc = np.array([np.interp(tc, t, qd[:, j]) for j in range(q.shape[1])])
        e0[k], ed0[k] = cmd_q[k] - qc, cmd_qd[k] - qdc
    error = cmd_q[step] - qk
    ideal = ideal_step_error((tk - cmd_t[step])[:, None], e0[step], wn=wn, ed0=ed0[step])
    return {
        "t": tk,
        "error": error,
        "ideal": ideal,
        "deviation": error - ideal,
        "e0": e0,
        "step": step,
        "velocity_error": cmd_qd[step] - qdk,
    }


def trajectory_tracking(
    t, q, qd, cmd_t, cmd_q, cmd_qd, cmd_qdd, wn: float = 5.0, timeout: float = 0.1
) -> dict:
    """step_tracking for a reference sent as samples of a trajectory (positions, velocities,
    accelerations, stamped cmd_t), held between samples as the controllers hold it: to second
    order, q_r = q + qd dt + qdd dt^2 / 2 and qd_r = qd + qdd dt, for dt up to `timeout`, then
    still at the position reached (a publisher that fell silent). With the feedforward the
    error of law (53) obeys (54) through the whole trajectory, so the ideal error is the decay
    of the error at the first sample; 'step' is the sample each joint state follows."""
    cmd_t = np.asarray(cmd_t, float)
    keep = t >= cmd_t[0] - 1e-9
    tk, qk, qdk = t[keep], q[keep], qd[keep]
    step = np.searchsorted(cmd_t, tk + 1e-9, side="right") - 1
    q_r, qd_r, _ = held_samples(cmd_t, cmd_q, cmd_qd, cmd_qdd, step, tk, timeout)
    error = q_r - qk
    e0 = np.array([cmd_q[0] - [np.interp(cmd_t[0], t, q[:, j]) for j in range(q.shape[1])]])
    ed0 = np.array([cmd_qd[0] - [np.interp(cmd_t[0], t, qd[:, j]) for j in range(q.shape[1])]])
    ideal = ideal_step_error((tk - cmd_t[0])[:, None], e0[0], wn=wn, ed0=ed0[0])
    return {
        "t": tk,
        "error": error,
        "ideal": ideal,
        "deviation": error - ideal,
        "e0": e0,
        "step": step,
        "velocity_error": qd_r - qdk,
    }


def held_samples(cmd_t, cmd_q, cmd_qd, cmd_qdd, k, t, timeout: float):
    """(q_r, qd_r, qdd_r) at times t (N,) of the samples k (N,) as the controllers hold them
    (control/trajectory.held_reference)."""
    q_s, qd_s, qdd_s = (np.asarray(a, float)[k] for a in (cmd_q, cmd_qd, cmd_qdd))
    age = (np.asarray(t, float) - np.asarray(cmd_t, float)[k])[:, None]
    return held_reference(q_s, qd_s, qdd_s, age, float(timeout))


def error_dynamics_residual(t, q, qd, cmd_t, cmd_q, cmd_qd, cmd_qdd, kp, kd, timeout: float = 0.1) -> dict:
    """How far the joints are from (54), e'' + Kd e' + Kp e = 0, e = q_r - q, per joint.

    Over each interval [t_i, t_i+1] between joint states (after the first reference), the mean
    of the left side, integrated exactly where it can be:
        r_i = (e'(t_i+1) - e'(t_i)) / h + Kd (e(t_i+1) - e(t_i)) / h + Kp (e(t_i) + e(t_i+1)) / 2,
    with q_r, q_r' the sample in force at t_i held to t_i+1 (so a new sample or a step at t_i+1
    opens the next interval rather than this one). Since law (53) commands the acceleration
    a = q_r'' + Kd e' + Kp e, r_i is the mean commanded acceleration minus the joint's own,
    a_i - (qd(t_i+1) - qd(t_i)) / h: zero for a plant that is its control model, whatever the
    reference. Returns 't' (interval midpoints), 'residual' r (M, J) and 'commanded' a (M, J)
    in rad/s^2, and 'percent' (J,): 100 RMS(r) / RMS(a) over the run, NaN for a joint whose
    commanded acceleration is all but zero (RMS under 1e-9 rad/s^2).
    """
    cmd_t = np.asarray(cmd_t, float)
    keep = t >= cmd_t[0] - 1e-9
    tk, qk, qdk = t[keep], q[keep], qd[keep]
    k = np.searchsorted(cmd_t, tk[:-1] + 1e-9, side="right") - 1
    h = np.diff(tk)[:, None]
    q0, qd0, _ = held_samples(cmd_t, cmd_q, cmd_qd, cmd_qdd, k, tk[:-1], timeout)
    q1, qd1, _ = held_samples(cmd_t, cmd_q, cmd_qd, cmd_qdd, k, tk[1:], timeout)
    e0, e1 = q0 - qk[:-1], q1 - qk[1:]
    ed0, ed1 = qd0 - qdk[:-1], qd1 - qdk[1:]
    kp, kd = (
        np.broadcast_to(np.asarray(kp, float), e0.shape[1:]),
        np.broadcast_to(np.asarray(kd, float), e0.shape[1:]),
    )
    residual = (ed1 - ed0) / h + kd * (e1 - e0) / h + kp * 0.5 * (e0 + e1)
    commanded = residual + np.diff(qdk, axis=0) / h
    scale = np.sqrt(np.mean(commanded**2, axis=0))
    rms = np.sqrt(np.mean(residual**2, axis=0))
    percent = np.where(scale > 1e-9, 100.0 * rms / np.maximum(scale, 1e-300), np.nan)
    return {"t": 0.5 * (tk[:-1] + tk[1:]), "residual": residual, "commanded": commanded, "percent": percent}


def draw_step_tracking(fig, tr, joints) -> None:
    """Each joint's tracking error (solid) over its ideal response (dashed), one colour per joint."""
    ax = fig.add_subplot(1, 1, 1)
    for j, name in enumerate(joints):
        (line,) = ax.plot(tr["t"], tr["error"][:, j], lw=1.1, label=name)
        ax.plot(tr["t"], tr["ideal"][:, j], lw=0.9, ls="--", color=line.get_color())
    ax.set_xlabel("time (s)")
    ax.set_ylabel("rad")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, ncol=2)


def draw_deviation(fig, tr, joints, unit: str) -> None:
    """tr['deviation'] (N, J) against tr['t'], one line per joint."""
    ax = fig.add_subplot(1, 1, 1)
    for j, name in enumerate(joints):
        ax.plot(tr["t"], tr["deviation"][:, j], lw=1.0, label=name)
    ax.set_xlabel("time (s)")
    ax.set_ylabel(unit)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
