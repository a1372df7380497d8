"""The rigid rocking block oracle (tests/oracles/rocking.py) against closed forms, conservation laws
and its own invariants, before ``drydem shake`` is held to it.

Sources of the expected values, each noted where used: Housner 1963 (BSSA 53(2)) for the uplift
threshold, the linearised free-rocking period and the restitution; energy conservation (derived in
the oracle's docstrings); a closed form of the linearised mode-2 overturning limit derived in
:func:`oracles.rocking.mode2_overturning_amplitude_ratio_linear`; and, for the table of minimum
overturning amplitudes, this oracle itself (regression values; computed by bisection on the
overturning flag and checked insensitive to max_step / 10 and rtol 1e-8).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from oracles.rocking import (
    RockingBlock,
    free_rocking_first_impact_time_s,
    free_rocking_quarter_period_s,
    minimum_overturning_amplitude,
    mode2_overturning_amplitude_ratio_linear,
    one_sine,
    peak_after_impacts,
    pulse_overturns,
    respond,
    rocking_energy,
)

#: alpha = 0.2 rad, R = 1 m, Housner's restitution (0.9408): the block of the DEM comparisons
BLOCK = RockingBlock.from_slenderness(0.2, 1.0)

#: minimum a_p / (g tan alpha) of a one-sine pulse that overturns BLOCK, against omega_p / p: this
#: oracle's own values (bisection on the overturning flag to 1e-6; unchanged with max_step / 10 and
#: rtol 1e-8; a 0.2 %-step scan from 1 up agrees). Not published numbers.
MINIMUM_OVERTURNING = {1.0: 1.10129, 2.0: 1.22004, 3.0: 1.38826, 4.0: 1.72798, 6.0: 4.12019}


def frequency_hz(block: RockingBlock, ratio: float) -> float:
    """The pulse frequency of omega_p / p = ratio."""
    return ratio * block.p_rad_s / (2.0 * math.pi)


def test_block_geometry():
    block = RockingBlock(half_width_m=0.3, half_height_m=0.4, restitution=0.9)
    assert block.R_m == pytest.approx(0.5)
    assert block.alpha_rad == pytest.approx(math.atan(0.75))
    assert block.p_rad_s == pytest.approx(math.sqrt(3 * 9.81 / 2.0))
    # Housner 1963: r = 1 - 1.5 sin^2(alpha); sin(alpha) = 0.6 here
    assert block.housner_restitution == pytest.approx(1 - 1.5 * 0.36)
    assert block.uplift_acceleration_m_s2 == pytest.approx(9.81 * 0.75)
    again = RockingBlock.from_slenderness(block.alpha_rad, 0.5, 0.9)
    assert (again.half_width_m, again.half_height_m) == pytest.approx((0.3, 0.4))
    assert BLOCK.restitution == pytest.approx(1 - 1.5 * math.sin(0.2) ** 2)


def test_one_sine_pulse():
    pulse = one_sine(2.0, 4.0)
    assert pulse(1 / 16) == pytest.approx(2.0)
    assert pulse(3 / 16) == pytest.approx(-2.0)
    assert pulse(-0.01) == 0.0 and pulse(0.26) == 0.0
    np.testing.assert_allclose(pulse(np.array([0.0, 1 / 16, 0.5])), [0.0, 2.0, 0.0], atol=1e-15)


@pytest.mark.parametrize("ratio", [0.5, 2.0, 6.0])
def test_block_stays_at_rest_below_g_tan_alpha(ratio):
    # Housner 1963: a block at rest uplifts only when |u_g''| > g tan(alpha)
    limit = BLOCK.uplift_acceleration_m_s2
    for amplitude in (0.999 * limit, -0.999 * limit):
        response = respond(BLOCK, one_sine(amplitude, frequency_hz(BLOCK, ratio)), 5.0)
        assert response.uplifts.size == 0 and response.impacts.size == 0 and not response.overturned
        assert np.all(response.theta_rad == 0.0)


def test_block_rocks_against_the_ground_acceleration_above_g_tan_alpha():
    limit, f = BLOCK.uplift_acceleration_m_s2, frequency_hz(BLOCK, 2.0)
    for sign in (1.0, -1.0):
        response = respond(BLOCK, one_sine(sign * 1.01 * limit, f), 2.0 / f)
        # uplift where A sin(2 pi f t) first reaches g tan(alpha)
        assert response.uplifts[0] == pytest.approx(math.asin(1 / 1.01) / (2 * math.pi * f), rel=1e-9)
        first = response.theta_rad[np.abs(response.theta_rad) > 0][0]
        assert np.sign(first) == -sign  # a base accelerating towards +x tips the block towards -x
        assert response.impacts.size >= 1 and not response.overturned


def test_uplift_from_statics_under_a_constant_acceleration():
    # a constant u_g'' = -1.5 g tan(alpha): theta > 0 (corner x = +b), starting with
    # theta'' = -p^2 [sin(alpha) + (u_g''/g) cos(alpha)] = 0.5 p^2 sin(alpha), and it falls
    a = -1.5 * BLOCK.uplift_acceleration_m_s2
    response = respond(BLOCK, lambda t: a, 10.0)
    assert response.uplifts.tolist() == [0.0] and response.overturned and response.impacts.size == 0
    assert response.theta_rad[-1] == pytest.approx(math.pi / 2)
    t = 1e-3
    theta, _ = response.at(t)
    assert theta[0] == pytest.approx(0.5 * 0.5 * BLOCK.p_rad_s**2 * math.sin(BLOCK.alpha_rad) * t**2, rel=1e-5)


def exact_quarter_period_s(block: RockingBlock, theta0: float) -> float:
    """T/4 by quadrature of the energy integral: t = int_0^theta0 dtheta / omega(theta) with
    omega^2 = 2 p^2 [cos(alpha - theta0) - cos(alpha - theta)] = 4 p^2 sin(alpha - (theta0 +
    theta)/2) sin((theta0 - theta)/2); the end singularity removed by theta0 - theta = theta0 s^2."""
    alpha, p = block.alpha_rad, block.p_rad_s

    def integrand(s):
        w = theta0 * s * s
        return 2 * theta0 * s / (2 * p * math.sqrt(math.sin(alpha - theta0 + w / 2) * math.sin(w / 2)))

    return quad(integrand, 0.0, 1.0, epsabs=0.0, epsrel=1e-13)[0]


def test_free_rocking_quarter_period_linearised_against_exact():
    def difference(alpha):
        block = RockingBlock.from_slenderness(alpha, 1.0)
        exact = free_rocking_first_impact_time_s(block, 0.5 * alpha)
        assert exact == pytest.approx(exact_quarter_period_s(block, 0.5 * alpha), rel=1e-9)
        return free_rocking_quarter_period_s(block, 0.5 * alpha) / exact - 1

    # observed: Housner's arccosh formula is short by 0.029 % at alpha = 0.1 rad (0.12 % at 0.2,
    # 0.47 % at 0.4; theta0 = alpha / 2), an error of order alpha^2 (sin x < x)
    at_01, at_005 = difference(0.1), difference(0.05)
    assert -1e-3 < at_01 < 0 and at_01 == pytest.approx(-2.93e-4, rel=0.02)
    assert at_01 / at_005 == pytest.approx(4.0, rel=0.02)


def test_respond_first_impact_and_quarter_period():
    theta0 = 0.15
    response = respond(BLOCK, lambda t: 0.0, 2.0, theta0=theta0)
    assert response.impacts[0] == pytest.approx(free_rocking_first_impact_time_s(BLOCK, theta0), rel=1e-9)
    assert response.impacts[0] == pytest.approx(exact_quarter_period_s(BLOCK, theta0), rel=1e-9)
    mirrored = respond(BLOCK, lambda t: 0.0, 2.0, theta0=-theta0)
    assert mirrored.impacts[0] == pytest.approx(response.impacts[0], rel=1e-12)


def test_peaks_after_impacts_follow_the_energy_balance():
    theta0, n = 0.15, 8
    response = respond(BLOCK, lambda t: 0.0, 12.0, theta0=theta0)
    bounds = [0.0, *response.impacts[: n + 1]]
    peaks = []
    for start, end in zip(bounds[1:-1], bounds[2:]):
        # omega = 0 between two impacts: the peak
        stop = brentq(lambda t: response.at(t)[1][0], start + 1e-9, end - 1e-9, xtol=1e-14)
        peaks.append(response.at(stop)[0][0])
    expected = peak_after_impacts(BLOCK, theta0, n)
    np.testing.assert_allclose(peaks, expected[1:], rtol=1e-8)
    assert np.all(np.sign(expected) == [(-1) ** k for k in range(n + 1)])
    # small rotations: |theta_{n+1}| ~ r^2 |theta_n| (cos(alpha - x) - cos(alpha) ~ x sin(alpha))
    tiny = peak_after_impacts(BLOCK, 1e-6, 1)
    assert abs(tiny[1] / tiny[0]) == pytest.approx(BLOCK.restitution**2, rel=1e-5)


def test_energy_is_conserved_between_impacts_and_lost_at_them():
    response = respond(BLOCK, lambda t: 0.0, 4.0, theta0=0.18)
    bounds = [0.0, *response.impacts[:5]]
    for start, end in zip(bounds[:-1], bounds[1:]):
        theta, omega = response.at(np.linspace(start, end, 400)[1:-1])
        energy = rocking_energy(BLOCK, theta, omega)
        assert np.ptp(energy) < 1e-10
    # at an impact the kinetic energy is multiplied by r^2
    for t in response.impacts[:4]:
        k = np.flatnonzero(response.time_s == t)
        assert k.size == 2
        before, after = response.omega_rad_s[k]
        assert after / before == pytest.approx(BLOCK.restitution, rel=1e-14)


def test_work_of_the_ground_motion_balances_the_energy():
    # d/dt [omega^2 / (2 p^2) + cos(alpha - |theta|)] = -(u_g''/g) omega cos(alpha - |theta|)
    limit, f = BLOCK.uplift_acceleration_m_s2, frequency_hz(BLOCK, 2.0)
    pulse = one_sine(2.0 * limit, f)
    response = respond(BLOCK, pulse, 1.0 / f)
    start, end = response.uplifts[0], (response.impacts[0] if response.impacts.size else 1.0 / f)
    assert end - start > 0.2 / f

    def power(t):
        theta, omega = response.at(t)
        return -pulse(t) / BLOCK.g * omega[0] * math.cos(BLOCK.alpha_rad - abs(theta[0]))

    work = quad(power, start, end, epsabs=1e-13, epsrel=1e-12, limit=200)[0]
    (theta0, theta1), (omega0, omega1) = response.at([start, end - 1e-12])
    change = rocking_energy(BLOCK, theta1, omega1) - rocking_energy(BLOCK, theta0, omega0)
    assert abs(work) > 1e-3
    assert change == pytest.approx(work, rel=1e-8)


def test_free_rocking_comes_to_rest():
    # r < 1: infinitely many impacts in a finite time; the oracle stops them once the next free peak
    # would be below 1e-7 alpha, then the block is at rest
    response = respond(BLOCK, lambda t: 0.0, 30.0, theta0=0.1)
    assert not response.overturned and 50 < response.impacts.size < 400
    assert np.all(np.diff(np.diff(response.impacts)) < 0)  # ever shorter cycles
    assert response.impacts[-1] < 30.0 and response.time_s[-1] == 30.0
    theta, omega = response.at([response.impacts[-1] + 1e-6, 29.0])
    assert np.all(theta == 0.0) and np.all(omega == 0.0)


@pytest.mark.parametrize("ratio", [1.0, 2.0, 4.0])
def test_mode2_overturning_converges_to_the_linearised_closed_form(ratio):
    # the nonlinear oracle's smallest amplitude that overturns without impact, at alpha = 0.05, vs
    # the closed form of the linearised equations (derived in mode2_overturning_amplitude_ratio_
    # linear). Observed by bisection: +1.0 % (alpha = 0.2), +0.26 % (0.1), +0.065 % (0.05),
    # +0.016 % (0.025) at omega_p/p = 4, i.e. an alpha^2 error; smaller at lower omega_p/p
    block = RockingBlock.from_slenderness(0.05, 1.0)
    limit, f = block.uplift_acceleration_m_s2, frequency_hz(block, ratio)
    closed = mode2_overturning_amplitude_ratio_linear(ratio)
    above = pulse_overturns(block, 1.003 * closed * limit, f)
    assert above.overturned and above.impacts.size == 0
    below = pulse_overturns(block, closed / 1.003 * limit, f)
    assert not (below.overturned and below.impacts.size == 0)


def test_linearised_mode2_limit_bounds():
    # slow pulses: the root sits just above sqrt(1 + W^2) (where sqrt(L^2 - 1) = W), -> 1
    assert mode2_overturning_amplitude_ratio_linear(0.25) == pytest.approx(math.sqrt(1 + 0.25**2), rel=1e-6)
    values = [mode2_overturning_amplitude_ratio_linear(w) for w in (0.5, 1, 2, 4, 8, 16)]
    assert np.all(np.diff(values) > 0)
    # fast pulses: L ~ W^2 / (2 pi) to leading order (the pulse's net displacement governs)
    assert 1.0 < mode2_overturning_amplitude_ratio_linear(50.0) / (50.0**2 / (2 * math.pi)) < 1.1


@pytest.mark.parametrize("ratio", sorted(MINIMUM_OVERTURNING))
def test_minimum_overturning_amplitude_table(ratio):
    limit, f = BLOCK.uplift_acceleration_m_s2, frequency_hz(BLOCK, ratio)
    minimum = MINIMUM_OVERTURNING[ratio]
    assert pulse_overturns(BLOCK, 1.003 * minimum * limit, f).overturned
    assert not pulse_overturns(BLOCK, minimum / 1.003 * limit, f).overturned


def test_minimum_overturning_amplitude_grows_with_frequency_and_tends_to_g_tan_alpha():
    values = [MINIMUM_OVERTURNING[w] for w in sorted(MINIMUM_OVERTURNING)]
    assert values[0] > 1.0 and np.all(np.diff(values) > 0)
    limit = BLOCK.uplift_acceleration_m_s2
    slow = minimum_overturning_amplitude(BLOCK, frequency_hz(BLOCK, 0.25), step_fraction=0.01)
    assert limit < slow < 1.05 * limit  # a slow pulse beyond g tan(alpha) is nearly a static push


def test_the_scan_finds_the_minimum():
    limit, f = BLOCK.uplift_acceleration_m_s2, frequency_hz(BLOCK, 2.0)
    found = minimum_overturning_amplitude(BLOCK, f, start=1.15 * limit, step_fraction=0.01)
    assert MINIMUM_OVERTURNING[2.0] <= found / limit <= 1.01 * MINIMUM_OVERTURNING[2.0]


def test_a_safe_region_above_the_minimum():
    # Zhang & Makris 2001 (qualitative): at omega_p/p = 6 the block overturns after one impact just
    # above the minimum (4.12 g tan alpha), survives larger pulses (this oracle: 8.89 to 9.62),
    # and overturns without impact above those
    limit, f = BLOCK.uplift_acceleration_m_s2, frequency_hz(BLOCK, 6.0)
    mode1 = pulse_overturns(BLOCK, 4.2 * limit, f)
    assert mode1.overturned and mode1.impacts.size == 1
    assert not pulse_overturns(BLOCK, 9.2 * limit, f).overturned
    mode2 = pulse_overturns(BLOCK, 9.8 * limit, f)
    assert mode2.overturned and mode2.impacts.size == 0


def test_self_similarity():
    # same alpha and omega_p/p, a 4x larger block: the same response in tau = p t (the equation in
    # tau involves only alpha, u_g''/g and omega_p/p), hence the same normalised minimum
    small, large = BLOCK, RockingBlock.from_slenderness(0.2, 4.0)
    tau = np.linspace(0.0, 8.0, 200)
    responses = []
    for block in (small, large):
        response = pulse_overturns(block, 1.5 * block.uplift_acceleration_m_s2, frequency_hz(block, 2.0))
        assert response.overturned and response.impacts.size == 1
        responses.append((response.overturn_time_s * block.p_rad_s, response.at(tau / block.p_rad_s)[0]))
    assert responses[0][0] == pytest.approx(responses[1][0], rel=1e-8)
    np.testing.assert_allclose(responses[0][1], responses[1][1], atol=1e-8)
    minima = [
        minimum_overturning_amplitude(b, frequency_hz(b, 3.0), start=1.35 * b.uplift_acceleration_m_s2, step_fraction=0.01)
        / b.uplift_acceleration_m_s2
        for b in (small, large)
    ]
    assert minima[0] == pytest.approx(minima[1], rel=1e-12)
    assert MINIMUM_OVERTURNING[3.0] <= minima[0] <= 1.01 * MINIMUM_OVERTURNING[3.0]
