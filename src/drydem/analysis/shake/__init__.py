"""Dynamic time-history analysis of a model on a shaking table (``drydem shake``).

The package, module by module: :mod:`~drydem.analysis.shake.motion` (the table's acceleration:
records, pulses, baseline correction, sampling per cycle), :mod:`~drydem.analysis.shake.settings`
(the settings, the history and the result), :mod:`~drydem.analysis.shake.restitution` (rocking
impacts: Housner's restitution and the contact damping that gives it) and
:mod:`~drydem.analysis.shake.run` (:func:`shake_analysis`).
"""

from drydem.analysis.shake.motion import PULSES, GroundMotion, pulse, read_motion
from drydem.analysis.shake.restitution import RockingBlock, calibrated_damping_ratio, housner_restitution
from drydem.analysis.shake.run import shake_analysis
from drydem.analysis.shake.settings import DURATION, HOUSNER, MONITOR_FELL, History, ShakeFrame, ShakeResult, ShakeSettings

__all__ = [
    "DURATION", "HOUSNER", "MONITOR_FELL", "PULSES", "GroundMotion", "History", "RockingBlock", "ShakeFrame", "ShakeResult",
    "ShakeSettings", "calibrated_damping_ratio", "housner_restitution", "pulse", "read_motion", "shake_analysis",
]
