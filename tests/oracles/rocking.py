"""The rigid rocking block (Housner 1963) in plain Python: the oracle of ``drydem shake``.

A rigid rectangular block, width ``2 b`` and height ``2 h``, stands on a rigid base that moves
horizontally with acceleration ``u_g''(t)``. It cannot slide or jump (enough friction, no free
flight); it either rests on its base or rocks about one of its two bottom corners. With
``R = sqrt(b^2 + h^2)``, ``alpha = atan(b / h)`` (the slenderness angle) and, for a rectangular
block whose inertia about a corner is ``I_O = 4/3 m R^2``, the frequency parameter
``p = sqrt(3 g / (4 R))``, the equation of motion is (Housner 1963, "The behavior of inverted
pendulum structures during earthquakes", BSSA 53(2); in this form Zhang & Makris 2001, "Rocking
response of free-standing blocks under cycloidal pulses", J. Eng. Mech. 127(5), eq. 1-3)::

    theta'' = -p^2 [ sin(alpha sgn(theta) - theta) + (u_g''/g) cos(alpha sgn(theta) - theta) ]

Sign conventions (checked from statics below)
---------------------------------------------
The block lies in the x-z plane, x horizontal (the direction of shaking), z up, y = z cross x
(into the page when x points right and z up). ``theta`` is the block's rotation about +y
(right-handed), so ``theta > 0`` tips the top towards +x: the block rocks about its corner at
``x = +b`` and leans towards +x. ``theta < 0``: about the corner at ``x = -b``, leaning towards -x.
``u_g'' > 0`` accelerates the base towards +x.

Statics: about the corner ``x = +b`` the centre of mass sits at ``R (-sin(alpha - theta),
cos(alpha - theta))``; gravity gives the moment ``-m g R sin(alpha - theta)`` about +y
(restoring) and the inertial force ``-m u_g''`` (in the base's frame) the moment ``-m u_g'' R
cos(alpha - theta)``. Dividing by ``I_O`` gives the equation above for ``theta > 0``; the block
leaves rest on that corner when the bracket turns negative at ``theta = 0``, i.e. when
``u_g'' < -g tan(alpha)``. So a ground acceleration beyond ``g tan(alpha)`` makes the block rock
*against* it: ``u_g'' > +g tan(alpha)`` starts ``theta < 0`` (leaning towards -x, on the corner
``x = -b``), ``u_g'' < -g tan(alpha)`` starts ``theta > 0``.

Impacts
-------
When ``theta`` returns to 0 the block strikes the base with its other corner and goes on rocking
about it with the angular velocity multiplied by the coefficient of restitution ``r`` (same sign:
the motion continues through the upright position). Housner's value for a rectangular block, from
conservation of angular momentum about the new corner, is ``r = 1 - 1.5 sin^2(alpha)``
(:attr:`RockingBlock.housner_restitution`); ``r`` is a parameter here.

What the oracle leaves out: sliding, jumping (free flight), bouncing after impacts, the base's
vertical motion, deformability; and it assumes ``alpha`` < pi/2 with a rigid base.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

#: tolerances of the time integration (DOP853)
RTOL = 1e-10
ATOL = 1e-12
#: a guard against an endless sequence of phases (rest, rocking, impact) in :func:`respond`
MAX_PHASES = 100_000


@dataclass(frozen=True)
class RockingBlock:
    """A rigid rectangular block of width ``2 half_width_m`` and height ``2 half_height_m`` with
    the coefficient of restitution ``restitution`` (ratio of angular velocities after/before an
    impact; see :attr:`housner_restitution`)."""

    half_width_m: float
    half_height_m: float
    restitution: float
    g: float = 9.81

    @property
    def R_m(self) -> float:
        """Half-diagonal: distance from a bottom corner to the centre of mass, m."""
        return math.hypot(self.half_width_m, self.half_height_m)

    @property
    def alpha_rad(self) -> float:
        """Slenderness angle ``atan(b / h)``, rad: the angle of the diagonal with the vertical."""
        return math.atan2(self.half_width_m, self.half_height_m)

    @property
    def p_rad_s(self) -> float:
        """Frequency parameter ``sqrt(m g R / I_O) = sqrt(3 g / (4 R))``, rad/s."""
        return math.sqrt(3.0 * self.g / (4.0 * self.R_m))

    @property
    def housner_restitution(self) -> float:
        """Housner's (1963) coefficient of restitution ``1 - 1.5 sin^2(alpha)`` of this block's
        shape: angular momentum about the new corner conserved through the impact."""
        return 1.0 - 1.5 * math.sin(self.alpha_rad) ** 2

    @property
    def uplift_acceleration_m_s2(self) -> float:
        """``g tan(alpha)``: the ground acceleration that starts a block at rest rocking."""
        return self.g * math.tan(self.alpha_rad)

    @classmethod
    def from_slenderness(cls, alpha_rad: float, R_m: float, restitution: float | None = None, g: float = 9.81) -> RockingBlock:
        """The block of slenderness ``alpha_rad`` and half-diagonal ``R_m``; ``restitution``
        defaults to Housner's ``1 - 1.5 sin^2(alpha)``."""
        r = 1.0 - 1.5 * math.sin(alpha_rad) ** 2 if restitution is None else restitution
        return cls(R_m * math.sin(alpha_rad), R_m * math.cos(alpha_rad), r, g)


