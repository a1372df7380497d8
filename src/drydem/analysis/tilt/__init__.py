"""Tilting-table analysis and pushover by a load multiplier (Savalle et al. 2022, Section 3).

Stage 1: vertical gravity in one step, cycled to equilibrium. Stage 2: the tilt theta
grows by ``increment_deg`` and gravity becomes

    tilt:        g (sin theta, 0, -cos theta)        (paper Eq. 5)
    multiplier:  g (lambda, 0, -1), lambda = tan theta   (classic pushover, the same statics
                 direction; theta = atan(lambda) is its tilt equivalent)

with the table turning about y (``tilt_axis`` "y", the default); about x (``tilt_axis`` "x")
the lateral component acts along y instead, g (0, sin theta, -cos theta) or g (0, lambda, -1),
loading out of their plane the walls that run along x (a 3D model's: an in-plane one cannot
move in y). The monitored displacement ("ux"), the drift and the stop displacement are
measured along the load direction.

cycling to equilibrium at each step, until the monitored point has moved
``stop_displacement_m`` horizontally, the monitored block has fallen out of the model (below,
a part of the wall that collapses onto the rubble of another may come to rest within the
stop displacement), or equilibrium cannot be reached within the solver's ``max_cycles``, or
the step's integration blows up (:class:`~drydem.errors.DivergenceError`; an adaptive coarse
step is undone and halved, as a failed one): the last two are no verdict, and the equilibria
found before are reported. The collapse angle is the largest tilt at which the model was in equilibrium.

Predictor: each step starts from the trend of the last two equilibria, extrapolated to the new
tilt and applied as one cycle's rigid motion (:meth:`~drydem.engine.simulation.Simulation.move`; the joints
follow it as in any cycle), so that dynamic relaxation only has the step's non-linearity left to
remove: about half the cycles on the competition walls. Only an elastic trend is extrapolated:
a slip or a local failure is not recovered when the load grows (friction keeps what it is
given), so extrapolating one would ratchet it on. The step after one whose motion per degree
grew more than ``predictor_growth`` times over the step before starts without a prediction,
and every move of a block point is capped at ``predictor_cap_closures`` elastic closures: the
median over the blocks of m g / sum(k A), what a block's own weight closes its joints by (the
contacts as drawn). The cap thus follows the joint stiffness: a soft wall moves far and
elastically at every step, a stiff one little, but as much as a soft one once it slips. The default, 150, is
about one contact tolerance at kn = 3e7 Pa/m on the competition walls and 1/30 of one at 1e9
(a cap of one tolerance there extrapolated a slip of WD1 into a local failure at 22.4 deg,
against 26.3 without the predictor).

Adaptive protocol: steps of ``increment_deg * 2**refinements``; a step that fails is undone
(the last equilibrium is restored, shear history included) and halved, down to
``increment_deg``; so the collapse angle is found to within one increment, as with fixed steps.
A coarse step is judged failed early, once its motion is clearly not elastic
(:func:`~drydem.analysis.tilt.run.trial_limit`): only steps of one increment are followed to
the stop criteria.

Blocks that fall out of the model (a rigid-body drop of more than ``lost_drop_heights`` of
their own heights: the centroid's drop below where it was drawn, less the settlement the
joints' elastic closure explains, :mod:`drydem.analysis.support`; e.g. a brick sliding out of a course)
are taken out of the analysis and reported, so that a local failure does not hide the global
collapse. A tall or soft wall's elastic settlement is not a fall.

Stage 1 ends in one of three ways: equilibrium; a fall (a block falls or the monitored point
moves ``stop_displacement_m``: the model cannot stand under its own weight, and the blocks that
fell are named); or no equilibrium within the solver's ``max_cycles``, which is no verdict on
stability (``stable_under_gravity`` is then None) and is reported as such.

The package, module by module: :mod:`~drydem.analysis.tilt.settings` (the settings, the
outcomes, the records and result), :mod:`~drydem.analysis.tilt.run` (one analysis as it
cycles: a step to equilibrium, the predictor, the blocks that fall out),
:mod:`~drydem.analysis.tilt.protocol` (the stages, and :func:`tilt_analysis`) and
:mod:`~drydem.analysis.tilt.checkpointing` (save and resume).
"""

from drydem.analysis.tilt.protocol import (
    CHECKPOINT_EVERY, CHECKPOINT_EVERY_S, FRAME_SAMPLING, TiltProtocol, replay_collapse, stand_under_gravity, step_up, tilt_analysis,
    tilt_result,
)
from drydem.analysis.tilt.run import TiltRun, Trace, elastic_closure, trial_limit
from drydem.analysis.tilt.settings import (
    DIVERGED, EQUILIBRIUM, FELL, GAVE_UP, LOADINGS, MAX_CYCLES, MAXIMUM_ANGLE, MONITOR_FELL, MONITOR_TOPPLED, NO_EQUILIBRIUM,
    NO_EQUILIBRIUM_UNDER_GRAVITY, SETTING_RANGES, STOP_DISPLACEMENT, TILT_AXES, TOPPLED_RAD, UNSTABLE_UNDER_GRAVITY, Frame, Record,
    TiltResult, TiltSettings, check_loading, check_stop_displacement, monitor_index, monitored_block, wall_height,
)

__all__ = [
    "CHECKPOINT_EVERY", "CHECKPOINT_EVERY_S", "DIVERGED", "EQUILIBRIUM", "FELL", "FRAME_SAMPLING", "GAVE_UP", "LOADINGS",
    "MAX_CYCLES", "MAXIMUM_ANGLE", "MONITOR_FELL", "MONITOR_TOPPLED",
    "NO_EQUILIBRIUM", "NO_EQUILIBRIUM_UNDER_GRAVITY", "SETTING_RANGES", "STOP_DISPLACEMENT", "TILT_AXES", "TOPPLED_RAD",
    "UNSTABLE_UNDER_GRAVITY",
    "Frame", "Record", "TiltProtocol", "TiltResult", "TiltRun", "TiltSettings", "Trace", "check_loading", "check_stop_displacement",
    "elastic_closure", "monitor_index",
    "monitored_block", "replay_collapse", "stand_under_gravity", "step_up", "tilt_analysis", "tilt_result", "trial_limit",
    "wall_height",
]
