"""The joint law of one sub-contact (paper Eq. 1 and 3; 3DEC Coulomb slip with residual strength)."""

import numpy as np
import pytest

from drydem.engine.joints import kernel_joint, normal_law, shear_law
from drydem.model.parameters import JointMaterial

AREA = 1e-4  # m2


def law(closure, dus=(0.0, 0.0, 0.0), fs=(0.0, 0.0, 0.0), intact=True, slack=0.0, **material):
    """(F_n, F_s x, F_s y, F_s z, intact) as the kernels apply the two laws (``slack``: the
    round-off of the closure, m, drydem.engine.joints.touch_slack)."""
    joint = kernel_joint(JointMaterial(**({"kn": 1e8, "ks": 5e7, "friction": 0.5} | material)))
    fn, carries = normal_law(closure, AREA, intact, joint, slack)
    if not carries:
        return 0.0, 0.0, 0.0, 0.0, False
    return (fn, *shear_law(fn, *dus, *fs, AREA, intact, joint))


def test_normal_force_is_kn_area_closure():
    fn, *_ = law(1e-6)
    assert fn == pytest.approx(1e8 * AREA * 1e-6)


def test_open_joint_carries_nothing_without_tension():
    assert law(-1e-9, fs=(1.0, 0, 0)) == (0.0, 0.0, 0.0, 0.0, False)


def test_a_bond_opened_within_the_round_off_of_its_coordinates_keeps_its_cohesion():
    """Found by a hunt: blocks drawn touching computed a closure of -1.4e-17 m in their first
    cycle, which broke every bond of a joint with cohesion and T = 0. Within the slack (16 ulps
    of the coordinates, here of 0.15 m) the bond is touching, F_n = 0, and holds its cohesion;
    beyond it, or once failed, it is open."""
    from drydem.engine.joints import touch_slack

    slack = touch_slack(0.0, 0.0, 0.15, 0.1)
    assert slack == pytest.approx(16 * np.finfo(float).eps * 0.25)
    bonded = {"cohesion": 1e4, "tension": 0.0}
    assert law(-1.4e-17, fs=(0.5, 0, 0), slack=slack, **bonded) == (0.0, 0.5, 0.0, 0.0, True)
    assert law(-1.01 * slack, fs=(0.5, 0, 0), slack=slack, **bonded) == (0.0, 0.0, 0.0, 0.0, False)
    assert law(-1.4e-17, fs=(0.5, 0, 0), slack=slack, intact=False, **bonded) == (0.0, 0.0, 0.0, 0.0, False)
    # with a tensile strength, the round-off's tension is the spring's, within T A; without a
    # bond (no cohesion, no tension) an opening is an opening
    fn, *_, intact = law(-1.4e-17, slack=slack, cohesion=1e4, tension=1e3)
    assert intact and fn == pytest.approx(-1e8 * AREA * 1.4e-17)
    assert law(-1.4e-17, fs=(0.5, 0, 0), slack=slack) == (0.0, 0.0, 0.0, 0.0, False)


def test_elastic_shear_is_incremental_and_opposes_the_slip():
    fn, fx, fy, fz, intact = law(1e-5, dus=(1e-7, -2e-7, 0.0), fs=(0.01, 0, 0))
    np.testing.assert_allclose([fx, fy, fz], [0.01 - 5e7 * AREA * 1e-7, 5e7 * AREA * 2e-7, 0.0])
    assert intact


def test_coulomb_limit_scales_shear_back_keeping_its_direction():
    fn, fx, fy, fz, intact = law(1e-6, dus=(-3e-6, -4e-6, 0.0))
    limit = 0.5 * fn
    assert np.hypot(fx, fy) == pytest.approx(limit)
    assert fx / fy == pytest.approx(3 / 4)
    assert not intact


def test_cohesion_and_tension_hold_until_failure_then_vanish():
    material = {"cohesion": 1e3, "tension": 500.0}
    fn, *_ , intact = law(-2e-6, **material)  # tensile stress 200 Pa < 500 Pa
    assert fn == pytest.approx(-1e8 * AREA * 2e-6) and intact
    assert law(-6e-6, **material) == (0.0, 0.0, 0.0, 0.0, False)  # 600 Pa > 500 Pa: fails
    # a failed sub-contact has no tension any more, even at a small opening
    assert law(-2e-6, intact=False, **material) == (0.0, 0.0, 0.0, 0.0, False)
    # shear strength c A + mu Fn while intact, mu Fn after failure
    fn, fx, *_ = law(1e-7, dus=(-1.0, 0, 0), **material)
    assert fx == pytest.approx(1e3 * AREA + 0.5 * fn)
    fn, fx, *_ = law(1e-7, dus=(-1.0, 0, 0), intact=False, **material)
    assert fx == pytest.approx(0.5 * fn)
