"""The ground motion of ``drydem shake``: the shaking table's acceleration history.

A :class:`GroundMotion` is sampled at times ``time_s`` (s, strictly increasing from 0) with the
table's acceleration ``acceleration_m_s2`` (m/s2, x, y, z components). It comes from a file
(:func:`read_motion`: a CSV table, :func:`read_csv_motion`, or a PEER NGA ``.AT2`` record,
:func:`read_at2`) or from an analytic pulse (:func:`pulse`), and gives the explicit engine its
mean acceleration over each cycle (:meth:`GroundMotion.per_cycle`).

Every bad input is a :class:`~drydem.errors.ModelError` naming the file (and line) or the
parameter, and the rule it breaks.
"""

from __future__ import annotations

import csv
import functools
import math
import re
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from scipy.integrate import cumulative_trapezoid, trapezoid

from drydem.errors import ModelError
from drydem.files import PLAIN_NUMBER, read_text
from drydem.model.geometry import given, real_array
from drydem.model.parameters import (
    FILE_PATH, MAX_ACCELERATION_M_S2, TEXT, G, OneOf, Range, Rule, check_arguments, field_problems, is_number, refuse, shown,
)

#: the analytic pulses of :func:`pulse`
PULSES = ("one-sine", "sine", "ricker")
#: the table's axes, in the order of the acceleration's columns
DIRECTIONS = ("x", "y", "z")
#: the columns of a CSV motion: time, then the acceleration along each of DIRECTIONS
TIME_COLUMN = "time_s"
ACCELERATION_COLUMNS = ("acc_x_m_s2", "acc_y_m_s2", "acc_z_m_s2")
#: the suffixes :func:`read_motion` knows (lower case)
SUFFIXES = (".csv", ".at2")

#: any finite real: a negative scale factor or amplitude flips the motion
REAL = Range(None, None)
#: s: the least time between two samples of a record read from a file: 1 us, a sampling rate
#: of 1 MHz, is beyond any accelerometer or shaking-table controller (their rates are kHz);
#: closer times are no record (times like 1e-300 s leave the baseline's integrals, of order
#: a T^2, below the smallest float). A motion built in code may be finer (a step change
#: idealised as two samples 1e-9 s apart)
MIN_SAMPLE_STEP_S = 1e-6
#: s: the longest motion: the longest analysed time (ShakeSettings duration_s), 11.6 days
MAX_DURATION_S = 1e6
#: the least timesteps of the analysis in a pulse's period 1/f, or in a record's duration: the
#: same least sampling as a pulse's own (PULSE_RULES samples_per_period), below which a peak
#: is missed by more than 1 - cos(pi / 20) = 1.2 %
STEPS_PER_PERIOD = 20
#: a baseline correction's well-posedness, 1 - sum (dt_i / T)^3 (:meth:`GroundMotion.baseline_corrected`),
#: at least this: 0 with 2 samples (dependent conditions), 3/4 with 3 evenly spaced ones; its
#: coefficients grow as 1 / this, so below 1e-6 they would be a million times the record's peak
BASELINE_POSEDNESS = 1e-6
#: a baseline larger than this fraction of a record's peak acceleration gets a note
#: (:meth:`GroundMotion._baseline_note`): below it, it only removes a drift
BASELINE_NOTE_FRACTION = 0.01
#: m/s2: the least peak acceleration of a motion read or asked for on the command line, 1e-10 g,
#: far below any accelerometer's resolution (~1e-6 g); below it the table is at rest
MIN_PEAK_M_S2 = 1e-9
#: s: the explicit timestep, or a pulse's period
TIMESTEP = Range(0.0, None, low_open=True, unit="s")
#: a number of cycles whose accelerations are made at once: at most 1e7 (an array of 240 MB;
#: 10**12 was a MemoryError)
COUNT = Range(0, 10**7, integer=True)
#: s, a time in the analysis
START = Range(0.0, None, unit="s")

#: the rule of each argument of :func:`pulse`
PULSE_RULES = {
    "kind": OneOf(PULSES),
    "amplitude_m_s2": Range(None, None, unit="m/s2"),
    "frequency_hz": Range(0.0, None, low_open=True, unit="Hz"),
    # 1000 periods are a stationary test, no pulse; the bound keeps the record below 1e7 samples
    "cycles": Range(1, 1000, integer=True),
    "direction": OneOf(DIRECTIONS),
    # below 20 samples a period, linear interpolation between samples misses a peak by more
    # than 1 - cos(pi / 20) = 1.2 %; beyond 10,000 the miss (5e-8) is far below any record's
    "samples_per_period": Range(20, 10_000, integer=True),
}


class NonZero(Rule):
    """A finite number other than 0 (a negative one flips the motion): the scale factor or
    amplitude of a motion asked for on the command line (``drydem shake --scale``,
    ``--amplitude``), where 0 would be a table at rest, no shaking test at all. (In code a zero
    motion is allowed: a table at rest is a test of its own.)"""

    def __contains__(self, value) -> bool:
        return is_number(value) and value != 0

    def __str__(self) -> str:
        return "must be a finite number other than 0 (0 is a table at rest, no motion; a negative one flips the motion)"


#: the rule of a motion's factor asked for on the command line
NONZERO = NonZero()