def _angular_acceleration(block: RockingBlock, side: int, theta: float, ground: float) -> float:
    """theta'' while rocking about the corner on ``side`` (+1: x = +b, theta >= 0; -1: x = -b)."""
    arg = side * block.alpha_rad - theta
    return -block.p_rad_s**2 * (math.sin(arg) + ground / block.g * math.cos(arg))


def rocking_energy(block: RockingBlock, theta, omega):
    """The block's mechanical energy in the base's frame, divided by ``m g R``, while it rocks:
    ``omega^2 / (2 p^2) + cos(alpha - |theta|)`` (``1/2 I_O omega^2 + m g z_G``). Constant in free
    rocking between impacts; ``cos(alpha)`` at rest. Under ground motion its rate is
    ``-(u_g''/g) omega cos(alpha - |theta|)`` (the work of the inertial force)."""
    theta, omega = np.asarray(theta, float), np.asarray(omega, float)
    return omega**2 / (2.0 * block.p_rad_s**2) + np.cos(block.alpha_rad - np.abs(theta))


# --------------------------------------------------------------------------------------------
# free rocking


def free_rocking_quarter_period_s(block: RockingBlock, theta0: float) -> float:
    """Housner's (1963) closed form of the time a block released from rest at ``theta0`` takes to
    reach ``theta = 0`` (a quarter of the free-rocking period), s::

        T / 4 = arccosh(1 / (1 - theta0 / alpha)) / p

    from the linearised equation ``theta'' = p^2 (theta - alpha)`` (``sin x ~ x``, ``cos x ~ 1``
    for ``x = alpha - theta``), whose solution is ``theta = alpha - (alpha - theta0) cosh(p t)``.
    Valid for slender blocks (``alpha`` up to about 0.2-0.35 rad, Housner's own range "alpha less
    than about 20 degrees") and ``0 < |theta0| < alpha``; it grows without bound as
    ``|theta0| -> alpha``. The linearisation overstates the restoring moment (``sin x < x``), so
    the closed form is slightly short: see :func:`free_rocking_first_impact_time_s` for the exact
    value.
    """
    ratio = abs(theta0) / block.alpha_rad
    if not 0.0 < ratio < 1.0:
        raise ValueError(f"need 0 < |theta0| < alpha = {block.alpha_rad}, got {theta0}")
    return math.acosh(1.0 / (1.0 - ratio)) / block.p_rad_s


def free_rocking_first_impact_time_s(block: RockingBlock, theta0: float) -> float:
    """The same time from the exact (nonlinear) equation of motion, by DOP853 integration from rest
    at ``theta0`` to the first ``theta = 0``, s."""
    if not 0.0 < abs(theta0) < block.alpha_rad:
        raise ValueError(f"need 0 < |theta0| < alpha = {block.alpha_rad}, got {theta0}")
    side = 1 if theta0 > 0 else -1

    def rhs(_t, y):
        return [y[1], _angular_acceleration(block, side, y[0], 0.0)]

    def upright(_t, y):
        return side * y[0]

    upright.terminal, upright.direction = True, -1
    # the exact time is a little longer than the linearised one: a generous horizon
    horizon = 2.0 * free_rocking_quarter_period_s(block, theta0) + 10.0 / block.p_rad_s
    sol = solve_ivp(rhs, (0.0, horizon), [theta0, 0.0], method="DOP853", rtol=RTOL, atol=ATOL, events=upright)
    if not sol.t_events[0].size:
        raise RuntimeError("no impact found")  # pragma: no cover
    return float(sol.t_events[0][0])


