"""The global stage of the isolation fit: where in the model's bounded space a record's misfit is lowest.

The weighted misfit of a free-vibration record (:mod:`quickrelease.building.isolation_fit`) has many basins: the
sliders' stick ends the motion at one reversal or another, so the chi-square jumps where the count of
half-cycles before the stick changes; friction trades against viscous damping (linear) and against the
yield force (bilinear: both act alike on the soft branch). A local least-squares search from design
values 20-30% off stops in the first basin it meets (Athanasiou, De Felice, Oliveto and Oliveto 2011 moved
to CMA-ES for the Solarino building's release record for this reason).

This module searches the model's physical parameters over a bounded box derived from the record (the
period from its zero crossings, the friction as a share of the push force, the yield force as a share of
the initial stiffness times d0, the damping ratio up to 0.4), in unit-cube coordinates, by independent
CMA-ES runs (Hansen's covariance-matrix adaptation, the maintained ``cma`` package) from seeded random
points. Its objective is the chi-square of a thinned record (at most :data:`SEARCH_SAMPLES` samples a
channel), the release instant held at its detected value, the pushed displacement at its record value
(searched as a factor where no displacement channel gives it), and each channel's offset profiled out in
closed form (the weighted mean of data minus model). The fit polishes the best point of each run, beside
the record's own starts and the design values, by least squares
(:func:`quickrelease.building.isolation_fit.fit_isolation`).

:func:`certificate` then says how many of those independent starts reached the best minimum and how far
the next distinct minimum lies above it: the honest statement of whether the global minimum was found.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["SearchBox", "search_box", "thin_channels", "profiled_chi2", "global_candidates", "Minimum",
           "SearchCertificate", "certificate", "cma_es", "noise_scatter", "record_period", "same_basin",
           "SEARCH_SAMPLES", "SEARCH_RUNS", "SEARCH_EVALUATIONS"]

#: Samples a channel at most in the global stage (the record thinned by an integer step).
SEARCH_SAMPLES = 1200
#: Independent CMA-ES runs of the global stage, per model.
SEARCH_RUNS = {"linear": 3, "bilinear": 4, "2dof": 3, "pendulum": 3, "boucwen": 4}
#: Objective evaluations per CMA-ES run at most, per model.
SEARCH_EVALUATIONS = {"linear": 500, "bilinear": 700, "2dof": 300, "pendulum": 500, "boucwen": 700}
#: Two minima are the same basin where every searched parameter lies within this many standard errors.
SAME_BASIN_SE = 3.0
#: The certificate calls a second basin competing when its chi-square lies within this of the best.
COMPETING_DELTA_CHI2 = 4.0


@dataclass(frozen=True)
class SearchBox:
    """The global stage's box: parameter names, their lower and upper bounds [SI or share], and which are
    searched on a log scale. The physical parameters map to unit-cube coordinates u in [0, 1]."""

    names: tuple[str, ...]
    lower: tuple[float, ...]
    upper: tuple[float, ...]
    scale: tuple[str, ...]
    """``"log"`` (the coordinate is the logarithm's share of its range), ``"sqrt"`` (the square root's: finer
    near the lower bound 0, where damping ratios and friction shares usually lie) or ``"linear"``."""

    def to_values(self, u) -> dict[str, float]:
        """Box coordinates -> the searched quantities (shares and SI values)."""
        u = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
        out = {}
        for n, lo, hi, sc, x in zip(self.names, self.lower, self.upper, self.scale, u, strict=True):
            if sc == "log":
                out[n] = float(math.exp(math.log(lo) + x * (math.log(hi) - math.log(lo))))
            elif sc == "linear":
                out[n] = float(lo + x * (hi - lo))
            else:
                out[n] = float((math.sqrt(lo) + x * (math.sqrt(hi) - math.sqrt(lo))) ** 2)
        return out

    def to_unit(self, values: dict[str, float]) -> np.ndarray:
        """Searched quantities -> box coordinates (clipped into the box)."""
        out = []
        for n, lo, hi, sc in zip(self.names, self.lower, self.upper, self.scale, strict=True):
            v = values[n]
            if sc == "log":
                x = (math.log(max(v, lo)) - math.log(lo)) / (math.log(hi) - math.log(lo))
            elif sc == "linear":
                x = (v - lo) / (hi - lo)
            else:
                x = (math.sqrt(max(v, lo)) - math.sqrt(lo)) / (math.sqrt(hi) - math.sqrt(lo))
            out.append(min(max(x, 0.0), 1.0))
        return np.array(out)


def noise_scatter(y: np.ndarray) -> float:
    """A channel's white-noise level from its second differences (1.4826 MAD / sqrt(6)), whatever it shows."""
    d2 = np.diff(y, 2)
    return 1.4826 * float(np.median(np.abs(d2 - np.median(d2)))) / math.sqrt(6.0)


