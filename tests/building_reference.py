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
