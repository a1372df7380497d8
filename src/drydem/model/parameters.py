"""Parameters as frozen, keyword-only dataclasses with units, validated when created.

Each class maps one-to-one to a table of the model file (``[joint]``,
``[contacts]``, ``[supports]``, ``[solver]``); field names are the TOML keys.

Every number is checked against a :class:`Range` whose bounds say what is physically or
numerically meaningful (each bound's reason is next to it), so that ``kn = true`` (a boolean
is not a stiffness, though Python counts it as 1) or ``ratio = 1e300`` stop with a message
naming the table, the key and the allowed range instead of running on nonsense.

The one way to check settings, here and in the analyses' settings (tilting, limit analysis,
calibration): a :class:`Rule` per field (:class:`Range` for numbers, :data:`FLAG` for
switches, :class:`OneOf` for names) and :func:`check_fields`, which raises one
:class:`~drydem.errors.ModelError` naming every field that breaks its rule, its value and the rule.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
import os
import sys
import unicodedata
from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass, fields
from types import SimpleNamespace

from drydem.errors import ModelError

#: standard gravity, m/s2
G = 9.81
#: m/s2: the largest acceleration anything applies to the blocks, about 100 g: a ground motion's
#: along each axis (past any earthquake record, whose largest peaks are about 4 g, and any
#: shaking table, about 10 g; a record of 1e300 m/s2 overflowed the integration, which was then
#: called diverged) and a Simulation's gravity (at the bound the own weight of a 1 m tall masonry
#: block, 2e6 Pa, closes a joint of 3e7 Pa/m by 67 mm; a gravity of 1e6 m/s2 drove a 5 cm brick
#: 2e8 m through its base). A tilt by load multiplier asks for g (tan theta, -1): within the bound
#: up to theta = atan(1000 / 9.81) = 89.4 deg (TiltSettings.max_angle_deg)
MAX_ACCELERATION_M_S2 = 1000.0
#: the axes a tilting table may turn about (tilt and limit analyses' tilt_axis), and for each, the
#: horizontal direction the lateral load acts along (0: x, 1: y)
TILT_AXES = ("y", "x")
LOAD_DIRECTION = {"y": 0, "x": 1}


def is_number(value) -> bool:
    """A finite real number: a float, or an integer within a float's range, NumPy's scalars of
    both kinds too (``np.int64(3)`` is a number as ``3`` is); not a boolean (``True`` is an int
    in Python and ``np.True_`` no number to NumPy, neither a number here), nor an int of 400
    digits (JSON and TOML hold one; it is no float)."""
    if isinstance(value, numbers.Integral):
        return not isinstance(value, bool) and abs(int(value)) <= sys.float_info.max
    return isinstance(value, numbers.Real) and math.isfinite(value)


def is_integer(value) -> bool:
    """An integer (an int or a NumPy integer scalar), and not a boolean."""
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)


def plain(value):
    """A NumPy number, boolean or text as the Python int, float, bool or str it equals (JSON and
    TOML writers take those, a Python int does not overflow, and messages and checkpoints'
    settings show ``0.5`` and ``'x'``, not ``np.float64(0.5)`` and ``np.str_('x')``); any other
    value as it is."""
    if _is_numpy_bool(value):
        return bool(value)
    if isinstance(value, str):
        return value if type(value) is str else str(value)
    if type(value) in (bool, int, float) or not isinstance(value, numbers.Real):
        return value
    return int(value) if isinstance(value, numbers.Integral) else float(value)


def _is_numpy_bool(value) -> bool:
    """Whether ``value`` is NumPy's boolean scalar (np.True_, np.False_; numbers.Real does not
    count it, and NumPy is not imported here to ask)."""
    return type(value).__module__ == "numpy" and type(value).__name__ in ("bool", "bool_")


#: the longest value a message shows whole, characters (a value from a file may be a 400-digit
#: number or a megabyte of text)
SHOWN_CHARACTERS = 40


def shown(value) -> str:
    """``repr(value)`` for a message, its middle elided past :data:`SHOWN_CHARACTERS` with the
    length said: ``1000000000...0000000000 (401 characters)``."""
    text = repr(value)
    if len(text) <= SHOWN_CHARACTERS:
        return text
    half = SHOWN_CHARACTERS // 2 - 2
    return f"{text[:half]}...{text[-half:]} ({len(text)} characters)"


class Rule:
    """What a setting's value must be: ``value in rule`` says whether it is, ``str(rule)`` the
    rule in words (``must be ...``)."""

    def __contains__(self, value) -> bool:
        raise NotImplementedError

    def problem(self, value, where: str) -> str | None:
        """``where = value: must be ...`` if ``value`` breaks the rule, else None."""
        return None if value in self else f"{where} = {shown(value)}: {self}"

    def check(self, value, where: str) -> None:
        """ModelError ``where = value: must be ...`` unless ``value`` obeys the rule."""
        problem = self.problem(value, where)
        if problem is not None:
            raise ModelError(problem)


class Flag(Rule):
    """A switch: True or False, or NumPy's (``z < 0.01`` of an array gives those); not 0 or 1,
    nor a string."""

    def __contains__(self, value) -> bool:
        return isinstance(value, bool) or _is_numpy_bool(value)

    def __str__(self) -> str:
        return "must be true or false"


#: the rule of every switch
FLAG = Flag()


@dataclass(frozen=True)
class OneOf(Rule):
    """One of ``options``, of the same type (``1`` is not ``True``, ``1.0`` not ``"1.0"``; a
    NumPy value counts as the Python one it equals, :func:`plain`)."""

    options: tuple

    def __contains__(self, value) -> bool:
        value = plain(value)
        return any(type(value) is type(option) and value == option for option in self.options)

    def __str__(self) -> str:
        return f"must be one of {self.options}"


@dataclass(frozen=True)
class InstanceOf(Rule):
    """An instance of ``kind`` (a model's joint a JointMaterial, not a dict of its keys nor None:
    the wrong object would only fail, by an AttributeError, where it is first used)."""

    kind: type

    def __contains__(self, value) -> bool:
        return isinstance(value, self.kind)

    def problem(self, value, where: str) -> str | None:
        """As :meth:`Rule.problem`; for a dict given for a dataclass, how to make one of it (its
        ``MADE_BY`` where its own constructor is not the way, as a Model's)."""
        found = super().problem(value, where)
        if found is not None and isinstance(value, Mapping) and dataclasses.is_dataclass(self.kind):
            found += f" (make one of the dict: {getattr(self.kind, 'MADE_BY', f'{self.kind.__name__}(**values)')})"
        return found

    def __str__(self) -> str:
        name = self.kind.__name__
        return f"must be {'an' if name[0] in 'AEIOU' else 'a'} {name}"


class Text(Rule):
    """A text with a character other than white space (a name that messages and results show)."""

    def __contains__(self, value) -> bool:
        return isinstance(value, str) and bool(value.strip())

    def __str__(self) -> str:
        return "must be a non-empty text"


#: the rule of every text (a source, a title: a file's name as the system gave it, even one
#: that is not UTF-8, such as a Latin-1 name read on Linux as 's\udce9isme.toml', is one)
TEXT = Text()


#: Unicode's bidirectional controls (UAX #9): marks, embeddings, overrides and isolates
BIDI_CONTROLS = frozenset("\u061c\u200e\u200f\u202a\u202b\u202c\u202d\u202e\u2066\u2067\u2068\u2069")


class Name(Text):
    """A block's name: a :class:`Text` of characters that UTF-8 can write, as every file drydem
    writes a model to (TOML, OBJ, STL, VTK, compas JSON) holds it (a lone surrogate, U+D800
    alone, is none: save_model and write_mesh failed on it with a UnicodeEncodeError), on one
    line and printable: no control character (a NUL went raw into OBJ and 3DEC files), line
    or paragraph separator (U+2028 broke a 3DEC group name's line) nor bidirectional control
    (U+202E turns the text after it around: a name that reads as another)."""

    def __contains__(self, value) -> bool:
        if not super().__contains__(value) or any(unicodedata.category(c) in ("Cc", "Zl", "Zp") or c in BIDI_CONTROLS for c in value):
            return False
        try:
            value.encode("utf-8")
        except UnicodeEncodeError:
            return False
        return True

    def __str__(self) -> str:
        return "must be a non-empty text on one line, of printable characters UTF-8 can write"


#: the rule of every block name
NAME = Name()


class FilePath(Rule):
    """A file's path as the API takes one: a str or a pathlib.Path (any os.PathLike giving a
    str), not blank and without a NUL character (no file has such a name); not bytes, nor None
    or a number (``Path(5)`` fails deep inside, with a bare TypeError)."""

    def __contains__(self, value) -> bool:
        if isinstance(value, os.PathLike):
            try:
                value = os.fspath(value)
            except TypeError:
                return False
        return isinstance(value, str) and bool(value.strip()) and "\0" not in value

    def __str__(self) -> str:
        return "must be a file path (a str or a pathlib.Path, not empty)"


#: the rule of every file path argument of the API
FILE_PATH = FilePath()


class Callback(Rule):
    """What an analysis calls as it goes (``on_record``, ``on_progress``, ``on_frame``): None
    (nothing to call) or a function, any callable; checked before the work, so that a wrong
    one does not fail at its first call, after minutes of cycling."""

    def __contains__(self, value) -> bool:
        return value is None or callable(value)

    def __str__(self) -> str:
        return "must be None or a function (a callable)"


#: the rule of every callback argument (Simulation's, the analyses')
CALLBACK = Callback()


@dataclass(frozen=True)
class Range(Rule):
    """An interval of allowed values: ``low`` and ``high`` (None: unbounded), each end open or
    closed; ``integer`` for counts; ``unit`` for messages. A boolean is never in a range
    (``True`` is an int in Python, not a number here)."""

    low: float | None
    high: float | None
    low_open: bool = False
    high_open: bool = False
    integer: bool = False
    unit: str = ""

    def __contains__(self, value) -> bool:
        if not (is_integer(value) if self.integer else is_number(value)):
            return False
        value = int(value) if self.integer else float(value)  # a float16 cast the bound to its own type (found by a hunt: 1e15 overflowed)
        above = self.low is None or (value > self.low if self.low_open else value >= self.low)
        below = self.high is None or (value < self.high if self.high_open else value <= self.high)
        return above and below

    def __str__(self) -> str:
        kind = "an integer" if self.integer else "a number"
        low = "-inf" if self.low is None else f"{self.low:.4g}"
        high = "inf" if self.high is None else f"{self.high:.4g}"
        interval = f"{'(' if self.low_open or self.low is None else '['}{low}, {high}{')' if self.high_open or self.high is None else ']'}"
        return f"must be {kind} in {interval}{' ' + self.unit if self.unit else ''}"


def field_problems(settings, rules: Mapping[str, Rule], name: Callable[[str], str] = str, *,
                   optional: Collection[str] = ()) -> list[str]:
    """``NAME = VALUE: must be ...`` for every field of ``settings`` (any object: a dataclass)
    named in ``rules`` whose value breaks its rule, each field named by ``name(field)``; a field
    in ``optional`` may also be None (a value derived later)."""
    found = []
    for field, rule in rules.items():
        value = getattr(settings, field)
        if not (value is None and field in optional) and value not in rule:
            found.append(rule.problem(value, name(field)))
    return found


def refuse(problems: list[str]) -> None:
    """One ModelError naming every problem of ``problems`` (``; ``-separated), if there is one."""
    if problems:
        raise ModelError("; ".join(problems))


def check_fields(settings, rules: Mapping[str, Rule], where: str, *, optional: Collection[str] = ()) -> None:
    """Check the fields of ``settings`` named in ``rules`` (:func:`field_problems`): one
    ModelError naming, for every field that breaks its rule, ``WHERE FIELD``, its value and
    the rule (``[joint] kn = True: must be a number in [1e+04, 1e+15] Pa/m``). A dataclass (one
    checking itself in ``__post_init__``, frozen or not) then holds each NumPy number of those
    fields as the Python number it equals (:func:`plain`): its settings are written to JSON."""
    refuse(field_problems(settings, rules, lambda field: f"{where} {field}", optional=optional))
    if dataclasses.is_dataclass(settings):
        for field in rules:
            value = getattr(settings, field)
            if plain(value) is not value:
                object.__setattr__(settings, field, plain(value))


def argument_problems(where: str, rules: Mapping[str, Rule], *, optional: Collection[str] = (), **arguments) -> list[str]:
    """``WHERE NAME = VALUE: must be ...`` for every argument of ``where`` (a function) that
    breaks its rule (one in ``optional`` may also be None)."""
    return field_problems(SimpleNamespace(**arguments), rules, f"{where} {{}}".format, optional=optional)


def check_arguments(where: str, rules: Mapping[str, Rule], *, optional: Collection[str] = (), **arguments) -> None:
    """One ModelError naming, for every argument of ``where`` (a function) that breaks its rule,
    ``WHERE NAME``, its value and the rule: ``tilt_analysis settings = None: must be a
    TiltSettings`` (with :class:`InstanceOf`), before a wrong object fails where it is first used
    (:func:`argument_problems`)."""
    refuse(argument_problems(where, rules, optional=optional, **arguments))


#: joint stiffness, Pa/m: below 1e4 the own weight of a 1 m masonry wall (~2e4 Pa) would close
#: a joint by metres; 1e15 is E / t of steel (2e11 Pa) over a 0.2 mm joint, stiffer than any block
JOINT_STIFFNESS = Range(1e4, 1e15, unit="Pa/m")
#: Coulomb coefficient: > 0 (a frictionless joint has no static equilibrium on a tilted table);
#: 10 is a friction angle of 84 deg, far beyond any masonry joint (0.4-1.2)
FRICTION = Range(0.0, 10.0, low_open=True)
#: cohesion and tensile strength, Pa: 1e8 (100 MPa) exceeds the strength of any masonry unit
STRENGTH = Range(0.0, 1e8, unit="Pa")
#: density, kg/m3: from air-light foams (1) to above osmium (22,590)
DENSITY = Range(1.0, 25_000.0, unit="kg/m3")
#: sub-contacts per length: a contact costs their square; beyond 32 the trapezoid areas are
#: converged far below the joints' other uncertainties
POINTS = Range(1, 32, integer=True)


#: the joint laws: stiffness constant, a power of the normal stress, or affine in it
JOINT_MODELS = ("constant", "power", "affine")
#: exponent of the power law: 0 is the constant law; 3 stiffens a thousandfold per decade of
#: stress, beyond any joint-closure test (Bandis et al. 1983 fit exponents below 1)
JOINT_EXPONENT = Range(0.0, 3.0)
#: reference stress of the power law, Pa: 1e-3 Pa is a millimetre of dust, 1e9 Pa crushes any unit
REFERENCE_STRESS = Range(1e-3, 1e9, unit="Pa")
#: stiffness gained per unit of normal stress, 1/m: >= 0 (joints stiffen as they close);
#: 1e7 /m is 570 times the 17.52 /mm of the seed paper's joint-closure fit
STIFFNESS_PER_STRESS = Range(0.0, 1e7, unit="1/m")

#: the rule of each field of :class:`JointMaterial` (those of the laws may be None)
JOINT_RULES = {"kn": JOINT_STIFFNESS, "ks": JOINT_STIFFNESS, "friction": FRICTION, "cohesion": STRENGTH, "tension": STRENGTH,
               "model": OneOf(JOINT_MODELS), "kn_exponent": JOINT_EXPONENT, "ks_exponent": JOINT_EXPONENT,
               "stress_ref": REFERENCE_STRESS, "kn_min": JOINT_STIFFNESS, "kn_max": JOINT_STIFFNESS,
               "kn_per_stress": STIFFNESS_PER_STRESS, "ks_per_stress": STIFFNESS_PER_STRESS}
#: the keys of each law beyond kn and ks: (required, optional)
LAW_KEYS = {
    "constant": ((), ()),
    "power": (("kn_exponent", "stress_ref", "kn_min"), ("ks_exponent", "kn_max")),
    "affine": (("kn_per_stress",), ("ks_per_stress", "kn_min", "kn_max")),
}


@dataclass(frozen=True, kw_only=True)
class JointMaterial:
    """Dry joint: springs per unit area plus Mohr-Coulomb slip.

    kn, ks : normal and shear stiffness, Pa/m (stress per unit relative displacement); with a
        stress-dependent ``model``, their value at zero stress (affine) or at ``stress_ref`` (power).
    friction : Coulomb coefficient mu (tan of the friction angle), > 0.
    cohesion : c, Pa. tension : tensile strength, Pa. Both drop to zero for a
        sub-contact once it fails in shear or tension (3DEC's rule).
    model : the joint law (:mod:`drydem.engine.joints`), with sigma the normal stress, Pa:

        "constant"  kn, ks
        "power"     kn (sigma / stress_ref)^kn_exponent, ks (sigma / stress_ref)^ks_exponent
        "affine"    kn + kn_per_stress sigma,            ks + ks_per_stress sigma

        each clamped to [kn_min, kn_max]. The power law needs kn_min (its stiffness vanishes
        with the stress: the floor decides how far a lightly loaded joint closes), and kn_max
        with an exponent above 1 (its stress then grows without bound at a finite closure);
        otherwise they default to the whole range of :data:`JOINT_STIFFNESS`.
        ks_exponent defaults to kn_exponent and ks_per_stress to kn_per_stress (ks follows kn,
        as in the seed paper's kn = ks); a key not given stays None (:meth:`law_value` gives
        the value in force). The keys of one law are errors with another.
    """

    kn: float = 3e7
    ks: float = 3e7
    friction: float = 0.5
    cohesion: float = 0.0
    tension: float = 0.0
    model: str = "constant"
    kn_exponent: float | None = None
    ks_exponent: float | None = None
    stress_ref: float | None = None
    kn_min: float | None = None
    kn_max: float | None = None
    kn_per_stress: float | None = None
    ks_per_stress: float | None = None

    def __post_init__(self):
        check_fields(self, JOINT_RULES, "[joint]", optional=LAW_FIELDS)
        refuse(_law_problems(self))
        if self.model != "constant":
            refuse(_clamp_problems(self))

    def law_value(self, key: str) -> float | None:
        """The value of the law's parameter ``key`` (one of :data:`LAW_FIELDS`): as given, or the
        default of an optional key (see the class docstring); None for a key of another law or a
        required key not given (a joint that :func:`_law_problems` refuses)."""
        value = getattr(self, key)
        if value is not None or key not in LAW_KEYS[self.model][1]:
            return value
        return {"kn_min": JOINT_STIFFNESS.low, "kn_max": JOINT_STIFFNESS.high,
                "ks_exponent": self.kn_exponent, "ks_per_stress": self.kn_per_stress}[key]

    def changed(self, **values) -> JointMaterial:
        """This joint with ``values`` (any of its fields) changed: a new ``model`` drops the old
        law's keys, the same model keeps those not given (ModelError for a key that is no field)."""
        unknown = sorted(set(values) - {f.name for f in fields(self)})
        if unknown:
            raise ModelError(f"[joint] unknown key(s) {unknown}; allowed: {[f.name for f in fields(self)]}")
        dropped = {key: None for key in LAW_FIELDS} if values.get("model", self.model) != self.model else {}
        return dataclasses.replace(self, **(dropped | values))

    @property
    def stiffness_text(self) -> str:
        """The stiffness in words: ``kn 3e+07 Pa/m, ks 3e+07 Pa/m``, and the law if not constant
        (``power law: kn (sigma / 1000 Pa)^1, ks ...^1, in [1e+06, 1e+15] Pa/m``)."""
        text = f"kn {self.kn:.3g} Pa/m, ks {self.ks:.3g} Pa/m"
        if self.model == "constant":
            return text
        value = self.law_value
        clamp = f"in [{value('kn_min'):.3g}, {value('kn_max'):.3g}] Pa/m"
        if self.model == "power":
            return (f"{text} at {self.stress_ref:.4g} Pa, power law: kn (sigma / {self.stress_ref:.4g} Pa)^{self.kn_exponent:g}, "
                    f"ks (...)^{value('ks_exponent'):g}, {clamp}")
        return f"{text} at zero stress, affine law: + {self.kn_per_stress:.4g} sigma, + {value('ks_per_stress'):.4g} sigma /m, {clamp}"

    @property
    def stress_dependent(self) -> bool:
        """Whether the stiffness changes with the normal stress (a law other than constant
        whose exponents or slopes are not all zero)."""
        if self.model == "power":
            return self.kn_exponent > 0 or self.law_value("ks_exponent") > 0
        return self.model == "affine" and (self.kn_per_stress > 0 or self.law_value("ks_per_stress") > 0)


#: the fields of the stress-dependent laws (None where the model has no such key)
LAW_FIELDS = ("kn_exponent", "ks_exponent", "stress_ref", "kn_min", "kn_max", "kn_per_stress", "ks_per_stress")


def _law_problems(joint: JointMaterial) -> list[str]:
    """A key of another law given, or a key the law needs missing."""
    if joint.model not in LAW_KEYS:
        return []
    required, optional = LAW_KEYS[joint.model]
    problems = [f"[joint] {key} applies to model = {_law_of(key)}, not {joint.model!r}"
                for key in LAW_FIELDS if getattr(joint, key) is not None and key not in required + optional]
    problems += [f"[joint] model = {joint.model!r} needs {key}" for key in required if getattr(joint, key) is None]
    steep = [key for key in ("kn_exponent", "ks_exponent") if joint.model == "power" and (joint.law_value(key) or 0.0) > 1.0]
    if steep and joint.kn_max is None:
        problems.append(f"[joint] {steep[0]} = {joint.law_value(steep[0])!r} > 1 needs kn_max: the stress of such a law grows "
                        "without bound at a finite closure, and the clamp is what keeps it (and the timestep) finite")
    return problems


def _law_of(key: str) -> str:
    return " or ".join(repr(law) for law, (required, optional) in LAW_KEYS.items() if key in required + optional)


def _clamp_problems(joint: JointMaterial) -> list[str]:
    """kn_min <= kn_max, and kn, ks (the stiffnesses at the law's origin) within them."""
    low, high = joint.law_value("kn_min"), joint.law_value("kn_max")
    if low > high:
        return [f"[joint] kn_min = {low:.4g} exceeds kn_max = {high:.4g} Pa/m"]
    return [f"[joint] {key} = {getattr(joint, key):.4g} Pa/m: must lie within [kn_min, kn_max] = [{low:.4g}, {high:.4g}] Pa/m"
            for key in ("kn", "ks") if not low <= getattr(joint, key) <= high]


#: contact tolerance, m: a nanometre or more (below it the free flight timestep, a tenth of the
#: time to fall through the tolerance, drops under a microsecond: 1e-300 m made it 4.5e-152 s);
#: its bound relative to the blocks is checked with the model
TOLERANCE = Range(1e-9, None, unit="m")


#: the rule of each field of :class:`ContactSettings` (points_across and tolerance may also be None)
CONTACT_RULES = {"points_per_length": POINTS, "points_across": POINTS, "tolerance": TOLERANCE}


@dataclass(frozen=True, kw_only=True)
class ContactSettings:
    """Contact detection and sub-contact density.

    points_per_length : sub-contacts along each in-plane direction of a full face,
        ends included (2 = corners only, 3DEC's vertex sub-contacts; 1 = one point at
        the centroid of the contact polygon).
    points_across : sub-contacts across the wall, along y; ``None`` = 1 for in-plane models
        (:attr:`drydem.model.assembly.Model.in_plane`: the contact forces are uniform across the width,
        so one point on the mid-plane with the whole width's area is exact), 2 for other
        models with every block fixed in y, else points_per_length.
    tolerance : m, gap below which faces are in contact; ``None`` = 5 % of the
        thinnest free block; a given one may be at most half the thinnest free block
        (:data:`drydem.model.assembly.MAX_TOLERANCE_FRACTION`).
        Contacts are re-detected whenever neighbouring blocks have moved half of it relative
        to each other.
    """

    points_per_length: int = 4
    points_across: int | None = None
    tolerance: float | None = None

    def __post_init__(self):
        check_fields(self, CONTACT_RULES, "[contacts]", optional=("points_across", "tolerance"))


@dataclass(frozen=True, kw_only=True)
class Supports:
    """Degrees of freedom fixed for every block (world axes); x, y, z translations, rx, ry, rz rotations."""

    fix_x: bool = False
    fix_y: bool = False
    fix_z: bool = False
    fix_rx: bool = False
    fix_ry: bool = False
    fix_rz: bool = False

    def __post_init__(self):
        check_fields(self, {f.name: FLAG for f in fields(self)}, "[supports]")

    @property
    def mask(self) -> tuple[bool, ...]:
        """Fixed flags in the order x, y, z, rx, ry, rz."""
        return (self.fix_x, self.fix_y, self.fix_z, self.fix_rx, self.fix_ry, self.fix_rz)


CRITERIA = ("ratio", "velocity")
#: local damping alpha (paper Eq. 4): 1 would remove every force that moves a block
DAMPING = Range(0.0, 1.0, high_open=True)
#: fraction of the critical timestep: above 1 the central differences are unstable
TIMESTEP_SAFETY = Range(0.0, 1.0, low_open=True)
#: unbalanced force / mean weight: below 1e-12 float64 round-off of the force sums is reached;
#: above 1e-2 a state still accelerating at 1 % of g would count as equilibrium
RATIO = Range(1e-12, 1e-2)
#: m/s: a block point moving 1 mm/s is not at rest (the paper uses 1e-13)
MAX_VELOCITY = Range(0.0, 1e-3, low_open=True, unit="m/s")
#: cycles per equilibrium: 1e10 cycles are days of computing for a single load step
MAX_CYCLES = Range(1, 10**10, integer=True)
#: the drop, in a block's own heights, past which a block has fallen out of a tilting or shaking
#: analysis: a block that fell a thousand of its heights has left any wall it was part of, and a
#: larger value only keeps falling blocks cycling (nothing below a model stops them)
LOST_DROP_HEIGHTS = Range(0.0, 1e3, low_open=True)


#: the rule of each field of :class:`SolverSettings`
SOLVER_RULES = {"damping": DAMPING, "timestep_safety": TIMESTEP_SAFETY, "mass_scaling": FLAG, "criterion": OneOf(CRITERIA),
                "ratio": RATIO, "max_velocity": MAX_VELOCITY, "max_cycles": MAX_CYCLES}


@dataclass(frozen=True, kw_only=True)
class SolverSettings:
    """Explicit dynamic relaxation.

    damping : local damping coefficient alpha (paper Eq. 4), 0 <= alpha < 1.
    timestep_safety : fraction of the critical timestep used, 0 < f <= 1.
    mass_scaling : scale each block's inertia to its contact stiffness (statics only; it can
        blow up in collapse flows, where fictitious masses differ a lot between neighbours).
    criterion : "ratio" (max unbalanced force / mean weight < ``ratio``) or
        "velocity" (max block point speed < ``max_velocity``, m/s; the paper's 1e-13).
    max_cycles : cycles allowed for one equilibrium before it is reported as not converged.
    """

    damping: float = 0.8
    timestep_safety: float = 0.8
    mass_scaling: bool = False
    criterion: str = "ratio"
    ratio: float = 1e-5
    max_velocity: float = 1e-13
    max_cycles: int = 2_000_000

    def __post_init__(self):
        check_fields(self, SOLVER_RULES, "[solver]")


@dataclass(frozen=True)
class ContactDensity:
    """Sub-contact density resolved for a model (:attr:`drydem.model.assembly.Model.contact_density`): ``along`` points over a full face length in each in-plane direction
    (ends included), except ``across`` points in the direction of the world unit vector
    ``across_axis`` when it lies in the face (in-plane walls: 1 across the width is exact)."""

    along: int
    across: int
    across_axis: tuple[float, float, float] = (0.0, 1.0, 0.0)