def record_period(channels, t_r: float) -> float | None:
    """The record's apparent period [s], a hint for the search's box.

    The median time between crossings of the final level in the same direction (twice the time between two
    where there are only two), each the last sign change before the record crosses a band about the level
    (a Schmitt trigger: +-5% of the first swing, at least 5 noise levels, so that the noise near a crossing
    does not count), on the first channel (x, v, a, then the roof's) with at least two such crossings after
    the release ``t_r``. A displacement that crosses once or never (sliders that stick after a swing or two)
    gives twice the time from the release to its first turning point (a half-period after a release from
    rest): where it turns back by half the band and 10 noise levels, else where it reaches its final level; a
    velocity that crosses once, twice the time to its crossing (the turn); an acceleration that
    crosses once, four times (the equilibrium, a quarter-period after the release)."""
    for kind in ("x", "v", "a", "x_roof", "v_roof", "a_roof"):
        for ch in channels:
            if ch.kind != kind:
                continue
            moving = ch.t > t_r
            if np.count_nonzero(moving) < 20:
                continue
            t, y = ch.t[moving], ch.values[moving]
            y = y - np.median(y[-max(y.size // 10, 5):])
            sigma = noise_scatter(ch.values)
            h = max(0.05 * float(np.max(np.abs(y[: max(y.size // 4, 10)]))), 5.0 * sigma)
            if not h > 0:
                continue
            state, crossings = 0, []
            above, below = y > h, y < -h
            sign = np.signbit(y)
            zeros = np.nonzero(sign[1:] != sign[:-1])[0]  # y changes sign between zeros[k] and zeros[k] + 1
            for i in np.nonzero(above | below)[0]:
                if (above[i] and state < 0) or (below[i] and state > 0):
                    # the band is crossed: the level's last crossing before it, interpolated
                    j = zeros[np.searchsorted(zeros, i) - 1]
                    crossings.append(float(t[j] - y[j] * (t[j + 1] - t[j]) / (y[j + 1] - y[j])))
                if above[i]:
                    state = 1
                elif below[i]:
                    state = -1
            if len(crossings) >= 3:  # the median time between crossings of the same direction: a level a
                c = np.array(crossings)  # little off the axis moves up- and down-crossings alike
                return float(np.median(c[2:] - c[:-2]))
            if len(crossings) == 2:
                return float(2.0 * (crossings[1] - crossings[0]))
            if kind in ("v", "v_roof") and len(crossings) == 1:  # the velocity changes sign at the first turn
                return float(2.0 * (crossings[0] - t_r))
            if kind in ("a", "a_roof") and len(crossings) == 1:  # the acceleration a quarter-period after the release
                return float(4.0 * (crossings[0] - t_r))
            if kind in ("x", "x_roof") and not crossings:
                z = y * math.copysign(1.0, float(y[0]))  # from the pushed side (+) towards the final level
                # a first turning point short of the level, where the record turns back by half the band and
                # 10 noise levels (a creep after it, as of a Bouc-Wen element whose Qd exceeds Kd d0: the final
                # level is reached tens of seconds later, and twice that time was taken for the period)
                run = np.minimum.accumulate(z)
                back = np.nonzero(z > run + max(0.5 * h, 10.0 * sigma))[0]
                if back.size and back[0] > 0:
                    return float(2.0 * (t[int(np.argmin(z[: back[0]]))] - t_r))
                # else stuck at its first turning point: the final level
                near = np.nonzero(z <= 3.0 * sigma + 1e-3 * h)[0]
                if near.size and t[near[0]] > t[0]:
                    return float(2.0 * (t[near[0]] - t_r))
            if kind in ("x", "x_roof") and len(crossings) == 1:
                z = y * math.copysign(1.0, float(y[0]))  # from the pushed side (+) through the level
                c = int(np.searchsorted(t, crossings[0]))
                run = np.minimum.accumulate(z[c:])
                back = np.nonzero(z[c:] > run + h)[0]  # where it turns back up by the band, if it does
                seg = z[c: c + int(back[0])] if back.size else z[c:]
                low = float(np.min(seg))
                turn = c + int(np.nonzero(seg <= low + 3.0 * sigma + 1e-3 * h)[0][0])
                return float(2.0 * (t[turn] - t_r))
    return None


def search_box(model: str, period_hint: float | None, search_d0: bool,
               release: tuple[float, float] | None = None, damping: str = "viscous",
               flexible: bool = False) -> SearchBox:
    """The global stage's box for ``model``: period (log) within a factor around ``period_hint`` (the
    record's apparent period; 0.2-20 s without one; bilinear: the initial period T1 from a quarter to 1.5
    times it, since the soft branch lengthens the apparent period), damping ratio [0, 0.4], the sliders'
    force as a share ``friction_share`` of the push force in [0, 0.9] (above 1 the building never moves),
    these two on a square-root scale; bilinear also k2/k1 (log, 0.01-0.6) and the yield displacement over
    d0 ``yield_share`` (log, 0.01-1.5); 2dof the superstructure's period (log, 2% to 30% of the upper
    period bound, i.e. 4% to 60% of the apparent period) and damping ratio [0, 0.2], and so a layer under a
    flexible superstructure (``flexible``), its storey's period 4% to 60% of the apparent period; a factor on d0's
    estimate (0.85-1.15 where the displacement's level before the release gives it, the sensor's zero
    unknown; log 0.5-2 where no displacement gives d0, ``search_d0``); and the release instant
    within ``release`` (the record's first departure lags it; where a jump of the acceleration at the
    release falls between other samples than the data's, one sample's misfit outweighs the rest).

    pendulum: the friction share is mu_slow's (W mu_slow over W |d0| / R), with mu_fast / mu_slow (log, 1-5)
    and Constantinou's rate (log, 1-300 s/m); boucwen: its period is Kd's (0.7 to 4 times the apparent
    period, which the initial stiffness shortens), Qd over Kd |d0| ``strength_share`` (log, 0.02-2), dy over
    d0 ``yield_share`` (log, 0.003-0.5) and the shape n (log, 0.7-8). The power-law damper (``damping =
    "power"``): the damping ratio is that of the viscous damper giving the same force at the velocity
    ``pi |d0| / T``, beside the exponent alpha (0.15-1.9)."""
    if period_hint is not None and math.isfinite(period_hint) and period_hint > 0:
        if model == "bilinear":
            t_lo, t_hi = 0.25 * period_hint, 1.5 * period_hint
        elif model == "boucwen":
            t_lo, t_hi = 0.7 * period_hint, 4.0 * period_hint
        else:
            t_lo, t_hi = 0.5 * period_hint, 2.0 * period_hint
    else:
        t_lo, t_hi = 0.2, 20.0
    names = ["period", "damping_ratio", "friction_share"]
    lower = [t_lo, 0.0, 0.0]
    upper = [t_hi, 0.4, 0.9]
    scale = ["log", "sqrt", "sqrt"]
    if model == "bilinear":
        names += ["stiffness_ratio", "yield_share"]
        lower += [0.01, 0.01]
        upper += [0.6, 1.5]
        scale += ["log", "log"]
    if model == "pendulum":
        names += ["fast_ratio", "rate"]
        lower += [1.0, 1.0]
        upper += [5.0, 300.0]
        scale += ["log", "log"]
    if model == "boucwen":
        names += ["strength_share", "yield_share", "shape"]
        lower += [0.02, 0.003, 0.7]
        upper += [2.0, 0.5, 8.0]
        scale += ["log", "log", "log"]
    if damping == "power":
        names.append("damping_exponent")
        lower.append(0.15)
        upper.append(1.9)
        scale.append("linear")
    if model == "2dof" or flexible:  # a storey stiffer than 4% of the isolation period moves with the layer (and
        # its free vibration, stepped at a fraction of T_s through every stick, costs the most to evaluate); a
        # flexible layer's storey from the apparent period (the model's own period range differs: Kd's, T1's)
        top = t_hi if model == "2dof" or period_hint is None or not math.isfinite(period_hint) or period_hint <= 0 \
            else 2.0 * period_hint
        names += ["superstructure_period", "superstructure_damping_ratio"]
        lower += [max(0.02, 0.02 * top), 0.0]
        upper += [max(0.3 * top, 0.05), 0.2]
        scale += ["log", "sqrt"]
    names.append("d0_factor")  # from the record's own level: its sensor zero is not known yet
    lower.append(0.5 if search_d0 else 0.85)
    upper.append(2.0 if search_d0 else 1.15)
    scale.append("log" if search_d0 else "linear")
    if release is not None:
        names.append("release_time")
        lower.append(release[0])
        upper.append(release[1])
        scale.append("linear")
    return SearchBox(tuple(names), tuple(lower), tuple(upper), tuple(scale))


def box_parameters(model: str, mass: float, box_values: dict[str, float], d0: float,
                   damping: str = "viscous") -> dict[str, float]:
    """The searched quantities as the fit's parameters [SI]: F_s = share times the push force (linear,
    2dof: k |d0|; bilinear: k2 |d0| + f_p, f_p = F_y (1 - k2 / k1); boucwen: Kd |d0| + Qd), F_y = yield share
    times k1 |d0|; pendulum: mu_slow = share times |d0| / R, mu_fast = mu_slow times ``fast_ratio``; boucwen:
    Qd = ``strength_share`` Kd |d0|, dy = ``yield_share`` |d0|; power-law damper: C = 2 zeta sqrt(k m)
    v^(1 - alpha), v = pi |d0| / T."""
    p = dict(box_values)
    d0 = d0 * p.pop("d0_factor", 1.0)
    k = mass * (2.0 * math.pi / p["period"]) ** 2
    share = p.pop("friction_share")
    if model == "bilinear":
        r = p["stiffness_ratio"]
        fy = p.pop("yield_share") * k * abs(d0)
        p["yield_force"] = fy
        push = r * k * abs(d0) + fy * (1.0 - r) if fy < k * abs(d0) else k * abs(d0)
    elif model == "boucwen":
        qd = p.pop("strength_share") * k * abs(d0)
        p["characteristic_strength"] = qd
        p["yield_displacement"] = p.pop("yield_share") * abs(d0)
        push = k * abs(d0) + qd
    else:
        push = k * abs(d0)
    if model == "pendulum":
        weight = mass * 9.80665
        p["friction_slow"] = share * push / weight
        p["friction_fast"] = p["friction_slow"] * p.pop("fast_ratio")
    else:
        p["friction"] = share * push
    if damping == "power":
        zeta = p.pop("damping_ratio")
        v_ref = math.pi * abs(d0) / p["period"]
        p["damping_coefficient"] = 2.0 * zeta * math.sqrt(k * mass) * v_ref ** (1.0 - p["damping_exponent"])
    p["d0"] = d0
    return p


def box_values(model: str, mass: float, params: dict[str, float], d0_estimate: float, search_d0: bool,
               damping: str = "viscous") -> dict[str, float]:
    """The inverse of :func:`box_parameters` (a start's parameters as the box's quantities)."""
    d0 = params.get("d0", d0_estimate)
    k = mass * (2.0 * math.pi / params["period"]) ** 2
    out = {n: params[n] for n in ("period", "damping_ratio", "stiffness_ratio", "superstructure_period",
                                  "superstructure_damping_ratio", "release_time", "rate", "shape",
                                  "damping_exponent") if n in params}
    if model == "bilinear":
        r, fy = params["stiffness_ratio"], params["yield_force"]
        out["yield_share"] = fy / (k * abs(d0))
        push = r * k * abs(d0) + fy * (1.0 - r) if fy < k * abs(d0) else k * abs(d0)
    elif model == "boucwen":
        qd = params["characteristic_strength"]
        out["strength_share"] = qd / (k * abs(d0))
        out["yield_share"] = params["yield_displacement"] / abs(d0)
        push = k * abs(d0) + qd
    else:
        push = k * abs(d0)
    if model == "pendulum":
        out["friction_share"] = params["friction_slow"] * mass * 9.80665 / push
        out["fast_ratio"] = params["friction_fast"] / params["friction_slow"] if params["friction_slow"] > 0 else 1.0
    else:
        out["friction_share"] = params.get("friction", 0.0) / push
    if damping == "power":
        v_ref = math.pi * abs(d0) / params["period"]
        out["damping_ratio"] = (params["damping_coefficient"] / (2.0 * math.sqrt(k * mass))
                                / v_ref ** (1.0 - params["damping_exponent"]))
    out["d0_factor"] = d0 / d0_estimate
    return out


def thin_channels(channels, t_r: float | None = None, samples: int = SEARCH_SAMPLES, quiet: int = 100):
    """The channels thinned for the global stage, and the factor by which the sample count fell (full over
    thinned). The motion keeps up to ``samples`` samples a channel (an integer step), the quiet parts (before
    the release ``t_r``, and after the last sample of any channel more than 8 noise levels off its final
    level) up to ``quiet`` each: a record whose sliders stick after two seconds of sixty would otherwise
    leave a few thinned samples on the motion and the rest weighing the search towards any model that stops
    at the right level."""
    moving_end = -math.inf
    if t_r is not None:
        for ch in channels:
            level = float(np.median(ch.values[-max(ch.values.size // 10, 5):]))
            off = np.nonzero(np.abs(ch.values - level) > 8.0 * noise_scatter(ch.values))[0]
            if off.size:
                moving_end = max(moving_end, float(ch.t[off[-1]]))
    out, n_full, n_thin = [], 0, 0
    for ch in channels:
        if t_r is None or not math.isfinite(moving_end):
            parts = [np.arange(ch.t.size)]
        else:
            idx = np.arange(ch.t.size)
            before, after = idx[ch.t < t_r], idx[ch.t > moving_end]
            during = idx[(ch.t >= t_r) & (ch.t <= moving_end)]
            parts = [before, during, after]
        keep = []
        for k, part in enumerate(parts):
            if part.size == 0:
                continue
            cap = samples if (len(parts) == 1 or k == 1) else quiet
            keep.append(part[:: max(1, math.ceil(part.size / cap))])
        keep = np.concatenate(keep)
        if keep.size < 10:
            keep = np.arange(ch.t.size)[:: max(1, ch.t.size // 10)]
        out.append(type(ch)(ch.name, ch.kind, ch.t[keep], ch.values[keep], ch.noise, ch.offset,  # a BuildingChannel
                            ch.drift))
        n_full += ch.t.size
        n_thin += out[-1].t.size
    return out, n_full / n_thin


def profiled_chi2(misfit, params: dict[str, float]) -> float:
    """The chi-square of ``misfit`` (an :class:`quickrelease.building.isolation_fit._Misfit`) at ``params``, each
    channel's offset (and drift) at its best value in closed form: they enter linearly and a channel's
    weights are equal, so its best offset is the mean of data minus model over its samples (with a drift,
    the straight line fitted to them). inf outside the model's domain."""
    from ..errors import ParameterError

    zeros = {f"{z}_{c.name}": 0.0 for c in misfit.channels for z in ("offset", "drift")}
    try:
        model = misfit.model_vector({**params, **zeros})
    except (ParameterError, ValueError, ZeroDivisionError, OverflowError):
        return math.inf
    r = (model - misfit.data) / misfit.sig
    if not np.all(np.isfinite(r)):
        return math.inf
    total = 0.0
    for c in misfit.channels:
        seg = r[misfit.rows_of[f"offset_{c.name}"]]
        if c.drift:  # least squares on the columns (1, t - t_0) (or t - t_0 alone)
            ramp = misfit.ramp[f"drift_{c.name}"]
            cols = np.column_stack([np.ones_like(ramp), ramp] if c.offset else [ramp])
            coef = np.linalg.lstsq(cols, seg, rcond=None)[0]
            seg = seg - cols @ coef
        elif c.offset:
            seg = seg - float(np.mean(seg))
        total += float(seg @ seg)
    return total


def global_candidates(model: str, mass: float, misfit, box: SearchBox, base: dict[str, float], d0: float, *,
                      runs: int, evaluations: int, seed: int = 0, fixed: dict[str, float] | None = None,
                      progress=None, damping: str = "viscous") \
        -> tuple[list[dict[str, Any]], int]:
    """Independent CMA-ES runs over ``box`` (unit-cube coordinates, bounds [0, 1]) of the profiled chi-square
    of the thinned record, each from a seeded uniform random point with step 0.3. Returns each run's best
    point (``{"chi2", "parameters", "origin"}``, parameters in the fit's names, the offsets at their
    profiled values) and the evaluations spent."""
    rng = np.random.default_rng(seed)
    fixed = dict(fixed or {})
    spent = 0
    out = []

    def objective(u) -> float:
        nonlocal spent
        spent += 1
        p = {**base, **box_parameters(model, mass, box.to_values(u), d0, damping), **fixed}
        return profiled_chi2(misfit, p)

    for run in range(runs):
        if progress is not None:
            progress(f"{model}: global search, run {run + 1} of {runs}")
        run_seed = int(rng.integers(1, 2**31 - 1))
        x0 = np.random.default_rng(run_seed).uniform(0.1, 0.9, len(box.names))
        u, f, _ = cma_es(objective, x0, 0.3, evaluations, run_seed)
        p = {**base, **box_parameters(model, mass, box.to_values(u), d0, damping), **fixed}
        out.append({"chi2": float(f), "parameters": p, "origin": f"global search {run + 1}"})
    return out, spent


def cma_es(objective, x0, sigma0: float, evaluations: int, seed: int, *, tolfun: float = 1e-2,
           tolx: float = 1e-4, popsize: int | None = None) -> tuple[np.ndarray, float, int]:
    """Minimise ``objective`` over the unit cube by CMA-ES (Hansen 2016, "The CMA Evolution Strategy: a
    tutorial", arXiv:1604.00772: the (mu/mu_w, lambda) strategy with cumulative step-size adaptation and the
    rank-one and rank-mu covariance updates, default parameters of its Table 1). Samples outside [0, 1] are
    evaluated at their projection into the cube plus a quadratic penalty on the distance (the boundary
    handling of Hansen's ``cma`` package in its simplest form). Stops after ``evaluations``, or when the
    best values of the last 10 + 30 n / lambda generations and of the current one span less than
    ``tolfun``, or the step in every coordinate falls below ``tolx``. Returns the best point (in the cube),
    its value and the evaluations spent."""
    rng = np.random.default_rng(seed)
    n = len(x0)
    lam = popsize or 4 + int(3 * math.log(n))
    mu = lam // 2
    w = math.log(mu + 0.5) - np.log(np.arange(1, mu + 1))
    w /= w.sum()
    mueff = 1.0 / float(w @ w)
    cc = (4 + mueff / n) / (n + 4 + 2 * mueff / n)
    cs = (mueff + 2) / (n + mueff + 5)
    c1 = 2 / ((n + 1.3) ** 2 + mueff)
    cmu = min(1 - c1, 2 * (mueff - 2 + 1 / mueff) / ((n + 2) ** 2 + mueff))
    damps = 1 + 2 * max(0.0, math.sqrt((mueff - 1) / (n + 1)) - 1) + cs
    chin = math.sqrt(n) * (1 - 1 / (4 * n) + 1 / (21 * n * n))
    mean = np.asarray(x0, dtype=float).copy()
    sigma = float(sigma0)
    C, B, D = np.eye(n), np.eye(n), np.ones(n)
    pc, ps = np.zeros(n), np.zeros(n)
    best_x, best_f, spent, gen = mean.copy(), math.inf, 0, 0
    history: list[float] = []
    while spent + lam <= evaluations:
        gen += 1
        z = rng.standard_normal((lam, n))
        y = (z * D) @ B.T
        x = mean + sigma * y
        inside = np.clip(x, 0.0, 1.0)
        f = np.array([objective(xi) for xi in inside]) + 1e3 * np.sum((x - inside) ** 2, axis=1) * \
            (1.0 + abs(best_f if math.isfinite(best_f) else 0.0))
        spent += lam
        order = np.argsort(f)
        if f[order[0]] < best_f and np.all(x[order[0]] == inside[order[0]]):
            best_f, best_x = float(f[order[0]]), inside[order[0]].copy()
        elif f[order[0]] < best_f:
            value = objective(inside[order[0]])
            spent += 1
            if value < best_f:
                best_f, best_x = float(value), inside[order[0]].copy()
        old = mean
        ysel = y[order[:mu]]
        mean = old + sigma * (w @ ysel)
        zmean = w @ z[order[:mu]]
        ps = (1 - cs) * ps + math.sqrt(cs * (2 - cs) * mueff) * (B @ zmean)
        hsig = float(np.linalg.norm(ps) / math.sqrt(1 - (1 - cs) ** (2 * gen)) / chin < 1.4 + 2 / (n + 1))
        pc = (1 - cc) * pc + hsig * math.sqrt(cc * (2 - cc) * mueff) * (mean - old) / sigma
        C = ((1 - c1 - cmu) * C + c1 * (np.outer(pc, pc) + (1 - hsig) * cc * (2 - cc) * C)
             + cmu * (ysel.T * w) @ ysel)
        sigma *= math.exp((cs / damps) * (np.linalg.norm(ps) / chin - 1))
        C = np.triu(C) + np.triu(C, 1).T
        evals, B = np.linalg.eigh(C)
        D = np.sqrt(np.clip(evals, 1e-20, None))
        history.append(float(f[order[0]]))
        span = history[-(10 + int(30 * n / lam)):]
        if len(history) > 10 + 30 * n / lam and max(span) - min(span) < tolfun and f[order[-1]] - f[order[0]] < tolfun:
            break
        if np.all(sigma * np.sqrt(np.diag(C)) < tolx):
            break
    return best_x, best_f, spent


def _finite_or_big(value: float) -> float:
    return value if math.isfinite(value) else 1e300


@dataclass(frozen=True)
class Minimum:
    """A distinct local minimum the fit's starts reached (SI)."""

    chi2: float
    """Its chi-square on the whole record (the weights of the final fit)."""
    delta_chi2: float
    """Its chi-square above the best minimum's, in units of the noise (divided by the best's reduced
    chi-square where that exceeds 1, so that a model that does not describe the record every detail does
    not make every basin look distinct)."""
    parameters: dict[str, float]
    starts: tuple[str, ...]
    """The starts that reached it."""


@dataclass(frozen=True)
class SearchCertificate:
    """Whether the fit found the global minimum of its misfit, and how sure that is."""

    starts: int
    """Independent starts polished: the record's own (decay analysis, hysteresis loop, dissipation splits),
    the design values where given, and the global search's runs."""
    reached_best: int
    """Starts whose polished fit lies in the best minimum's basin (every searched parameter within
    ``SAME_BASIN_SE`` standard errors of it)."""
    next_best_delta_chi2: float
    """The next distinct minimum's chi-square above the best (noise units; inf where every start reached the
    best)."""
    global_minimum_confirmed: bool
    """At least two independent starts reached the best minimum and no distinct minimum lies within
    ``COMPETING_DELTA_CHI2`` of it."""
    minima: tuple[Minimum, ...]
    """The distinct minima, best first."""
    evaluations: int
    """Objective evaluations of the global search."""
    method: str = "CMA-ES (isolation_search.cma_es), independent seeded runs on the thinned record, then least squares"
    warnings: tuple[str, ...] = field(default=())

    def summary(self) -> dict[str, Any]:
        return {"method": self.method, "starts": self.starts, "reached_best": self.reached_best,
                "next_best_delta_chi2": self.next_best_delta_chi2 if math.isfinite(self.next_best_delta_chi2)
                else None, "global_minimum_confirmed": self.global_minimum_confirmed,
                "evaluations": self.evaluations,
                "minima": [{"chi2": m.chi2, "delta_chi2": m.delta_chi2, "parameters": m.parameters,
                            "starts": list(m.starts)} for m in self.minima]}


def same_basin(a: dict[str, float], b: dict[str, float], se: dict[str, float]) -> bool:
    """Whether two fits lie in one basin: every parameter of ``se`` within ``SAME_BASIN_SE`` standard errors
    (a parameter without a finite, positive standard error is not identified by the record and does not
    tell basins apart)."""
    for n, s in se.items():
        if n not in a or n not in b or not (math.isfinite(s) and s > 0):
            continue
        if abs(a[n] - b[n]) > SAME_BASIN_SE * s:
            return False
    return True


def certificate(groups: list[dict[str, Any]], starts: int, chi2_reduced: float, evaluations: int) \
        -> SearchCertificate:
    """The certificate of a multi-start from its distinct minima ``groups`` (``{"chi2", "parameters",
    "starts"}``, the best first, chi-squares on the whole record with the final weights), the count of
    ``starts`` polished, the best fit's reduced chi-square and the global search's ``evaluations``."""
    scale = max(chi2_reduced, 1.0) if math.isfinite(chi2_reduced) else 1.0
    head, best_chi2 = groups[0], groups[0]["chi2"]
    rest = sorted(groups[1:], key=lambda g: g["chi2"])
    minima = [Minimum(chi2=best_chi2, delta_chi2=0.0, parameters=head["parameters"], starts=tuple(head["starts"]))]
    minima += [Minimum(chi2=g["chi2"], delta_chi2=max(g["chi2"] - best_chi2, 0.0) / scale, parameters=g["parameters"],
                       starts=tuple(g["starts"])) for g in rest]
    next_best = minima[1].delta_chi2 if len(minima) > 1 else math.inf
    reached = len(head["starts"])
    confirmed = reached >= 2 and next_best >= COMPETING_DELTA_CHI2
    warnings = []
    if reached < 2:
        warnings.append(f"the best minimum was reached from {reached} of {starts} independent starts: the global "
                        "minimum is not confirmed")
    if next_best < COMPETING_DELTA_CHI2:
        warnings.append(f"a second minimum lies within delta chi-square {next_best:.2g} of the best (both in the "
                        "certificate; the 95% intervals cover both)")
    return SearchCertificate(starts=starts, reached_best=reached, next_best_delta_chi2=next_best,
                             global_minimum_confirmed=confirmed, minima=tuple(minima), evaluations=evaluations,
                             warnings=tuple(warnings))
