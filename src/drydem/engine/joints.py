"""The dry-joint constitutive law of one sub-contact (paper Eqs. 1 and 3; 3DEC's Coulomb slip joint).

With closure u_n (m, positive when the blocks interpenetrate), shear displacement
increment du_s (m, tangential, incident block relative to the reference block) and
tributary area A (m2):

    F_n = k_n A u_n                          compression positive
    F_s <- F_s - k_s A du_s                  incremental, force on the incident block
    |F_s| <= max(c A + mu F_n, 0)            Mohr-Coulomb, scaled back to the limit when exceeded

No tension by default: F_n = 0 and F_s = 0 once the joint opens. With a tensile
strength T and cohesion c, F_n >= -T A while the sub-contact is intact; it fails
(intact = False, c and T lost for good) when F_n < -T A or when it slips (Itasca
3DEC, "Coulomb slip joint model with residual strength").

Stress-dependent joints (``JointMaterial.model`` "power" or "affine"): k_n and k_s depend on
the sub-contact's normal stress sigma = F_n / A; F_n = sigma(u_n) A with d sigma = k_n(sigma) d u_n
integrated exactly (:func:`normal_stress`), and the shear increment uses the tangent k_s(sigma).
The critical timestep follows the stiffness reached (:func:`drydem.engine.inertia.stiffness_bound`).
"""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np
from numba.extending import overload

from drydem import compiled_cache
from drydem.model.parameters import JointMaterial


class JointConstants(NamedTuple):
    """A joint of constant stiffness as plain floats for the kernels (units as in :class:`JointMaterial`)."""

    kn: float
    ks: float
    friction: float
    cohesion: float
    tension: float


#: law codes of :class:`StressJoint`
POWER, AFFINE = 1, 2


class StressJoint(NamedTuple):
    """A stress-dependent joint for the kernels: :class:`JointConstants`' fields, then the law.

    law : POWER or AFFINE. exponent_n, exponent_s : the power law's exponents. per_stress_n,
    per_stress_s : the affine law's slopes, 1/m. stress_ref : Pa. k_min, k_max : the clamp,
    Pa/m. The breakpoints of the normal law (:func:`normal_stress`), where its tangent stiffness
    reaches k_min (power law only) and k_max: stress_low, stress_high (Pa) and the closures
    there, closure_low, closure_high (m); closure_scale = (kn / stress_ref) s_low^(e - 1), 1/m,
    of the power law's inversion (:func:`normal_stress`).

    A separate type, so that the kernels are compiled for each kind of joint
    (:func:`normal_force`): a joint of constant stiffness runs exactly the arithmetic it always did.
    """

    kn: float
    ks: float
    friction: float
    cohesion: float
    tension: float
    law: int
    exponent_n: float = 0.0
    exponent_s: float = 0.0
    per_stress_n: float = 0.0
    per_stress_s: float = 0.0
    stress_ref: float = 1.0
    k_min: float = 0.0
    k_max: float = np.inf
    stress_low: float = 0.0
    closure_low: float = 0.0
    stress_high: float = np.inf
    closure_high: float = np.inf
    closure_scale: float = 0.0


def kernel_joint(joint: JointMaterial) -> JointConstants | StressJoint:
    """``joint`` for the kernels: :class:`JointConstants` when its stiffness is constant (a
    stress-dependent law whose exponents or slopes are all zero is that law exactly), else
    :class:`StressJoint` with its breakpoints."""
    base = (float(joint.kn), float(joint.ks), float(joint.friction), float(joint.cohesion), float(joint.tension))
    if not joint.stress_dependent:
        return JointConstants(*base)
    value = joint.law_value
    clamp = dict(k_min=float(value("kn_min")), k_max=float(value("kn_max")))
    if joint.model == "affine":
        law = StressJoint(*base, law=AFFINE, per_stress_n=float(joint.kn_per_stress), per_stress_s=float(value("ks_per_stress")), **clamp)
    else:
        law = StressJoint(*base, law=POWER, exponent_n=float(joint.kn_exponent), exponent_s=float(value("ks_exponent")),
                          stress_ref=float(joint.stress_ref), **clamp)
    return _with_breakpoints(law)