def peak_after_impact(block: RockingBlock, theta_peak: float) -> float:
    """The magnitude of the next peak rotation of a block rocking freely from the peak
    ``theta_peak`` (rad), from the energy balance (see :func:`peak_after_impacts`)."""
    alpha, r = block.alpha_rad, block.restitution
    before = math.cos(alpha - abs(theta_peak)) - math.cos(alpha)
    return alpha - math.acos(math.cos(alpha) + r**2 * before)


def peak_after_impacts(block: RockingBlock, theta0: float, n: int) -> np.ndarray:
    """The successive peak rotations of a block released from rest at ``theta0`` and rocking freely:
    ``n + 1`` signed values, ``theta0`` first, alternating in sign (each impact takes the block to
    the other corner).

    Derivation: between impacts the energy ``omega^2 / (2 p^2) + cos(alpha - |theta|)`` (per
    ``m g R``, :func:`rocking_energy`) is constant, so the block reaches ``theta = 0`` from the
    peak ``theta_n`` with ``omega^2 / (2 p^2) = cos(alpha - |theta_n|) - cos(alpha)``; the impact
    multiplies ``omega`` by ``r``, so the kinetic energy by ``r^2``; the block then climbs on the
    other corner until it stops at::

        cos(alpha - |theta_{n+1}|) - cos(alpha) = r^2 [cos(alpha - |theta_n|) - cos(alpha)]

    exact for the nonlinear equation (no linearisation). For slender blocks and small rotations it
    is ``|theta_{n+1}| ~ r^2 |theta_n|``.
    """
    peaks = [float(theta0)]
    for _ in range(n):
        peaks.append(-math.copysign(peak_after_impact(block, peaks[-1]), peaks[-1]))
    return np.array(peaks)


# --------------------------------------------------------------------------------------------
# forced response


@dataclass(frozen=True)
class OneSinePulse:
    """The one-sine acceleration pulse ``A sin(2 pi f t)`` for ``0 <= t <= 1/f``, 0 outside
    (Zhang & Makris 2001's type-A cycloidal pulse, m/s2). Callable on floats and arrays."""

    amplitude_m_s2: float
    frequency_hz: float

    @property
    def duration_s(self) -> float:
        return 1.0 / self.frequency_hz

    def __call__(self, t):
        t = np.asarray(t, float)
        value = np.where((t >= 0.0) & (t <= self.duration_s), self.amplitude_m_s2 * np.sin(2.0 * math.pi * self.frequency_hz * t), 0.0)
        return float(value) if value.ndim == 0 else value


def one_sine(amplitude_m_s2: float, frequency_hz: float) -> OneSinePulse:
    """``a(t) = A sin(2 pi f t)`` for ``0 <= t <= 1/f``, else 0 (Zhang & Makris 2001, type-A
    pulse): the base first accelerates towards +x, so the block rocks first with ``theta < 0``."""
    return OneSinePulse(float(amplitude_m_s2), float(frequency_hz))


@dataclass(frozen=True)
class _Segment:
    start: float
    end: float
    side: int  # 0: at rest
    solution: object = None  # OdeSolution while rocking


@dataclass(frozen=True)
class RockingResponse:
    """A block's response: the integrator's own time points (with the start and end of every rest
    and rocking phase), the rotation and angular velocity there; ``overturned`` when
    ``|theta|`` reached pi/2 (the response then ends at that time, ``overturn_time_s``); the
    times of the impacts (``theta`` back to 0 while rocking) and of the uplifts (rest -> rocking).
    An impact's time appears twice in ``time_s``, with the angular velocity just before and just
    after it. :meth:`at` interpolates the integrator's dense output at any times (0 at rest)."""

    time_s: np.ndarray
    theta_rad: np.ndarray
    omega_rad_s: np.ndarray
    overturned: bool
    impacts: np.ndarray
    uplifts: np.ndarray
    overturn_time_s: float | None
    segments: tuple[_Segment, ...] = field(repr=False, default=())

    def at(self, times) -> tuple[np.ndarray, np.ndarray]:
        """(theta, omega) at ``times`` (s, within the response), from the dense output."""
        times = np.atleast_1d(np.asarray(times, float))
        theta, omega = np.zeros_like(times), np.zeros_like(times)
        starts = np.array([s.start for s in self.segments])
        which = np.clip(np.searchsorted(starts, times, side="right") - 1, 0, len(self.segments) - 1)
        for k in np.unique(which):
            seg, mask = self.segments[k], which == k
            if seg.side:
                y = seg.solution(np.clip(times[mask], seg.start, seg.end))
                theta[mask], omega[mask] = y[0], y[1]
        return theta, omega

    @property
    def peak_rad(self) -> float:
        """The largest ``|theta|`` reached (at the integrator's points and the events)."""
        return float(np.max(np.abs(self.theta_rad)))


