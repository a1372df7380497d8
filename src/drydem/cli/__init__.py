"""The ``drydem`` command line: the click group :func:`main` (:mod:`drydem.cli.common`) and its
commands, one module per kind of work, each thin over the Python API: :mod:`~drydem.cli.models`
(check, show, export, designs), :mod:`~drydem.cli.tilting` (tilt, animate),
:mod:`~drydem.cli.shaking` (shake), :mod:`~drydem.cli.limits` (limit), :mod:`~drydem.cli.studies`
(sweep, report, calibrate) and :mod:`~drydem.cli.montecarlo` (montecarlo)."""

from drydem.cli import limits, models, montecarlo, shaking, studies, tilting
from drydem.cli.common import main
from drydem.cli.shaking import PULSE_KINDS

#: the modules whose import registers their commands on :func:`main`
COMMAND_MODULES = (models, tilting, shaking, limits, studies, montecarlo)

__all__ = ["COMMAND_MODULES", "PULSE_KINDS", "main"]
