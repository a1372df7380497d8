"""What the shaking-table analysis refuses to run, and what it must not mistake for a blow-up:
a table thrown down faster than g (the block flies, as a free body), a real blow-up (caught),
a floating block, a motion along an axis every block is held in, and a pulse too short for
the timestep.

One brick (25 x 12 x 5.5 mm, 1800 kg/m3, in-plane) on a wide fixed base, kn = ks = 3e7 Pa/m:
the model of the hostile-input sweep's finding that a vertical pulse stronger than g was
called a divergence."""

import math

import numpy as np
import pytest

import drydem as dd
from drydem.analysis.shake import ShakeSettings, pulse, shake_analysis
from drydem.errors import DivergenceError, DrydemError, ModelError
from conftest import stack_model

#: one-sine pulse of the finding: the table drops first, at up to 15 m/s2 > g, at 4 Hz
DROP_M_S2, FREQUENCY_HZ = -15.0, 4.0


def brick(**options) -> dd.Model:
    return stack_model([0.0055], joint=dd.JointMaterial(kn=3e7, ks=3e7, friction=0.5), supports=dd.Supports(fix_y=True), points=2,
                       **options)


def free_flight(amplitude_m_s2: float, frequency_hz: float) -> tuple[float, float, float]:
    """Lift-off time, peak height (m) and landing time (s) of a rigid block on a table whose
    acceleration is a(t) = A sin(2 pi f t) along z, A < -g (closed form, in the table's frame).

    The block follows the table while the table frame's body force per unit mass, -g - a(t),
    pushes it down: until sin(w t1) = g / |A| (w = 2 pi f). Then it flies: z'' = -g + |A| sin(w t),
    z(t1) = z'(t1) = 0, so z'(t) = -g (t - t1) + |A| / w (cos w t1 - cos w t) and
    z(t) = -g (t - t1)^2 / 2 + |A| / w (cos(w t1) (t - t1) - (sin w t - sin w t1) / w);
    the peak is where z' = 0 and the landing where z returns to 0 (both found on a 1 us grid;
    here both within the pulse, 1 / f = 0.25 s)."""
    w, a = 2 * math.pi * frequency_hz, abs(amplitude_m_s2)
    t1 = math.asin(dd.G / a) / w
    t = t1 + np.arange(1, int(1 / frequency_hz / 1e-6)) * 1e-6
    z = -dd.G * (t - t1) ** 2 / 2 + a / w * (math.cos(w * t1) * (t - t1) - (np.sin(w * t) - math.sin(w * t1)) / w)
    landed = int(np.argmax(z < 0.0))
    assert landed > 0, "the block lands after the pulse"
    return t1, float(z.max()), float(t[landed])


def test_a_table_dropping_faster_than_g_throws_the_block_up_as_a_free_body():
    """Not a divergence (the finding: 'more kinetic energy than gravity can have supplied'):
    the table's inertial force did the work. The block flies as the closed form says
    (:func:`free_flight`: lift-off at 28.4 ms, 13.82 mm up, landing at 173.5 ms; measured
    13.90 mm and 173.9 ms). The output every 1 ms places the peak within 1e-6 m and the landing
    within 1 ms; the joints' elastic closure, m g / (kn A) = 3e-6 m, is the block's start
    above its rest. The 0.6 % of the peak: the timestep grows as the contact opens (0.29 to
    0.75 ms) and a constant joint's velocity step across the change is first order
    (Simulation._update_inertia): ~1e-3 m/s over the 0.07 s climb."""
    settings = ShakeSettings(motion=pulse("one-sine", amplitude_m_s2=DROP_M_S2, frequency_hz=FREQUENCY_HZ, direction="z"),
                             duration_s=0.3, contact_damping_ratio=0.05, output_interval_s=0.001)
    result = shake_analysis(brick(), settings)
    lift_off, peak, landing = free_flight(DROP_M_S2, FREQUENCY_HZ)
    h = result.history
    assert h.uz_m.max() == pytest.approx(peak, rel=0.01)
    assert h.time_s[np.argmax(h.uz_m)] > lift_off
    top = int(np.argmax(h.uz_m))
    down = top + int(np.argmax(h.uz_m[top:] < 1e-5))  # back on its joints (10 um: three elastic closures)
    assert h.time_s[down] == pytest.approx(landing, abs=2e-3)
    assert not result.overturned and result.ended_by == "duration"
    assert result.max_rotation_rad < 1e-6  # thrown straight up: it does not turn