def _first_uplift(block: RockingBlock, ground_acc: Callable[[float], float], t0: float, t1: float, step: float) -> float | None:
    """The first time in [t0, t1] at which ``|u_g''|`` exceeds ``g tan(alpha)``: scanned on a grid
    of spacing ``step`` and refined by Brent's method, then nudged forward to where the excess is
    strictly positive (an excursion shorter than ``step`` between two grid points is missed)."""
    limit = block.uplift_acceleration_m_s2

    def excess(t):
        return abs(ground_acc(t)) - limit

    if excess(t0) > 0.0:
        return t0
    n = max(1, math.ceil((t1 - t0) / step))
    grid = np.linspace(t0, t1, n + 1)
    before = t0
    for t in grid[1:]:
        if excess(t) > 0.0:
            root = brentq(excess, before, t, xtol=1e-15, rtol=4 * np.finfo(float).eps)
            nudge = 4 * np.finfo(float).eps * max(1.0, abs(root))
            while root < t and excess(root) <= 0.0:
                root, nudge = min(root + nudge, t), 2.0 * nudge
            return root
        before = t
    return None


def respond(
    block: RockingBlock,
    ground_acc: Callable[[float], float],
    duration_s: float,
    *,
    theta0: float = 0.0,
    omega0: float = 0.0,
    max_step: float | None = None,
    rest_fraction: float = 1e-7,
) -> RockingResponse:
    """The block's response to the ground acceleration ``ground_acc(t)`` (m/s2, +x) over
    ``[0, duration_s]`` from ``theta0``, ``omega0`` (a block at ``theta0 = omega0 = 0`` starts at
    rest).

    Phases:

    * at rest: the block stays put until ``|u_g''| > g tan(alpha)`` (found by scanning the ground
      acceleration every ``max_step``, then refined; see :func:`_first_uplift`), then starts rocking
      from ``theta = omega = 0`` on the corner opposite to the acceleration (``u_g'' > 0``:
      ``theta < 0``);
    * rocking: DOP853 (rtol 1e-10, atol 1e-12, steps no longer than ``max_step``) on the exact
      equation, with the pivot corner held fixed, until an event: **impact** (``theta`` back to 0,
      then the angular velocity is multiplied by ``r`` and the block goes on about the other
      corner), **overturn** (``|theta| = pi/2``: the block has fallen, the response ends),
      or the end of ``duration_s``;
    * back to rest: after an impact, if the energy left would lift the block, rocking freely, by
      less than ``rest_fraction * alpha`` (the peak from :func:`rocking_energy`), the block is taken
      to be at rest (``theta = omega = 0``). This ends the infinite sequence of ever shorter rocking
      cycles of free rocking with ``r < 1`` (they sum to a finite time) at a negligible error; if
      the ground acceleration already exceeds ``g tan(alpha)`` at that time, the block starts
      rocking again at once as from rest.

    Overturning rule: ``overturned`` is True when ``|theta|`` reaches pi/2 within ``duration_s``.
    A block that ends the excitation with the energy to pass ``|theta| = alpha`` always falls, but
    the closer to that limit, the longer it takes (the unstable equilibrium at ``|theta| = alpha``,
    centre of mass above the corner, repels at the rate ``p``): callers give it time after the excitation (``~ 10 / p`` or more).

    ``max_step`` defaults to ``0.05 / p``; keep it well below the shortest feature of the ground
    motion, which the rest-phase scan and the integrator must not step over.
    """
    if max_step is None:
        max_step = 0.05 / block.p_rad_s
    alpha, p = block.alpha_rad, block.p_rad_s
    ts, thetas, omegas = [0.0], [float(theta0)], [float(omega0)]
    impacts: list[float] = []
    uplifts: list[float] = []
    segments: list[_Segment] = []
    overturn_time = None
    t, theta, omega = 0.0, float(theta0), float(omega0)
    if theta != 0.0:
        side = 1 if theta > 0.0 else -1
    elif omega != 0.0:
        side = 1 if omega > 0.0 else -1
    else:
        side = 0

    def record(times, th, om):
        ts.extend(times)
        thetas.extend(th)
        omegas.extend(om)

    for _ in range(MAX_PHASES):
        if t >= duration_s:
            break
        if side == 0:  # at rest
            start = _first_uplift(block, ground_acc, t, duration_s, max_step)
            end = duration_s if start is None else start
            if end > t:
                segments.append(_Segment(t, end, 0))
                record([end], [0.0], [0.0])
            if start is None:
                break
            t = start
            uplifts.append(t)
            # on the corner away from the acceleration (|u_g''(t)| > g tan(alpha) > 0 here)
            side = -1 if ground_acc(t) > 0.0 else 1
            theta = omega = 0.0
            continue

        s = side

        def rhs(_t, y, s=s):
            return [y[1], _angular_acceleration(block, s, y[0], ground_acc(_t))]

        def impact(_t, y, s=s):
            return s * y[0]

        def overturn(_t, y, s=s):
            return s * y[0] - 0.5 * math.pi

        impact.terminal, impact.direction = True, -1
        overturn.terminal, overturn.direction = True, 1
        sol = solve_ivp(
            rhs, (t, duration_s), [theta, omega], method="DOP853", rtol=RTOL, atol=ATOL,
            max_step=max_step, events=(impact, overturn), dense_output=True,
        )
        if sol.status < 0:
            raise RuntimeError(f"integration failed at t = {sol.t[-1]}: {sol.message}")  # pragma: no cover
        end = float(sol.t[-1])
        segments.append(_Segment(t, end, s, sol.sol))
        hit_ground, fell = sol.t_events[0].size > 0, sol.t_events[1].size > 0
        body = slice(1, -1) if (hit_ground or fell) else slice(1, None)
        record(sol.t[body], sol.y[0, body], sol.y[1, body])
        if fell:
            overturn_time = float(sol.t_events[1][0])
            record([overturn_time], [s * 0.5 * math.pi], [float(sol.y_events[1][0][1])])
            break
        if not hit_ground:
            break
        t = float(sol.t_events[0][0])
        omega_before = float(sol.y_events[0][0][1])
        record([t], [0.0], [omega_before])
        impacts.append(t)
        omega = block.restitution * omega_before
        theta = 0.0
        side = -s
        # the peak the block would reach rocking freely on its new corner
        top = math.cos(alpha) + omega**2 / (2.0 * p**2)
        free_peak = alpha - math.acos(top) if top < 1.0 else alpha
        if free_peak < rest_fraction * alpha:
            side, omega = 0, 0.0
        # the state just after the impact
        record([t], [0.0], [omega])

    else:
        raise RuntimeError(f"more than {MAX_PHASES} rest and rocking phases before t = {duration_s} s")  # pragma: no cover
    return RockingResponse(
        time_s=np.array(ts),
        theta_rad=np.array(thetas),
        omega_rad_s=np.array(omegas),
        overturned=overturn_time is not None,
        impacts=np.array(impacts),
        uplifts=np.array(uplifts),
        overturn_time_s=overturn_time,
        segments=tuple(segments),
    )


