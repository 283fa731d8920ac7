"""Kinematics of the release: head retraction u, opening v and their rates (Tables 4-5).

alpha is the angle of the bars E1 with the loading axis (Fig. 7). Each head
retracts by ``u`` along the loading axis and each central hinge moves outwards by
``v``; both follow from alpha alone (one degree of freedom). All functions accept
floats or numpy arrays and return the same.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "retraction",
    "opening",
    "retraction_rate",
    "opening_rate",
    "retraction_acceleration",
    "opening_acceleration",
    "section_kinematics",
]


def retraction(alpha, alpha0, L1):
    """Retraction of each head along the loading axis, ``u = L1 (cos alpha0 - cos alpha)`` (Table 4) [m].

    Parameters
    ----------
    alpha : float or array
        Current angle [rad].
    alpha0 : float
        Angle at release [rad].
    L1 : float
        Bar length [m].

    Notes
    -----
    Written as ``2 L1 sin((alpha + alpha0)/2) sin((alpha - alpha0)/2)``, the same
    quantity free of cancellation when alpha is close to alpha0.
    """
    return 2.0 * L1 * np.sin(0.5 * (alpha + alpha0)) * np.sin(0.5 * (alpha - alpha0))


def opening(alpha, alpha0, L1):
    """Outward displacement of each central hinge, ``v = L1 (sin alpha - sin alpha0)`` (Table 4) [m].

    Computed as ``2 L1 cos((alpha + alpha0)/2) sin((alpha - alpha0)/2)`` (no cancellation).
    """
    return 2.0 * L1 * np.cos(0.5 * (alpha + alpha0)) * np.sin(0.5 * (alpha - alpha0))


def retraction_rate(alpha, alpha_dot, L1):
    """Head velocity ``u_dot = L1 sin(alpha) alpha_dot`` (Table 4) [m/s]."""
    return L1 * np.sin(alpha) * alpha_dot


def opening_rate(alpha, alpha_dot, L1):
    """Central hinge velocity ``v_dot = L1 cos(alpha) alpha_dot`` (Table 4) [m/s]."""
    return L1 * np.cos(alpha) * alpha_dot


def retraction_acceleration(alpha, alpha_dot, alpha_ddot, L1):
    """Head acceleration ``u_ddot = L1 (cos(alpha) alpha_dot^2 + sin(alpha) alpha_ddot)`` (Table 4) [m/s^2]."""
    return L1 * (np.cos(alpha) * alpha_dot**2 + np.sin(alpha) * alpha_ddot)


def opening_acceleration(alpha, alpha_dot, alpha_ddot, L1):
    """Central hinge acceleration (Table 4) [m/s^2].

    ``v_ddot = L1 (-sin(alpha) alpha_dot^2 + cos(alpha) alpha_ddot)``
    """
    return L1 * (-np.sin(alpha) * alpha_dot**2 + np.cos(alpha) * alpha_ddot)


def section_kinematics(z, alpha, alpha_dot, alpha_ddot, alpha0, L1):
    """Motion of the section of a bar E1 at distance z from the central hinge (Table 5).

    ``x = u z / L1`` (parallel to u) and ``y = v (1 - z / L1)`` (parallel to v), and
    their first and second time derivatives.

    Parameters
    ----------
    z : float or array
        Position along the bar, from the central hinge (z = 0) to the head (z = L1) [m].
    alpha, alpha_dot, alpha_ddot : float or array
        Angle [rad], rate [rad/s] and acceleration [rad/s^2].
    alpha0 : float
        Angle at release [rad].
    L1 : float
        Bar length [m].

    Returns
    -------
    dict of str to array
        ``x, y, x_dot, y_dot, x_ddot, y_ddot`` [m, m/s, m/s^2], broadcast over z and alpha.
    """
    s = np.asarray(z) / L1
    return {
        "x": retraction(alpha, alpha0, L1) * s,
        "y": opening(alpha, alpha0, L1) * (1.0 - s),
        "x_dot": retraction_rate(alpha, alpha_dot, L1) * s,
        "y_dot": opening_rate(alpha, alpha_dot, L1) * (1.0 - s),
        "x_ddot": retraction_acceleration(alpha, alpha_dot, alpha_ddot, L1) * s,
        "y_ddot": opening_acceleration(alpha, alpha_dot, alpha_ddot, L1) * (1.0 - s),
    }
