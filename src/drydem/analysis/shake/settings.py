"""What a shaking-table analysis is given and gives back: :class:`ShakeSettings` (checked
against :data:`SETTING_RULES`), the outcome names, the response history (:class:`History`),
the frames it shows (:class:`ShakeFrame`) and :class:`ShakeResult`."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from drydem.analysis.shake.motion import MAX_DURATION_S, GroundMotion
from drydem.engine.contacts import SubContacts
from drydem.engine.damping import VISCOUS_RULES
from drydem.errors import ModelError
from drydem.model.parameters import LOST_DROP_HEIGHTS, Range, check_fields
from drydem.model.state import State

#: why an analysis ended (ShakeResult.ended_by)
DURATION, MONITOR_FELL = "duration", "monitored block fell"
#: the named restitution: Housner's rigid-block value for the monitored block
HOUSNER = "housner"
#: the contacts' damping ratio when neither it nor a restitution is given: about what gives
#: Housner's r to a slender block on stiff joints (0.58 for 2b x 2h = 0.2 x 0.8 m at kn = 1e9 Pa/m)
DEFAULT_CONTACT_DAMPING_RATIO = 0.5

#: the allowed values of ShakeSettings' numbers
SETTING_RULES = {
    "duration_s": Range(0.0, MAX_DURATION_S, low_open=True, unit="s"),
    "output_interval_s": Range(0.0, 1e3, low_open=True, unit="s"),
    "contact_damping_ratio": VISCOUS_RULES["contact_ratio"],
    "rayleigh_mass_per_s": VISCOUS_RULES["mass_proportional"],
    "rayleigh_stiffness_s": VISCOUS_RULES["stiffness_proportional"],
    "fall_rotation_deg": Range(0.0, 180.0, low_open=True, high_open=True, unit="deg"),
    "lost_drop_heights": LOST_DROP_HEIGHTS,
}
#: a coefficient of restitution of rocking impacts (angular-velocity ratio): 0 < r <= 1
RESTITUTION = Range(0.0, 1.0, low_open=True)


@dataclass(frozen=True, kw_only=True)
class ShakeSettings:
    """A time history on a shaking table (CLI options of ``drydem shake``).

    motion : the table's acceleration (:class:`~drydem.analysis.shake.motion.GroundMotion`).
    duration_s : analysed time, s (default: the record's; longer follows the free motion
    after it). output_interval_s : one row of the history every this many seconds.
    restitution : target coefficient of restitution of the monitored block's rocking impacts
    (angular velocity after / before), a number in (0, 1] or "housner" (1 - 1.5 sin^2 alpha),
    from which the contacts' damping ratio is calibrated
    (:mod:`drydem.analysis.shake.restitution`: it needs a block that rocks, alpha < 54.7 deg
    for Housner's r > 0); or contact_damping_ratio : zeta, set directly
    (:mod:`drydem.engine.damping`). Neither given: zeta = DEFAULT_CONTACT_DAMPING_RATIO (the
    monitored block of a brick wall is a squat brick, which does not rock on its own: its
    restitution cannot be calibrated). rayleigh_mass_per_s (1/s),
    rayleigh_stiffness_s (s) : Rayleigh damping C = alpha_R M + beta K.
    monitor : block name (default: the top block nearest the middle). fall_rotation_deg : a
    block turned more than this has overturned. lost_drop_heights : a block whose centroid
    dropped more than this many of its heights (beyond its joints' elastic settlement) fell out
    of the model (as in the tilting analysis) and is taken out.
    """

    motion: GroundMotion
    duration_s: float | None = None
    output_interval_s: float = 0.005
    restitution: float | str | None = None
    contact_damping_ratio: float | None = None
    rayleigh_mass_per_s: float = 0.0
    rayleigh_stiffness_s: float = 0.0
    monitor: str | None = None
    fall_rotation_deg: float = 80.0
    lost_drop_heights: float = 2.0

    def __post_init__(self):
        if not isinstance(self.motion, GroundMotion):
            raise ModelError(f"shake setting motion = {self.motion!r}: must be a GroundMotion (a record or a pulse)")
        check_fields(self, SETTING_RULES, "shake setting", optional=("duration_s", "contact_damping_ratio"))
        if self.monitor is not None and not isinstance(self.monitor, str):
            raise ModelError(f"shake setting monitor = {self.monitor!r}: must be a block name")
        if self.restitution is not None:
            if self.contact_damping_ratio is not None:
                raise ModelError("shake settings restitution and contact_damping_ratio both set: the ratio is calibrated "
                                 "from the restitution, give one of them")
            if not (isinstance(self.restitution, str) and self.restitution == HOUSNER):  # an array's != has no truth value
                RESTITUTION.check(self.restitution, f"shake setting restitution (or {HOUSNER!r})")

    @property
    def analysed_s(self) -> float:
        """The analysed time, s."""
        return self.motion.duration_s if self.duration_s is None else self.duration_s

    @property
    def damping_ratio(self) -> float | None:
        """The contacts' damping ratio unless it is to be calibrated (None)."""
        if self.restitution is not None:
            return None
        return DEFAULT_CONTACT_DAMPING_RATIO if self.contact_damping_ratio is None else self.contact_damping_ratio


@dataclass(frozen=True)
class History:
    """The response, one row per output interval: time (s), the table's acceleration (m/s2,
    (n, 3)), the monitored block's displacement relative to the table from where it rested
    before the shaking (ux, uy, uz, m) and its rotation across the motion's main direction
    (:attr:`~drydem.analysis.shake.motion.GroundMotion.main_direction`), rad: about y for a
    motion mainly along x (positive when its top moves toward +x: the right-hand rule about
    +y), about x for one mainly along y (positive when its top moves toward +y: about -x).
    Found by a hunt: it was about y whatever the motion, 1e-17 rad for a block rocking about x
    until it overturned. ``rotation_about``: "y", or "-x" for a motion mainly along y."""

    time_s: np.ndarray
    ground_acceleration_m_s2: np.ndarray
    ux_m: np.ndarray
    uy_m: np.ndarray
    uz_m: np.ndarray
    rotation_rad: np.ndarray
    rotation_about: str = "y"


@dataclass(frozen=True)
class ShakeFrame:
    """A state to show, and the history's row of it: model time (s), the table's acceleration
    ((3,) m/s2), the monitored block's displacement ((3,) m) and rotation across the motion
    (rad) as in :class:`History`, the blocks' State, their sub-contacts and the blocks still in the analysis."""

    time_s: float
    ground_acceleration_m_s2: np.ndarray
    displacement_m: np.ndarray
    rotation_rad: float
    state: State = field(repr=False)
    contacts: SubContacts = field(repr=False)
    active: np.ndarray = field(repr=False)

    @property
    def ux_m(self) -> float:
        return float(self.displacement_m[0])


@dataclass
class ShakeResult:
    """Outcome of :func:`~drydem.analysis.shake.shake_analysis`.

    overturned : a block fell: the monitored one, or any other, by either rule of
    :class:`ShakeSettings` (``fallen_blocks`` names each, with the time and the rule).
    max_rotation_rad : the largest angle the monitored block turned from rest over the history,
    about any axis (at least the largest |rotation_rad| of :class:`History`, which is the part
    across the motion; it reaches the fall rule's angle when the block overturned).
    max_displacement_m : its largest horizontal displacement relative to the table over the
    history; residual_displacement_m :
    its horizontal displacement at the end. contact_damping_ratio : zeta used (given or
    calibrated to ``restitution``, the target, None when zeta was given). timestep_s : of the
    dynamic stage at its start. ended_by : DURATION or MONITOR_FELL (the analysis stops there).
    """

    settings: ShakeSettings
    monitored_block: str
    overturned: bool
    fallen_blocks: list[tuple[str, float, str]]
    max_rotation_rad: float
    max_displacement_m: float
    residual_displacement_m: float
    duration_s: float
    cycles: int
    runtime_s: float
    contact_damping_ratio: float
    restitution: float | None
    timestep_s: float
    ended_by: str
    history: History = field(repr=False)
    final_state: State = field(repr=False)

    @property
    def pga_m_s2(self) -> float:
        return self.settings.motion.pga_m_s2

    def to_dataframe(self):
        """The response history as a pandas DataFrame
        (:func:`~drydem.analysis.dataframes.data_frame`), one row per output interval
        (:class:`History`): ``time_s``, the table's acceleration ``ground_acc_x_m_s2``,
        ``ground_acc_y_m_s2``, ``ground_acc_z_m_s2``, the monitored block's ``ux_m``, ``uy_m``,
        ``uz_m`` and ``rotation_rad``; ``attrs``: the outcome (``overturned``, ``fallen_blocks``
        as (block, time_s, rule), ``max_rotation_rad``, ``max_displacement_m``,
        ``residual_displacement_m``, ``pga_m_s2``, ``ended_by``, ``monitored_block``,
        ``contact_damping_ratio``, ``restitution``, ``duration_s``) and the ``motion``'s name."""
        from drydem.analysis.dataframes import data_frame

        h = self.history
        columns = {"time_s": h.time_s} | {f"ground_acc_{axis}_m_s2": h.ground_acceleration_m_s2[:, k] for k, axis in enumerate("xyz")}
        columns |= {"ux_m": h.ux_m, "uy_m": h.uy_m, "uz_m": h.uz_m, "rotation_rad": h.rotation_rad}
        outcome = ("overturned", "fallen_blocks", "max_rotation_rad", "max_displacement_m", "residual_displacement_m", "pga_m_s2",
                   "ended_by", "monitored_block", "contact_damping_ratio", "restitution", "duration_s")
        return data_frame(columns, {name: getattr(self, name) for name in outcome} | {"motion": self.settings.motion.name})