# --------------------------------------------------------------------------------------------
# overturning under a one-sine pulse


def pulse_overturns(block: RockingBlock, amplitude_m_s2: float, frequency_hz: float, *, free_time_s: float | None = None) -> RockingResponse:
    """The response to :func:`one_sine` (``amplitude_m_s2``, ``frequency_hz``) over the pulse and
    ``free_time_s`` after it (default ``3 / f + 20 / p``), steps no longer than a 40th of the pulse
    nor ``0.05 / p``."""
    p = block.p_rad_s
    free = 3.0 / frequency_hz + 20.0 / p if free_time_s is None else free_time_s
    return respond(
        block, one_sine(amplitude_m_s2, frequency_hz), 1.0 / frequency_hz + free,
        max_step=min(0.025 / frequency_hz, 0.05 / p),
    )


def minimum_overturning_amplitude(
    block: RockingBlock,
    frequency_hz: float,
    *,
    start: float | None = None,
    step_fraction: float = 0.01,
    stop: float | None = None,
    free_time_s: float | None = None,
) -> float | None:
    """The smallest amplitude of a one-sine pulse of ``frequency_hz`` that overturns the block, m/s2,
    to within ``step_fraction`` (relative): the amplitudes ``start (1 + step_fraction)^k`` are tried
    upwards from ``start`` (default ``g tan(alpha)``, which cannot even lift the block) and the
    first that overturns (:func:`pulse_overturns`) is returned; None if none up to ``stop``
    (default ``2 (1 + W + W^2 / (2 pi)) g tan(alpha)`` with ``W = omega_p / p``: twice the large-W
    asymptote of the linearised mode-2 limit, :func:`mode2_overturning_amplitude_ratio_linear`,
    and above it at every W).

    A scan, not a bisection: the set of amplitudes that overturn is not an interval. Above the
    smallest one (often overturning after one impact, Zhang & Makris's "mode 1") there can be a
    "safe region" of larger amplitudes that do not overturn, before the amplitudes that overturn
    without impact ("mode 2") take over (Zhang & Makris 2001, figures of the minimum overturning
    acceleration spectra).
    """
    limit = block.uplift_acceleration_m_s2
    ratio = 2.0 * math.pi * frequency_hz / block.p_rad_s
    amplitude = limit if start is None else float(start)
    stop = 2.0 * (1.0 + ratio + ratio**2 / (2.0 * math.pi)) * limit if stop is None else float(stop)
    while amplitude <= stop:
        if pulse_overturns(block, amplitude, frequency_hz, free_time_s=free_time_s).overturned:
            return amplitude
        amplitude *= 1.0 + step_fraction
    return None