def _with_breakpoints(joint: StressJoint) -> StressJoint:
    """``joint`` with the stresses and closures where its normal tangent stiffness reaches
    k_min and k_max (:func:`normal_stress`)."""
    if joint.law == AFFINE:
        a = joint.per_stress_n
        if a == 0.0:
            return joint
        high = (joint.k_max - joint.kn) / a
        return joint._replace(stress_high=high, closure_high=np.log(joint.k_max / joint.kn) / a)
    e = joint.exponent_n
    if e == 0.0:
        return joint
    low = joint.stress_ref * (joint.k_min / joint.kn) ** (1.0 / e)
    high = joint.stress_ref * (joint.k_max / joint.kn) ** (1.0 / e)
    joint = joint._replace(stress_low=low, closure_low=low / joint.k_min, stress_high=high,
                           closure_scale=joint.kn / joint.stress_ref * (low / joint.stress_ref) ** (e - 1.0))
    return joint._replace(closure_high=joint.closure_low + _power_closure(high, joint))


def _power_closure(stress, joint):
    """u(sigma) - u(sigma_low) of the power law's middle part: (sigma_ref / k) (s^(1-e) -
    s_low^(1-e)) / (1 - e) with s = sigma / sigma_ref (ln(s / s_low) for e = 1), in the form
    that stays exact as e -> 1."""
    e = joint.exponent_n
    s_low = joint.stress_low / joint.stress_ref
    log_ratio = np.log(stress / joint.stress_low)
    growth = log_ratio if e == 1.0 else np.expm1((1.0 - e) * log_ratio) / (1.0 - e)
    return joint.stress_ref / joint.kn * s_low ** (1.0 - e) * growth


@numba.njit(cache=True, inline="always")
def tangent_stiffness(stress, k, exponent, per_stress, joint):
    """The law's stiffness at normal stress ``stress`` (Pa; below 0 taken as 0), Pa/m, for the
    value ``k`` and ``exponent`` (power) or ``per_stress`` (affine) of kn or ks, clamped to
    [k_min, k_max]."""
    sigma = max(stress, 0.0)
    if joint.law == AFFINE:
        value = k + per_stress * sigma
    elif exponent == 1.0:  # the linear law (joint-closure tests' kn proportional to sigma), without pow
        value = k * sigma / joint.stress_ref
    else:
        value = k * (sigma / joint.stress_ref) ** exponent
    return min(max(value, joint.k_min), joint.k_max)


@numba.njit(cache=True, inline="always")
def normal_stiffness(stress, joint):
    """kn(sigma), Pa/m (:func:`tangent_stiffness`)."""
    return tangent_stiffness(stress, joint.kn, joint.exponent_n, joint.per_stress_n, joint)


@numba.njit(cache=True, inline="always")
def shear_stiffness(stress, joint):
    """ks(sigma), Pa/m (:func:`tangent_stiffness`)."""
    return tangent_stiffness(stress, joint.ks, joint.exponent_s, joint.per_stress_s, joint)