def test_a_blow_up_under_shaking_is_still_caught(monkeypatch):
    """The table's work is allowed for, yet a real blow-up is caught: were the critical
    timestep overestimated 20 x (as in test_solver), the undamped brick under a gentle table
    (1 m/s2 along x) stops with DivergenceError, saying the table's motion was counted; in one
    call of 10,000 cycles too (65 s of the table: the allowance is that of each TABLE_CHUNK
    of them, not of the call's end, which would let the brick fly off at 55 m/s unnoticed)."""
    import drydem.engine.inertia

    real = drydem.engine.inertia.critical_timestep
    monkeypatch.setattr(drydem.engine.inertia, "critical_timestep", lambda *args: 20.0 * real(*args))
    monkeypatch.setattr(drydem.engine.inertia, "free_flight_timestep", lambda *args: math.inf)  # its bound would hold the timestep
    sim = dd.Simulation(brick(solver=dd.SolverSettings(damping=0.0)))
    ground = np.zeros((10_000, 3))
    ground[:, 0] = 1.0
    with pytest.raises(DivergenceError, match="more kinetic energy than gravity and the table's motion can have supplied"):
        sim.cycle(10_000, ground_acceleration=ground)
    assert sim.cycles < 10_000


def test_a_floating_block_is_refused_as_a_model_that_cannot_stand():
    """A brick drawn 0.1 m above its base falls while the model settles, as in the tilting
    analysis's stage 1 ('the model cannot stand under its own weight'): it is not shaken."""
    model = brick(lift=0.1)
    settings = ShakeSettings(motion=pulse("one-sine", amplitude_m_s2=2.0, frequency_hz=FREQUENCY_HZ), contact_damping_ratio=0.05)
    with pytest.raises(DrydemError, match="the model cannot stand under its own weight: 'block0' fell while it settled") as error:
        shake_analysis(model, settings)
    assert "it was not run" in str(error.value)


def test_a_brick_on_joints_too_soft_to_carry_it_is_refused_with_the_reason():
    """kn = 1e4 Pa/m closes a 5.5 mm brick's bed by rho g h / kn = 9.71 mm under its own weight:
    it sinks through its base while settling, and the refusal says the joints are why."""
    model = stack_model([0.0055], joint=dd.JointMaterial(kn=1e4, ks=1e4, friction=0.5), supports=dd.Supports(fix_y=True), points=2)
    settings = ShakeSettings(motion=pulse("one-sine", amplitude_m_s2=2.0, frequency_hz=FREQUENCY_HZ), contact_damping_ratio=0.05)
    with pytest.raises(DrydemError, match="'block0' fell while it settled") as error:
        shake_analysis(model, settings)
    assert "the joints are too soft to carry it: under its own weight alone, 'block0' closes its joint by 9.71 mm" in str(error.value)


def test_a_brick_drawn_a_hair_above_its_base_settles_and_is_shaken():
    """The same rule as the tilting analysis's: a drop within two of its heights is a settling,
    not a fall (0.1 mm here, against 11 mm)."""
    settings = ShakeSettings(motion=pulse("one-sine", amplitude_m_s2=2.0, frequency_hz=FREQUENCY_HZ), duration_s=0.02,
                             contact_damping_ratio=0.05)
    assert not shake_analysis(brick(lift=1e-4), settings).overturned


def test_a_motion_along_an_axis_every_block_is_held_in_is_refused():
    """The finding: an in-plane model (fix_y) shaken along y gave 0 mm, silently; it cannot
    move at all (the supports take the table frame's force): refused, as the tilting analysis
    refuses to tilt it about x."""
    settings = ShakeSettings(motion=pulse("one-sine", amplitude_m_s2=20.0, frequency_hz=FREQUENCY_HZ, direction="y"),
                             contact_damping_ratio=0.05)
    with pytest.raises(ModelError, match=r"its y component shakes the model along y \(peak 20 m/s2\), but its blocks are held in y "
                                         r"\(\[supports\] fix_y = true\): the motion would move nothing; shake it along x or z"):
        shake_analysis(brick(), settings)


def test_a_pulse_shorter_than_twenty_timesteps_is_refused_at_the_start():
    """1 kHz has a period of 1 ms: 3.4 timesteps of this brick's 0.294 ms, which the analysis
    cannot follow (at least 20: at most 1 / (20 x 0.294 ms) = 170 Hz)."""
    settings = ShakeSettings(motion=pulse("one-sine", amplitude_m_s2=2.0, frequency_hz=1000.0), contact_damping_ratio=0.05)
    with pytest.raises(ModelError, match=r"its period, 0.001 s, spans 3.\d+ timesteps of 0.000294 s .* at least 20 timesteps: "
                                         r"give a frequency of at most 17\d(\.\d+)? Hz \(--frequency"):
        shake_analysis(brick(), settings)