def mode2_overturning_amplitude_ratio_linear(frequency_ratio: float) -> float:
    """The smallest ``a_p / (g tan alpha)`` of a one-sine pulse (``omega_p / p`` =
    ``frequency_ratio``) that overturns a slender block *without any impact*, from Housner's
    linearised equations, in closed form (derived here, not quoted from a paper).

    With ``tau = p t``, ``W = omega_p / p``, ``L = a_p / (g alpha)`` and ``psi = -theta / alpha``
    (the pulse starts towards +x so the block rocks with ``theta < 0``), the linearised equation is
    ``psi'' - psi = L sin(W tau) - 1`` from rest at the uplift ``L sin(W tau0) = 1``. Its solution
    is ``psi = 1 - L sin(W tau) / (1 + W^2) + C1 e^tau + C2 e^-tau``; after the pulse
    (``tau_e = 2 pi / W``) the free solution ``1 + D1 e^tau + D2 e^-tau`` runs away (overturns)
    iff ``D1 > 0``. Matching at ``tau0`` and ``tau_e`` reduces that to::

        exp((2 pi - asin(1/L)) / W) (sqrt(L^2 - 1) - W) > L

    provided ``psi`` stays positive during the pulse (no impact; after the pulse, ``D1 > 0`` and
    ``psi(tau_e) > 0`` keep it positive). The function returns the root ``L`` of equality (it
    checks the no-impact proviso). As ``W -> 0`` it tends to 1; for large ``W`` it grows like
    ``W``. For a block of finite ``alpha`` the nonlinear equation gives a slightly different value
    (``tan alpha`` for ``alpha`` in the threshold and ``cos``, ``sin`` terms); the tests compare at
    small ``alpha``.
    """
    w = float(frequency_ratio)

    def margin(lam):
        return math.exp((2.0 * math.pi - math.asin(1.0 / lam)) / w) * (math.sqrt(lam * lam - 1.0) - w) - lam

    low = math.sqrt(1.0 + w * w)  # margin < 0 there (sqrt(L^2-1) = W)
    high = 2.0 * low
    while margin(high) <= 0.0:
        high *= 2.0
    lam = brentq(margin, low, high, xtol=1e-13, rtol=1e-13)
    # no impact during the pulse: psi > 0 on (tau0, tau_e]
    tau0 = math.asin(1.0 / lam) / w
    c1 = math.exp(-tau0) * (-w * w + lam * w * math.cos(w * tau0)) / (2.0 * (1.0 + w * w))
    c2 = math.exp(tau0) * (-w * w - lam * w * math.cos(w * tau0)) / (2.0 * (1.0 + w * w))
    tau = np.linspace(tau0, 2.0 * math.pi / w, 2001)[1:]
    psi = 1.0 - lam * np.sin(w * tau) / (1.0 + w * w) + c1 * np.exp(tau) + c2 * np.exp(-tau)
    if np.min(psi) <= 0.0:
        raise ValueError(f"at omega_p/p = {w} the linearised block strikes the base during the pulse: no mode-2 closed form")
    return lam