@numba.njit(cache=True, inline="always")
def normal_stress(closure, joint):
    """sigma(u_n), Pa, of a stress-dependent law: d sigma = kn(sigma) d u_n integrated exactly.

    The law is non-linear elastic: unloading follows the loading curve back and re-loading it
    again, so sigma depends on the closure alone and the integral from the unloaded joint
    (u_n = 0, sigma = 0) is the exact value of every incremental path (an explicit increment
    kn(sigma) du would drift off the curve and create energy over load-unload cycles).
    Opening (u_n < 0, with a tensile strength): the stiffness at zero stress.

    affine, kn = k0 + a sigma (k0 = ``kn``, a = ``per_stress_n``):
        sigma = (k0 / a) (exp(a u) - 1), up to closure_high = ln(k_max / k0) / a;
        so a block of weight W on area A settles by u = ln(1 + a W / (k0 A)) / a.
    power, kn = k (sigma / sigma_ref)^e (k = ``kn``), clamped: sigma = k_min u up to
        stress_low = sigma_ref (k_min / k)^(1/e); then u - u_low = integral of d sigma / kn =
        (sigma_ref / k) (s^(1-e) - s_low^(1-e)) / (1 - e), s = sigma / sigma_ref (ln(s / s_low) at
        e = 1), inverted below, up to stress_high = sigma_ref (k_max / k)^(1/e).
    Above closure_high: sigma_high + k_max (u - u_high). (The continuously yielding joint of
    Itasca 3DEC has the power form kn = a_n sigma^e_n; the affine one is the linear fit of
    joint-closure tests, kn = 17.52 sigma per mm in Savalle et al. 2022, Section 4.3.)
    """
    if closure <= 0.0:
        return normal_stiffness(0.0, joint) * closure
    if closure >= joint.closure_high:
        return joint.stress_high + joint.k_max * (closure - joint.closure_high)
    if joint.exponent_n == 0.0 and joint.per_stress_n == 0.0:  # only ks depends on the stress
        return joint.kn * closure
    if joint.law == AFFINE:
        a = joint.per_stress_n
        return joint.kn / a * np.expm1(a * closure)
    if closure <= joint.closure_low:
        return joint.k_min * closure
    e = joint.exponent_n
    # s^(1-e) = s_low^(1-e) + (1 - e) x, x = (u - u_low) k / sigma_ref; s = s_low exp(y) with
    # y = ln(1 + (1 - e) t) / (1 - e), t = x s_low^(e-1) (= x at e = 1)
    t = (closure - joint.closure_low) * joint.closure_scale
    y = t if e == 1.0 else np.log1p((1.0 - e) * t) / (1.0 - e)
    return joint.stress_low * np.exp(y)


@numba.njit(cache=True)
def normal_closures(stress, joint):
    """u(sigma), m, of each stress (n,) Pa >= 0 of a :class:`StressJoint`: the inverse of
    :func:`normal_stress` (the integral of d sigma / kn(sigma), piece by piece)."""
    out = np.empty_like(stress)
    for i in range(stress.shape[0]):
        sigma = stress[i]
        if joint.exponent_n == 0.0 and joint.per_stress_n == 0.0:
            out[i] = sigma / joint.kn
        elif sigma >= joint.stress_high:
            out[i] = joint.closure_high + (sigma - joint.stress_high) / joint.k_max
        elif joint.law == AFFINE:
            out[i] = np.log1p(joint.per_stress_n * sigma / joint.kn) / joint.per_stress_n
        elif sigma <= joint.stress_low:
            out[i] = sigma / joint.k_min
        else:
            e, log_ratio = joint.exponent_n, np.log(sigma / joint.stress_low)
            growth = log_ratio if e == 1.0 else np.expm1((1.0 - e) * log_ratio) / (1.0 - e)
            out[i] = joint.closure_low + growth / joint.closure_scale
    return out


#: a stress-dependent joint's timestep is renewed once a sub-contact's closure, plus this many
#: times what its closing speed adds in one cycle, passes the closure its timestep holds to
CLOSING_CYCLES = 2.0


@numba.njit(cache=True, inline="always")
def _never_stiffer(closure, normal_velocity, dt, closure_limit, s, joint):
    return False


@numba.njit(cache=True, inline="always")
def _closes_past_limit(closure, normal_velocity, dt, closure_limit, s, joint):
    return closure - CLOSING_CYCLES * min(normal_velocity, 0.0) * dt > closure_limit[s]