class Notes(Rule):
    """A motion's notes: a tuple (or list) of texts, one a note (a text itself would be its
    characters, one a note)."""

    def __contains__(self, value) -> bool:
        return isinstance(value, (tuple, list)) and all(isinstance(note, str) for note in value)

    def __str__(self) -> str:
        return "must be a tuple of texts, one a note"


#: the rule of each field of :class:`GroundMotion` that says what it is (``source`` may be None)
DESCRIPTION_RULES = {"name": TEXT, "notes": Notes(), "source": TEXT}


@dataclass(frozen=True, eq=False)
class GroundMotion:
    """The shaking table's acceleration history.

    time_s : (n,) sample times, s: strictly increasing, from 0; n >= 2.
    acceleration_m_s2 : (n, 3) the table's acceleration at each sample, m/s2 (x, y, z).
    name : the file name or the pulse's description, for messages and reports.
    period_s : a pulse's period 1/f, s, which the analysis must resolve
    (:meth:`resolution_problem`); None for a record, whose content is not known.
    notes : what reading the motion changed, for the commands to print (a record shifted to
    start at 0).
    source : the file a record was read from, as given (its path), which messages name in
    place of the file name that begins ``name`` (:attr:`label`); None for a pulse or a motion
    made in code.

    Both arrays are stored as read-only float copies. Between samples the acceleration is
    linear; after the last one the table moves freely (zero acceleration).
    """

    time_s: np.ndarray
    acceleration_m_s2: np.ndarray
    name: str
    period_s: float | None = None
    notes: tuple[str, ...] = ()
    source: str | None = None

    def __post_init__(self):
        refuse(field_problems(self, DESCRIPTION_RULES, "GroundMotion {}".format, optional=("source",)))
        time, acceleration = real_array(self.time_s), real_array(self.acceleration_m_s2)
        for field, array in (("time_s", time), ("acceleration_m_s2", acceleration)):
            if array is None:
                raise ModelError(f"{self.label}: {field} must be an array of real numbers (no texts, booleans, complex numbers or masked "
                                 f"values), got {given(getattr(self, field))}")
        problem = _samples_problem(time, acceleration)
        if problem is not None:
            raise ModelError(f"{self.label}: {problem}")
        if self.period_s is not None:
            TIMESTEP.check(self.period_s, f"{self.label}: period_s")
        time.flags.writeable = acceleration.flags.writeable = False
        object.__setattr__(self, "time_s", time)
        object.__setattr__(self, "acceleration_m_s2", acceleration)
        object.__setattr__(self, "notes", tuple(self.notes))

    @property
    def label(self) -> str:
        """The motion as messages name it: its ``name``, with the file name it begins with given
        as the file's path (:attr:`source`: ``records/el-centro.csv, baseline-corrected``), as
        every message of reading the file names it."""
        if self.source is None or not self.name.startswith(Path(self.source).name):
            return self.name
        return self.source + self.name.removeprefix(Path(self.source).name)

    @property
    def duration_s(self) -> float:
        """The last sample's time, s."""
        return float(self.time_s[-1])

    @property
    def peaks_m_s2(self) -> tuple[float, float, float]:
        """The peak |acceleration| of each component (x, y, z), m/s2."""
        return tuple(float(peak) for peak in np.abs(self.acceleration_m_s2).max(axis=0))

    @property
    def main_direction(self) -> int:
        """The horizontal axis with the larger peak acceleration: 0 (x; also on a tie) or 1 (y)."""
        peak_x, peak_y, _ = self.peaks_m_s2
        return int(peak_y > peak_x)

    @property
    def pga_m_s2(self) -> float:
        """Peak horizontal acceleration, m/s2: max over the samples of sqrt(a_x^2 + a_y^2)."""
        return float(np.hypot(self.acceleration_m_s2[:, 0], self.acceleration_m_s2[:, 1]).max())

    @property
    def pga_g(self) -> float:
        """Peak horizontal acceleration in units of g (:data:`~drydem.model.parameters.G`)."""
        return self.pga_m_s2 / G

    def scaled(self, factor: float) -> GroundMotion:
        """The motion with every acceleration times ``factor`` (any finite real: 0 is a table at
        rest, a negative factor flips the motion)."""
        REAL.check(factor, f"{self.label}: scale factor")
        return replace(self, acceleration_m_s2=self.acceleration_m_s2 * factor, name=f"{self.name} x {factor:g}")

    def velocity_m_s(self) -> np.ndarray:
        """(n, 3) the table's velocity at each sample, m/s: v(t_i) = sum over j < i of
        (a_j + a_(j+1)) / 2 (t_(j+1) - t_j), from rest (the trapezoidal rule)."""
        return cumulative_trapezoid(self.acceleration_m_s2, self.time_s, axis=0, initial=0.0)

    def displacement_m(self) -> np.ndarray:
        """(n, 3) the table's displacement at each sample, m: the velocity
        (:meth:`velocity_m_s`) integrated in the same way, from 0."""
        return cumulative_trapezoid(self.velocity_m_s(), self.time_s, axis=0, initial=0.0)

    def baseline_corrected(self) -> GroundMotion:
        """The motion less a linear baseline that brings the table to rest at the record's end.

        Each component's acceleration becomes a(t) - (c0 + c1 t / T), T the duration, with c0
        and c1 the one solution of the two linear conditions that the table's final velocity and
        final displacement, integrated from the samples as :meth:`velocity_m_s` and
        :meth:`displacement_m` do, are both zero. A polynomial baseline fitted to the
        acceleration is the classic correction of strong-motion records; see Boore (2001),
        "Effect of baseline corrections on displacements and response spectra for several
        recordings of the 1999 Chi-Chi, Taiwan, earthquake", BSSA 91(5), 1199-1211, and Boore &
        Bommer (2005), "Processing of strong-motion accelerograms: needs, options and
        consequences", Soil Dyn. Earthq. Eng. 25, 93-115. Here the baseline is fixed by the end
        conditions instead of a least-squares fit, as for shaking-table drive signals, whose
        stroke must come back to its start.

        The conditions are solved in the time u = t / T: they are homogeneous, and the final
        velocity and displacement in u are those in t over T and T^2, so the coefficients are the
        same, and no record's time scale can leave them outside floating point's range. In u
        the conditions' matrix is [[1, 1/2], [1/2, 1/6 + q']] (the trapezoidal rule integrates
        the baseline's linear velocity exactly, and overestimates the displacement of its
        quadratic one by q' = sum (dt_i / T)^3 / 12), whose determinant is -q / 12 with
        q = 1 - sum (dt_i / T)^3: 0 for 2 samples (the conditions are then dependent), near 0 for
        a record that is one long step and a few short ones. A record whose q is below
        :data:`BASELINE_POSEDNESS` is refused: its baseline would be far larger than the record.

        The baseline shifts every sample, so the PGA changes, by at most the baseline's peak
        max(|c0|, |c0 + c1|): slightly for a record that nearly ends at rest. A record that
        already ends at rest (zero final velocity and displacement) has c0 = c1 = 0 and is left
        unchanged up to round-off. Needs 3 samples or more (with 2 the conditions are dependent).
        """
        if self.time_s.size < 3:
            raise ModelError(f"{self.label}: a baseline correction needs at least 3 samples; the record has {self.time_s.size}")
        u = self.time_s / self.duration_s
        posedness = 1.0 - float(np.sum(np.diff(u) ** 3))
        if posedness < BASELINE_POSEDNESS:
            longest = float(np.diff(u).max())
            raise ModelError(f"{self.label}: a baseline correction needs samples spread over the record: one step spans "
                             f"{longest:.9%} of it, which leaves the conditions of zero final velocity and displacement "
                             f"nearly dependent (1 - sum (dt / T)^3 = {posedness:.3g}, at least {BASELINE_POSEDNESS:g}); "
                             "resample the record, or do not correct it (--no-baseline)")
        basis = np.stack([np.ones_like(u), u], axis=1)
        coefficients = np.linalg.solve(_final_state(basis, u), _final_state(self.acceleration_m_s2, u))
        return replace(self, acceleration_m_s2=self.acceleration_m_s2 - basis @ coefficients,
                       name=f"{self.name}, baseline-corrected", notes=(*self.notes, *self._baseline_note(coefficients)))

    def _baseline_note(self, coefficients: np.ndarray) -> tuple[str, ...]:
        """A note if the baseline c0 + c1 t / T (``coefficients`` (2, 3), :meth:`baseline_corrected`)
        reaches more than :data:`BASELINE_NOTE_FRACTION` of the record's peak: then it changes
        the motion, not only its drift (found by a hunt: a one-sine pulse given as a record,
        whose table ends displaced by 0.2 m, got a baseline of 0.53 m/s2, 11 % of its PGA, which
        made the block's residual slip 34 times the pulse's); else none. The line is extreme at
        the record's ends: its peak is max(|c0|, |c0 + c1|)."""
        baseline = np.maximum(np.abs(coefficients[0]), np.abs(coefficients.sum(axis=0)))
        k = int(np.argmax(baseline))
        peak = float(np.abs(self.acceleration_m_s2).max())
        if baseline[k] <= BASELINE_NOTE_FRACTION * peak:
            return ()
        moved = float(self.displacement_m()[-1, k])
        return (f"{self.label}: the baseline correction shifts the {DIRECTIONS[k]} acceleration by up to {baseline[k]:.3g} m/s2, "
                f"{baseline[k] / peak:.1%} of the record's peak, to bring the table to rest where it started (the record moves "
                f"it {moved:.3g} m along {DIRECTIONS[k]}); if that displacement is genuine (a pulse, a fling step), "
                "give --no-baseline",)

    def resolution_problem(self, dt_s: float) -> str | None:
        """What keeps an analysis of timestep ``dt_s`` (s) from following the motion, or None.

        The table's acceleration is taken once a cycle (its mean over the cycle,
        :meth:`per_cycle`), so the shortest time the motion must be followed over, a pulse's
        period (:attr:`period_s`) or, for a record, its whole duration, must span at least
        :data:`STEPS_PER_PERIOD` timesteps; a pulse shorter than that is averaged over a
        cycle or two, and the response to it would be meaningless. (A record's content is not
        known: sampled finer than the timestep, its faster content is averaged out.)"""
        span, what = (self.period_s, "its period") if self.period_s is not None else (self.duration_s, "its duration")
        if span >= STEPS_PER_PERIOD * dt_s:
            return None
        advice = (f"give a frequency of at most {1.0 / (STEPS_PER_PERIOD * dt_s):.4g} Hz (--frequency; FREQUENCY_HZ of a study's pulse)"
                  if self.period_s is not None else f"give a record lasting at least {STEPS_PER_PERIOD * dt_s:.4g} s")
        return (f"{self.label}: {what}, {span:.4g} s, spans {span / dt_s:.3g} timesteps of {dt_s:.3g} s (the model's at the start "
                f"of the shaking); the analysis follows a motion only over at least {STEPS_PER_PERIOD} timesteps: {advice}")

    def aliasing_note(self, dt_s: float) -> str | None:
        """A note if a record is sampled finer than the timestep ``dt_s`` (s), else None: its
        content above half the cycle rate, 1 / (2 dt), cannot be followed. Each cycle takes the
        record's mean over its step (:meth:`per_cycle`), which keeps the table's velocity exact
        at the half steps; what is left of content at f > 1 / (2 dt) is aliased into slower
        motion at f_a, its acceleration weakened about f_a / f (found by a hunt: read at the
        cycles' times, a 5.45 kHz vibration of 6 m/s2 read every 1.8e-4 s became a 1 Hz motion
        of 6 m/s2, and moved a block 21 mm). A pulse is analytic and its period spans at least
        STEPS_PER_PERIOD timesteps (:meth:`resolution_problem`): None."""
        finest = float(np.diff(self.time_s).min())
        if self.period_s is not None or finest >= dt_s * (1.0 - 1e-6):  # a step of dt in times rounded off is not finer
            return None
        return (f"{self.label} is sampled every {finest:.3g} s at its finest, finer than the timestep, {dt_s:.3g} s: its content "
                f"above {0.5 / dt_s:.4g} Hz (half the cycle rate) is averaged over each cycle, and what is left of it is aliased into "
                "slower motion, weakened by the ratio of the frequencies; filter the record below that frequency if it has any")

    def acceleration_at(self, time_s: float) -> np.ndarray:
        """(3,) the table's acceleration at ``time_s`` (s, at least 0), m/s2: linear between
        samples (exact at the sample times), zero after the record's end."""
        check_arguments("acceleration_at", {"time_s": START}, time_s=time_s)
        return np.array([np.interp(time_s, self.time_s, component, right=0.0) for component in self.acceleration_m_s2.T])

    def per_cycle(self, dt_s: float, cycles: int, start_s: float = 0.0, first_step_s: float | None = None) -> np.ndarray:
        """(cycles, 3) the table's mean acceleration over each explicit cycle's velocity step, m/s2.

        Cycle k is at t_k = start_s + k dt_s; its central-difference update takes the velocity
        from t_k + dt/2 - s_k to t_k + dt/2, with s_k = dt_s (the first, s_0, is
        ``first_step_s`` where given: the step right after a change of timestep,
        :attr:`drydem.engine.simulation.Simulation.velocity_step_s`). Row k is the table's
        velocity change over that step divided by it,

            (v_g(t_k + dt/2) - v_g(t_k + dt/2 - s_k)) / s_k,

        with v_g the exact integral of the record (linear between samples, zero before 0 and
        after its end: :meth:`_velocity_change`). The engine's velocity update then adds the
        table's own velocity change exactly, so its relative velocities are exact at every half
        step, whatever the sampling, and a record sampled finer than the timestep is averaged
        over each step (a box filter) instead of read at the cycles' times: content faster than
        the cycles, which moves the table by little, is not aliased into slow motion of the
        same acceleration (found by a hunt: a 5.45 kHz vibration of 6 m/s2 read every 1.8e-4 s
        became a 1 Hz motion of 6 m/s2 and moved a block 21 mm). For a record sampled at dt or
        coarser the mean differs from the value at t_k only where a step spans a sample, by at
        most |s_i - s_(i-1)| dt / 8, s the record's slopes on either side of the sample.
        """
        check_arguments("per_cycle", {"dt_s": TIMESTEP, "cycles": COUNT, "start_s": START},
                        dt_s=dt_s, cycles=cycles, start_s=start_s)
        if first_step_s is not None:
            TIMESTEP.check(first_step_s, "per_cycle first_step_s")
        ends = start_s + (np.arange(cycles) + 0.5) * dt_s
        steps = np.full(cycles, dt_s)
        steps[:1] = dt_s if first_step_s is None else first_step_s
        return self._velocity_change(ends - steps, ends) / steps[:, None]

    @functools.cached_property
    def _velocity_at_samples(self) -> np.ndarray:
        """(n + 1, 3) 0, then the table's velocity at each sample (:meth:`velocity_m_s`), m/s."""
        return np.concatenate([np.zeros((1, 3)), self.velocity_m_s()])

    def _velocity_change(self, start_s: np.ndarray, end_s: np.ndarray) -> np.ndarray:
        """(n, 3) the table's velocity change from each ``start_s`` to each ``end_s`` (s), m/s.

        v_g(t) = V_i + a_i tau + (a_(i+1) - a_i) tau^2 / (2 h_i), tau = t - t_i within sample
        step i (t_i to t_(i+1), h_i long), V_i the trapezoidal integral up to t_i
        (:meth:`velocity_m_s`, exact for a linear acceleration); 0 before t = 0 and V_(n-1)
        after the end. The V_i and the parts within the steps are subtracted apart, so that a
        change within one step, where the V_i cancel exactly, keeps its digits whatever the
        velocity reached."""
        (start_whole, start_part), (end_whole, end_part) = self._velocity_parts(start_s), self._velocity_parts(end_s)
        return (end_whole - start_whole) + (end_part - start_part)

    def _velocity_parts(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The table's velocity at times ``t`` (s) as two (n, 3) parts, m/s: the integral up to
        the sample step each time falls in, and the integral within that step
        (:meth:`_velocity_change`)."""
        time, acceleration = self.time_s, self.acceleration_m_s2
        step = np.searchsorted(time, t, side="right") - 1  # -1 before the record, n - 1 after its end
        before = self._velocity_at_samples[step + 1]
        inside = (step >= 0) & (step < time.size - 1)
        i = np.clip(step, 0, time.size - 2)
        tau = np.where(inside, t - time[i], 0.0)[:, None]
        slope = (acceleration[i + 1] - acceleration[i]) / (time[i + 1] - time[i])[:, None]
        return before, acceleration[i] * tau + 0.5 * slope * tau * tau


def _final_state(acceleration: np.ndarray, time: np.ndarray) -> np.ndarray:
    """(2, k) the final velocity (row 0) and displacement (row 1) of each of the k columns of
    ``acceleration`` (n, k) sampled at ``time``, integrated as :meth:`GroundMotion.velocity_m_s`
    and :meth:`GroundMotion.displacement_m` do."""
    velocity = cumulative_trapezoid(acceleration, time, axis=0, initial=0.0)
    return np.stack([velocity[-1], trapezoid(velocity, time, axis=0)])


def _samples_problem(time: np.ndarray, acceleration: np.ndarray) -> str | None:
    """What is wrong with a motion's samples (the rules of :class:`GroundMotion`), or None."""
    if time.ndim != 1 or time.size < 2:
        return f"time_s must be a list of at least 2 times; got shape {time.shape}"
    if acceleration.shape != (time.size, 3):
        return f"acceleration_m_s2 must have shape ({time.size}, 3), one x, y, z row per time; got {acceleration.shape}"
    if not (np.isfinite(time).all() and np.isfinite(acceleration).all()):
        return "the times and accelerations must be finite numbers (no NaN or infinity)"
    if time[0] != 0.0:
        return f"time_s must start at 0 s; it starts at {time[0]:g} s"
    steps = np.diff(time)
    if (steps <= 0.0).any():
        i = int(np.argmax(steps <= 0.0)) + 1
        return f"time_s must increase strictly; sample {i} (t = {time[i]:g} s) is not after sample {i - 1} (t = {time[i - 1]:g} s)"
    if time[-1] > MAX_DURATION_S:
        return f"the motion lasts {time[-1]:g} s; at most {MAX_DURATION_S:g} s (the longest analysed time)"
    peak = np.abs(acceleration)
    if peak.max() > MAX_ACCELERATION_M_S2:
        i, k = np.unravel_index(int(np.argmax(peak)), peak.shape)
        return (f"the acceleration reaches {acceleration[i, k]:g} m/s2 ({'xyz'[k]} at t = {time[i]:g} s); at most "
                f"{MAX_ACCELERATION_M_S2:g} m/s2 in magnitude along each axis (about 100 g, past any earthquake record or shaking table)")
    return None


def _check_file(path: Path, kind: str) -> None:
    """A ModelError naming ``path`` if it is a folder or missing."""
    if path.is_dir():
        raise ModelError(f"{path}: is a folder, not a {kind} file")
    if not path.exists():
        raise ModelError(f"{path}: no such file")


def _read_text(path: Path, kind: str, encoding: str) -> str:
    """The text of ``path``; a ModelError naming it if it is missing, a folder or unreadable
    (:func:`~drydem.files.read_text`), or binary: a NUL byte, which Latin-1 decodes like any
    other (found by a hunt: a binary .AT2 was refused at "line 3: ''")."""
    _check_file(path, kind)
    text = read_text(path, f"a {kind} file is text", encoding=encoding)
    if (nul := text.find("\0")) >= 0:
        raise ModelError(f"{path}: not a text file (character {nul} is a NUL byte); a {kind} file is text")
    return text


def _number(text: str, where: str) -> float:
    """``text`` as a finite float; else a ModelError ``WHERE: 'TEXT' is not a (finite) number``:
    a number of a motion file is a plain decimal (:data:`drydem.files.PLAIN_NUMBER`: not 1_0, 0x10, 1.0D-3)."""
    if not PLAIN_NUMBER.fullmatch(text.strip()):
        raise ModelError(f"{where}: {shown(text.strip())} is not a number (a plain decimal such as 0.01, -2 or 1.5e-3)")
    value = float(text)
    if not math.isfinite(value):
        raise ModelError(f"{where}: {shown(text.strip())} is not a finite number")
    return value


def _moving(path: Path, acceleration: np.ndarray) -> np.ndarray:
    """``acceleration`` (n, 3), m/s2, read from the record ``path``; a ModelError naming the file
    if every value is below :data:`MIN_PEAK_M_S2` in magnitude: a table at rest, no motion (as
    ``drydem shake --scale 0`` is refused; found by a hunt: a record whose only value other than
    0 was 1e-320 ran)."""
    peak = float(np.abs(acceleration).max(initial=0.0))
    if peak < MIN_PEAK_M_S2:
        raise ModelError(f"{path}: every acceleration of the record is " + ("0" if peak == 0.0 else f"below {MIN_PEAK_M_S2:g} m/s2")
                         + ": a table at rest, no motion; a record must move the table")
    return acceleration


def _checked_times(path: Path, time: np.ndarray, lines: list[int]) -> tuple[np.ndarray, tuple[str, ...]]:
    """The times of a file's samples (read on ``lines``) shifted to start at 0, and a note
    saying so if they did not; a ModelError naming the file and line if one is negative, not
    after the one before, or closer to it than :data:`MIN_SAMPLE_STEP_S`, or if the record lasts
    longer than :data:`MAX_DURATION_S`."""
    if time[0] < 0.0:
        raise ModelError(f"{path}: line {lines[0]}: time_s = {time[0]:g}: times must be >= 0 s")
    steps = np.diff(time)
    late = np.flatnonzero(steps <= 0.0)
    if late.size:
        i = int(late[0]) + 1
        raise ModelError(f"{path}: line {lines[i]}: time_s = {time[i]:g} is not after {time[i - 1]:g} "
                         f"(line {lines[i - 1]}): times must increase strictly")
    close = np.flatnonzero(steps < MIN_SAMPLE_STEP_S - 4.0 * np.spacing(time[1:]))  # a 1 MHz record's steps round below 1e-6 s
    if close.size:
        i = int(close[0]) + 1
        raise ModelError(f"{path}: line {lines[i]}: time_s = {time[i]:.10g} is {steps[i - 1]:.3g} s after {time[i - 1]:.10g} "
                         f"(line {lines[i - 1]}): a record's samples must be at least {MIN_SAMPLE_STEP_S:g} s apart "
                         "(a sampling rate of at most 1 MHz)")
    if time[-1] - time[0] > MAX_DURATION_S:
        raise ModelError(f"{path}: line {lines[-1]}: time_s = {time[-1]:.10g}: the record lasts {time[-1] - time[0]:.4g} s; "
                         f"at most {MAX_DURATION_S:g} s (the longest analysed time)")
    shifted = () if time[0] == 0.0 else (f"{path}: the record starts at t = {time[0]:.10g} s; it was shifted by "
                                         f"{time[0]:.10g} s to start at 0",)
    return time - time[0], shifted


def read_csv_motion(path: str | Path) -> GroundMotion:
    """A motion from a CSV table: a header naming the columns ``time_s`` (s) and
    ``acc_x_m_s2`` (m/s2), and optionally ``acc_y_m_s2`` and ``acc_z_m_s2``, in any order
    (a missing one is zero); then one row of finite numbers per sample, at least 2, the times
    strictly increasing from 0 or later, at least :data:`MIN_SAMPLE_STEP_S` apart (a record
    starting at t0 > 0 is shifted to start at 0, and its ``notes`` say so). Blank lines are
    skipped. A ModelError names the file, the line and the rule broken."""
    path = Path(path)
    rows = csv.reader(_read_text(path, "CSV motion", "utf-8-sig").splitlines())
    cells = _csv_rows(path, rows)
    header = [name.strip() for name in next(cells, [])]
    present = _present_columns(path, header)
    samples, lines = [], []
    for row in cells:
        if not any(cell.strip() for cell in row):
            continue
        if len(row) != len(header):
            raise ModelError(f"{path}: line {rows.line_num}: {len(row)} values; the header has {len(header)} columns")
        samples.append([_number(row[header.index(name)], f"{path}: line {rows.line_num}: {name}") for name in present])
        lines.append(rows.line_num)
    if len(samples) < 2:
        raise ModelError(f"{path}: {len(samples)} rows of samples; a motion needs at least 2")
    table = np.array(samples)
    acceleration = np.zeros((len(samples), 3))
    for column, name in enumerate(present[1:], start=1):
        acceleration[:, ACCELERATION_COLUMNS.index(name)] = table[:, column]
    time, notes = _checked_times(path, table[:, 0], lines)
    return GroundMotion(time, _moving(path, acceleration), path.name, notes=notes, source=str(path))


def _csv_rows(path: Path, rows):
    """The rows of the csv.reader ``rows``; a ModelError naming the file and the line the csv
    module cannot read (a field longer than its limit, 131,072 characters)."""
    while True:
        try:
            row = next(rows)
        except StopIteration:
            return
        except csv.Error as exc:
            raise ModelError(f"{path}: line {rows.line_num}: not a CSV row ({exc}); a motion's rows hold one number a column") from None
        yield row


def _present_columns(path: Path, header: list[str]) -> list[str]:
    """The known columns ``header`` names, time first, then the accelerations along x, y, z;
    a ModelError naming the file if a column is missing, unknown or repeated."""
    expected = f"expected the columns {TIME_COLUMN}, {ACCELERATION_COLUMNS[0]} and optionally {', '.join(ACCELERATION_COLUMNS[1:])}"
    if not header:
        raise ModelError(f"{path}: empty: no header line; {expected}")
    known = (TIME_COLUMN, *ACCELERATION_COLUMNS)
    unknown = [name for name in header if name not in known]
    repeated = sorted({name for name in header if header.count(name) > 1})
    missing = [name for name in known[:2] if name not in header]
    for problem, names in (("unknown columns", unknown), ("repeated columns", repeated), ("missing columns", missing)):
        if names:
            raise ModelError(f"{path}: line 1: {problem} {', '.join(map(repr, names))}; {expected}")
    return [name for name in known if name in header]


#: line 4 of a PEER NGA .AT2 file: ``NPTS=  5590, DT=   .0050 SEC`` (NGA-West2) or
#: ``5590    0.0050    NPTS, DT`` (the older NGA files)
AT2_NPTS_DT = (re.compile(r"NPTS\s*=\s*(\S+?)\s*,?\s*DT\s*=\s*(\S+?)(?:\s*SECS?)?\s*,?\s*$", re.IGNORECASE),
               re.compile(r"^\s*(\S+)\s+(\S+)\s+NPTS\s*,\s*DT\b", re.IGNORECASE))
#: line 3 of a PEER NGA .AT2 file: ``ACCELERATION TIME SERIES IN UNITS OF G`` (or ``HISTORY``), G
#: ending the line (found by a hunt: ``UNITS OF G/100`` was read as g, a record 100 times too strong)
AT2_UNITS = re.compile(r"\bACCELERATION\b.*\bUNITS\s+OF\s+G\s*\.?\s*$", re.IGNORECASE)
#: the number of points, at least 2 (a motion's least)
NPTS = Range(2, None, integer=True)
#: s: an .AT2 record's time step DT, at least that of any record read from a file
AT2_DT = Range(MIN_SAMPLE_STEP_S, None, unit="s")


def read_at2(path: str | Path, direction: str = "x") -> GroundMotion:
    """A motion from a PEER NGA ``.AT2`` record, which drives the table along ``direction``
    ("x", "y" or "z"; the other components are zero).

    The file has 4 header lines: a title; the event, date, station and component; the units,
    ``ACCELERATION TIME SERIES IN UNITS OF G``; the number of points and the time step, s, as
    ``NPTS=  5590, DT=   .0050 SEC`` (NGA-West2; the commas optional) or as
    ``5590    0.0050    NPTS, DT`` (older files); DT at least :data:`MIN_SAMPLE_STEP_S`. Then
    the NPTS accelerations in g, several to a line, sampled every DT from t = 0; they are
    converted to m/s2 with g = 9.81 m/s2
    (:data:`~drydem.model.parameters.G`). A ModelError names the file, the line and the rule
    broken; the count of values must be NPTS (a truncated file is refused)."""
    path = Path(path)
    OneOf(DIRECTIONS).check(direction, f"{path}: direction")
    lines = _utf8_where_it_is(_read_text(path, "PEER .AT2", "latin-1")).splitlines()
    if len(lines) < 4:
        raise ModelError(f"{path}: {len(lines)} lines; a PEER .AT2 file has 4 header lines "
                         "(title; event and station; units; NPTS and DT), then the accelerations")
    if not AT2_UNITS.search(lines[2]):
        raise ModelError(f"{path}: line 3: {shown(lines[2].strip())}: expected 'ACCELERATION TIME SERIES IN UNITS OF G'")
    npts, dt_s = _at2_npts_dt(path, lines[3])
    values = [_number(text, f"{path}: line {number}") for number, line in enumerate(lines[4:], start=5) for text in line.split()]
    if len(values) != npts:
        raise ModelError(f"{path}: line 4 gives NPTS = {shown(npts)}, but the file holds {len(values)} values"
                         f"{' (truncated?)' if len(values) < npts else ''}")
    acceleration = np.zeros((npts, 3))
    acceleration[:, DIRECTIONS.index(direction)] = np.array(values) * G
    return GroundMotion(np.arange(npts) * dt_s, _moving(path, acceleration), path.name, source=str(path))


def _utf8_where_it_is(text: str) -> str:
    """``text``, read as Latin-1 (every byte a character: older records' station names), decoded
    again as UTF-8 where its bytes are UTF-8 (found by a hunt: a unicode minus in a record was
    shown as three Latin-1 characters)."""
    try:
        return text.encode("latin-1").decode("utf-8")
    except UnicodeDecodeError:
        return text


def _at2_npts_dt(path: Path, line: str) -> tuple[int, float]:
    """NPTS and DT (s) from line 4 of an .AT2 file (:data:`AT2_NPTS_DT`); a ModelError naming
    the file if the line is neither form or NPTS is not an integer >= 2 or DT below
    :data:`MIN_SAMPLE_STEP_S`."""
    match = AT2_NPTS_DT[0].search(line) or AT2_NPTS_DT[1].match(line)
    if match is None:
        raise ModelError(f"{path}: line 4: {shown(line.strip())}: expected 'NPTS=  5590, DT=   .0050 SEC' or '5590    0.0050    NPTS, DT'")
    npts_text, dt_text = match.groups()
    # ASCII digits (str.isdigit also takes superscripts, which int() refuses), fewer than the
    # 4300 that int() converts
    npts = int(npts_text) if npts_text.isascii() and npts_text.isdigit() and len(npts_text) <= 4000 else npts_text
    NPTS.check(npts, f"{path}: line 4: NPTS")
    dt_s = _number(dt_text, f"{path}: line 4: DT")
    AT2_DT.check(dt_s, f"{path}: line 4: DT")
    return npts, dt_s


def read_motion(path: str | Path, direction: str | None = None) -> GroundMotion:
    """A motion from a file, by its suffix (either case): ``.csv`` (:func:`read_csv_motion`,
    whose columns say the directions) or ``.at2`` (:func:`read_at2`, along ``direction``,
    default "x"). A ModelError names the file if it is missing or a folder, if the suffix is
    another, or if a direction is given for a CSV file, and ``path`` if it is no path (found by
    a hunt: None was a TypeError)."""
    check_arguments("read_motion", {"path": FILE_PATH}, path=path)
    path = Path(path)
    _check_file(path, "motion")
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        raise ModelError(f"{path}: unknown motion file type {path.suffix!r}; supported: {', '.join(SUFFIXES)} (either case)")
    if suffix == ".at2":
        return read_at2(path, "x" if direction is None else direction)
    if direction is not None:
        raise ModelError(f"{path}: direction = {direction!r} applies to a single-component .AT2 record; "
                         f"a CSV motion gives its directions as columns {', '.join(ACCELERATION_COLUMNS)}")
    return read_csv_motion(path)


def pulse(kind: str, *, amplitude_m_s2: float, frequency_hz: float, cycles: int = 1, direction: str = "x",
          samples_per_period: int = 200) -> GroundMotion:
    """An analytic acceleration pulse of amplitude A = ``amplitude_m_s2`` (a negative one
    pushes the other way) and frequency f = ``frequency_hz`` along ``direction``, sampled at
    ``samples_per_period`` points per period 1/f (at least; times k dt from 0).

    ``"one-sine"``: a(t) = A sin(2 pi f t), 0 <= t <= 1/f: one full period, ``cycles`` = 1;
    the one-sine acceleration pulse, type-A cycloidal pulse of Zhang & Makris (2001),
    "Rocking response of free-standing blocks under cycloidal pulses", J. Eng. Mech. 127(5),
    473-483. The table ends at zero velocity, v = A / (2 pi f) (1 - cos 2 pi f t), displaced
    by A / (2 pi f^2).

    ``"sine"``: the same for ``cycles`` whole periods, 0 <= t <= cycles / f: zero final
    velocity; the displacement drifts, A / (2 pi f) (t - sin(2 pi f t) / (2 pi f)), to
    A cycles / (2 pi f^2) (:meth:`GroundMotion.baseline_corrected` brings it back).

    ``"ricker"``: a(t) = A (1 - 2 u^2) exp(-u^2), u = pi f (t - t0), t0 = 1.5 / f,
    0 <= t <= 2 t0 (Ricker 1953, "The form and laws of propagation of seismic wavelets",
    Geophysics 18(1), 10-40); f is the peak frequency of its spectrum, A the peak at t0. Its
    ends are -1e-8 A; the table's velocity, A / (pi f) (u exp(-u^2) + u0 exp(-u0^2)) with
    u0 = 1.5 pi, ends at 2 u0 exp(-u0^2) A / (pi f), and its displacement at
    2 u0^2 exp(-u0^2) A / (pi f)^2: both within 2e-8 of their peaks, it ends at rest.
    ``cycles`` must be 1.
    """
    check_arguments("pulse", PULSE_RULES, kind=kind, amplitude_m_s2=amplitude_m_s2, frequency_hz=frequency_hz,
                    cycles=cycles, direction=direction, samples_per_period=samples_per_period)
    if kind != "sine" and cycles != 1:
        raise ModelError(f"pulse cycles = {cycles}: a {kind} pulse has no cycles to repeat (cycles = 1); "
                         "use kind 'sine' for several periods")
    if kind == "ricker":
        half = math.ceil(1.5 * samples_per_period)  # t0 = 1.5 / f is a sample
        time = np.arange(2 * half + 1) * (1.5 / frequency_hz / half)
        u = math.pi * frequency_hz * (time - 1.5 / frequency_hz)
        values = amplitude_m_s2 * (1.0 - 2.0 * u**2) * np.exp(-(u**2))
        name = f"ricker pulse {amplitude_m_s2:g} m/s2, {frequency_hz:g} Hz along {direction}"
    else:
        time = np.arange(cycles * samples_per_period + 1) / (frequency_hz * samples_per_period)
        values = amplitude_m_s2 * np.sin(2.0 * math.pi * frequency_hz * time)
        repeats = f", {cycles} cycles" if kind == "sine" else ""
        name = f"{kind} pulse {amplitude_m_s2:g} m/s2, {frequency_hz:g} Hz{repeats} along {direction}"
    acceleration = np.zeros((time.size, 3))
    acceleration[:, DIRECTIONS.index(direction)] = values
    return GroundMotion(time, acceleration, name, period_s=1.0 / frequency_hz)
