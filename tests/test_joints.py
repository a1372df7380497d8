"""The joint law of one sub-contact (paper Eq. 1 and 3; 3DEC Coulomb slip with residual strength)."""

import numpy as np
import pytest

from drydem.engine.joints import kernel_joint, normal_law, shear_law
from drydem.model.parameters import JointMaterial

AREA = 1e-4  # m2


def law(closure, dus=(0.0, 0.0, 0.0), fs=(0.0, 0.0, 0.0), intact=True, **material):
    """(F_n, F_s x, F_s y, F_s z, intact) as the kernels apply the two laws."""
    joint = kernel_joint(JointMaterial(**({"kn": 1e8, "ks": 5e7, "friction": 0.5} | material)))
    fn, carries = normal_law(closure, AREA, intact, joint)
    if not carries:
        return 0.0, 0.0, 0.0, 0.0, False
    return (fn, *shear_law(fn, *dus, *fs, AREA, intact, joint))


def test_normal_force_is_kn_area_closure():
    fn, *_ = law(1e-6)
    assert fn == pytest.approx(1e8 * AREA * 1e-6)


def test_open_joint_carries_nothing_without_tension():
    assert law(-1e-9, fs=(1.0, 0, 0)) == (0.0, 0.0, 0.0, 0.0, False)


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