def stiffer_than_timestep(closure, normal_velocity, dt, closure_limit, s, joint):
    """Whether sub-contact ``s`` (closure m, normal relative velocity m/s, > 0 opening) is about
    to close past ``closure_limit[s]`` (m, :func:`drydem.engine.inertia.stiffness_bound`): its
    closure in CLOSING_CYCLES cycles at its current speed; so the timestep is renewed before the
    stiffness outgrows it, however fast the joint closes. Never for a joint of constant
    stiffness (compiled away by type, as :func:`normal_force`)."""
    return (_closes_past_limit if _is_stress_joint(joint) else _never_stiffer)(closure, normal_velocity, dt, closure_limit, s, joint)


@overload(stiffer_than_timestep, inline="always")
def _stiffer_by_type(closure, normal_velocity, dt, closure_limit, s, joint):
    chosen = _closes_past_limit if _is_stress_joint(joint) else _never_stiffer
    return lambda closure, normal_velocity, dt, closure_limit, s, joint: chosen(closure, normal_velocity, dt, closure_limit, s, joint)


@numba.njit(cache=True, inline="always")
def _linear_normal_force(closure, area, joint):
    return joint.kn * area * closure


@numba.njit(cache=True, inline="always")
def _law_normal_force(closure, area, joint):
    return normal_stress(closure, joint) * area


@numba.njit(cache=True, inline="always")
def _linear_shear_scale(fn, area, joint):
    return joint.ks * area


@numba.njit(cache=True, inline="always")
def _law_shear_scale(fn, area, joint):
    return shear_stiffness(fn / area, joint) * area


def _is_stress_joint(joint) -> bool:
    """Whether ``joint`` (a value, or its numba type when compiling) is a :class:`StressJoint`."""
    return isinstance(joint, StressJoint) or getattr(joint, "instance_class", None) is StressJoint


def _by_joint_type(constant, stress_dependent):
    """A function of (x, area, joint) that runs ``constant`` for a :class:`JointConstants` and
    ``stress_dependent`` for a :class:`StressJoint`: chosen by the joint's class from Python, by
    its numba type when compiled (an overload), so that a constant joint's kernels are compiled
    without the law, their arithmetic as it always was."""
    def chosen(joint):
        return stress_dependent if _is_stress_joint(joint) else constant

    def function(x, area, joint):
        return chosen(joint)(x, area, joint)

    @overload(function, inline="always")
    def _compiled(x, area, joint):
        implementation = chosen(joint)
        return lambda x, area, joint: implementation(x, area, joint)

    return function


#: F_n, N, of a sub-contact of area ``area`` (m2) closed by ``closure`` (m): kn A u_n, or
#: sigma(u_n) A for a :class:`StressJoint` (``normal_force(closure, area, joint)``)
normal_force = _by_joint_type(_linear_normal_force, _law_normal_force)
#: ks A, N/m, of a sub-contact carrying ``fn`` (N): ks(F_n / A) for a :class:`StressJoint`, the
#: tangent at its normal stress (``shear_scale(fn, area, joint)``)
shear_scale = _by_joint_type(_linear_shear_scale, _law_shear_scale)


#: an opening of an intact sub-contact up to this many times the magnitude of the coordinates
#: its closure is computed from (:func:`touch_slack`) is their round-off, not a failure in
#: tension (found by a hunt: blocks drawn touching computed closures of -1e-17 m in their first
#: cycle, and a joint with cohesion and T = 0 lost its cohesion everywhere before it was loaded)
TOUCH_ROUND_OFF = 16.0 * np.finfo(np.float64).eps


@numba.njit(cache=True, inline="always")
def touch_slack(dx, dy, dz, offset):
    """m: the round-off of a closure computed from the centroids' separation (dx, dy, dz), m,
    and the contact's offset, m (:data:`TOUCH_ROUND_OFF`)."""
    return TOUCH_ROUND_OFF * (abs(dx) + abs(dy) + abs(dz) + abs(offset))


