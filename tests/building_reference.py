"""An independent reference for the isolated building's free vibration (used by several test files).

solve_ivp (DOP853, tight tolerances) on the equation of motion written here from scratch, with the state
changes of the sliders and of the bilinear spring located as events; shares no code with the package.
"""

import math

import numpy as np
from scipy.integrate import solve_ivp


def reference(m, k1, k2, fp, c, Fs, d0, t_out, with_rates=False):
    """Event-driven solve_ivp of m x'' + c x' + k2 x + z + Fs sign(x') = 0 with z' = (k1 - k2) x' unless the
    element yields (|z| = fp, loading); the sliders stick at a reversal where |k2 x + z| <= Fs.
    Returns x at t_out (or, ``with_rates``, the rows x, x_dot, x_ddot) and the stop time (inf if it moves
    until t_out[-1]). Before t = 0 the layer rests at d0."""
    z = math.copysign(min(abs(d0) * (k1 - k2), fp), d0)
    t, x, v = 0.0, d0, 0.0
    direction = -math.copysign(1.0, k2 * d0 + z)
    out = np.full((3,) + t_out.shape, np.nan)
    out[:, t_out < 0] = [[d0], [0.0], [0.0]]
    t_end = float(t_out[-1])
    while t < t_end:
        yielding = direction * z >= fp * (1 - 1e-12)

        def rhs(_, s, yielding=yielding, direction=direction):
            return [s[1], -(c * s[1] + k2 * s[0] + s[2] + Fs * direction) / m,
                    0.0 if yielding else (k1 - k2) * s[1]]

        def reversal(_, s):
            return s[1]

        reversal.terminal, reversal.direction = True, -direction

        def yields(_, s, direction=direction):
            return direction * s[2] - fp

        yields.terminal, yields.direction = True, 1
        events = [reversal] if yielding or not math.isfinite(fp) else [reversal, yields]
        sol = solve_ivp(rhs, (t, t_end), [x, v, z], method="DOP853", rtol=1e-13, atol=1e-16 * abs(d0),
                        events=events, dense_output=True)
        seg = (t_out >= t) & (t_out <= sol.t[-1])
        xs, vs, zs = sol.sol(t_out[seg])
        out[:, seg] = xs, vs, -(c * vs + k2 * xs + zs + Fs * direction) / m
        t, (x, v, z) = sol.t[-1], sol.y[:, -1]
        if sol.status != 1:
            break
        if sol.t_events[0].size:  # a reversal: stick or turn
            v = 0.0
            R = k2 * x + z
            if abs(R) <= Fs:
                out[:, t_out > t] = [[x], [0.0], [0.0]]
                return (out if with_rates else out[0]), t
            direction = -math.copysign(1.0, R)
        else:
            z = direction * fp
    return (out if with_rates else out[0]), math.inf


def reference_2dof(m, ms, k, c, ks, cs, Fs, d0, t_out):
    """Event-driven solve_ivp (DOP853, tight tolerances) of the 2-DOF shear building, written from scratch:
    base mass mb = m - ms on the isolators (k, c, Coulomb sliders Fs), roof mass ms on the storey (ks, cs).

    Sliding (direction s): mb xb'' = -k xb - c vb + ks (xs - xb) + cs (vs - vb) - Fs s, ms xs'' = -ks (xs - xb)
    - cs (vs - vb), until vb = 0; then the sliders hold the base if |k xb - ks (xs - xb) - cs vs| <= Fs, else it
    turns. Held: xb fixed, the roof vibrates on it, until that force reaches +-Fs (breakaway, the base moving
    against it). Two more states integrate the viscous power c vb^2 + cs (vs - vb)^2 and the friction power
    Fs |vb|. The release starts at xb = xs = d0, at rest (pushed quasi-statically at the base).

    Returns (out, t_stop): out[name] at t_out for name in xb, xs, vb, vs, ab, as, viscous, friction
    (before t = 0 at rest at d0), and the time the base is held for good (inf if not within t_out[-1]).
    """
    mb = m - ms
    names = ("xb", "xs", "vb", "vs", "ab", "as", "viscous", "friction")
    out = {n: np.full(t_out.shape, np.nan) for n in names}
    before = t_out < 0
    for n in names:
        out[n][before] = d0 if n in ("xb", "xs") else 0.0
    t_end = float(t_out[-1])
    t, y = 0.0, np.array([d0, d0, 0.0, 0.0, 0.0, 0.0])

    def hold(y):
        return k * y[0] - ks * (y[1] - y[0]) - cs * y[3]

    G = hold(y)
    held = abs(G) <= Fs
    s = -math.copysign(1.0, G)
    t_stop = math.inf
    while t < t_end:
        if held:
            xb = y[0]

            def rhs(_, q, xb=xb):
                fs = ks * (q[1] - xb) + cs * q[3]
                zero = 0.0 * q[3]
                return [zero, q[3], zero, -fs / ms, cs * q[3] ** 2, zero]

            def up(_, q):
                return hold(q) - Fs

            def down(_, q):
                return hold(q) + Fs

            up.terminal, up.direction = True, 1
            down.terminal, down.direction = True, -1
            events = [up, down]
        else:
            def rhs(_, q, s=s):
                fs = ks * (q[1] - q[0]) + cs * (q[3] - q[2])
                return [q[2], q[3], (-k * q[0] - c * q[2] + fs - Fs * s) / mb, -fs / ms,
                        c * q[2] ** 2 + cs * (q[3] - q[2]) ** 2, Fs * abs(q[2])]

            def turn(_, q):
                return q[2]

            turn.terminal, turn.direction = True, -s
            events = [turn]
        sol = solve_ivp(rhs, (t, t_end), y, method="DOP853", rtol=1e-13, atol=1e-16 * abs(d0), events=events,
                        dense_output=True)
        seg = (t_out >= t) & (t_out <= sol.t[-1])
        if seg.any():  # a piece shorter than a sampling interval (a stiff storey's stick) holds no sample
            q = sol.sol(t_out[seg])
            acc = rhs(0.0, q)  # the right-hand sides are written elementwise: they take the rows of samples too
            for n, row in zip(names, (q[0], q[1], q[2], q[3], acc[2], acc[3], q[4], q[5]), strict=True):
                out[n][seg] = row
        t, y = sol.t[-1], sol.y[:, -1].copy()
        if sol.status != 1:
            break
        if held:  # breakaway: the base moves against the force the sliders held
            s = -1.0 if sol.t_events[0].size else 1.0
            held = False
            t_stop = math.inf
        else:
            y[2] = 0.0
            G = hold(y)
            if abs(G) <= Fs:
                held, t_stop = True, t
            else:
                s = -math.copysign(1.0, G)
    if not held:
        t_stop = math.inf
    return out, t_stop