@numba.njit(cache=True, inline="always")
def normal_law(closure, area, intact, joint, slack):
    """(F_n, carries): the normal force (:func:`normal_force`) and whether the sub-contact
    carries load at all.

    It does not once opened beyond its tensile strength (any opening when T = 0 or failed);
    then F_n = F_s = 0 and the sub-contact has failed. An intact bond (a joint with cohesion or
    tension) opened by no more than ``slack`` (m, :func:`touch_slack`) is touching, at -T A."""
    fn = normal_force(closure, area, joint)
    if fn >= -(joint.tension * area if intact else 0.0):
        return fn, True
    bonded = intact and (joint.cohesion > 0.0 or joint.tension > 0.0)
    return -joint.tension * area, bonded and closure >= -slack


@numba.njit(cache=True, inline="always")
def shear_law(fn, dus_x, dus_y, dus_z, fs_x, fs_y, fs_z, area, intact, joint):
    """New (F_s x, F_s y, F_s z, intact) of a loaded sub-contact; see module docstring. The shear
    stiffness is that of :func:`shear_scale` (for a stress-dependent law, the tangent at the
    current normal stress: the shear force is incremental).

    ``fs_*`` is the previous shear force already rotated into the current tangent plane."""
    scale = shear_scale(fn, area, joint)
    fs_x -= scale * dus_x
    fs_y -= scale * dus_y
    fs_z -= scale * dus_z
    limit = max((joint.cohesion * area if intact else 0.0) + joint.friction * fn, 0.0)
    magnitude_sq = fs_x * fs_x + fs_y * fs_y + fs_z * fs_z
    if magnitude_sq > limit * limit:
        scale = limit / np.sqrt(magnitude_sq)
        return fs_x * scale, fs_y * scale, fs_z * scale, False
    return fs_x, fs_y, fs_z, intact


@numba.njit(cache=True)
def normal_energies(closure, joint):
    """The elastic energy per area w(u) = int_0^u sigma du' (J/m2) of each closure (n,) m of a
    :class:`StressJoint`, in closed form: w = int_0^sigma s ds / kn(s) piece by piece, with
    sigma = sigma(u) (:func:`normal_stress`):

        clamp at k:  (sigma_b^2 - sigma_a^2) / (2 k)
        power:       (sigma_ref^2 / k) (s^(2-e) - s_low^(2-e)) / (2 - e)   (ln(s / s_low) at e = 2)
        affine:      (k0 / a^2) (x - ln(1 + x)), x = a sigma / k0          (its series for small x)

    Opening (u < 0): the stiffness at zero stress, kn(0) u^2 / 2."""
    out = np.empty_like(closure)
    for i in range(closure.shape[0]):
        u = closure[i]
        sigma = normal_stress(u, joint)
        if u <= 0.0 or (joint.exponent_n == 0.0 and joint.per_stress_n == 0.0):
            out[i] = 0.5 * sigma * u
        elif u >= joint.closure_high:
            high = joint.stress_high
            out[i] = _law_energy(high, joint) + (sigma * sigma - high * high) / (2.0 * joint.k_max)
        else:
            out[i] = _law_energy(sigma, joint)
    return out


@numba.njit(cache=True, inline="always")
def _law_energy(sigma, joint):
    """int_0^sigma s ds / kn(s), J/m2, below stress_high (see :func:`normal_energies`)."""
    if joint.law == AFFINE:
        x = joint.per_stress_n * sigma / joint.kn
        # x - ln(1 + x), by its series where the subtraction would cancel
        rest = x * x * (0.5 - x * (1.0 / 3.0 - x * (0.25 - x * (0.2 - x / 6.0)))) if x < 1e-3 else x - np.log1p(x)
        return joint.kn / joint.per_stress_n ** 2 * rest
    low = joint.stress_low
    if sigma <= low:
        return sigma * sigma / (2.0 * joint.k_min)
    e, s_low = joint.exponent_n, low / joint.stress_ref
    log_ratio = np.log(sigma / low)
    growth = log_ratio if e == 2.0 else np.expm1((2.0 - e) * log_ratio) / (2.0 - e)
    return low * low / (2.0 * joint.k_min) + joint.stress_ref ** 2 / joint.kn * s_low ** (2.0 - e) * growth


compiled_cache.check(__name__)  # last: none of the functions above is loaded from a stale cache
