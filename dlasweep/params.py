"""Model parameters: defaults, types and validation.

Every parameter a cluster depends on lives in ``PARAMETERS``, with its
default, allowed values and meaning; ``resolve`` fills in the defaults and
raises ``ValueError`` naming the offending parameter.
"""

from __future__ import annotations

import contextlib
import enum
import functools
import math
import numbers
from collections.abc import Callable
from dataclasses import dataclass
from decimal import Decimal, InvalidOperation

MODELS = ("lattice", "offlattice")
MODEL_KINDS = {
    "lattice-2d": {"model": "lattice", "dim": 2},
    "offlattice-2d": {"model": "offlattice", "dim": 2},
    "lattice-3d": {"model": "lattice", "dim": 3},
    "offlattice-3d": {"model": "offlattice", "dim": 3},
}
"""Each model and dimension by its name, as ``dlasweep bench --model`` and ``dlasweep compile --model``
take it: each grows with kernels compiled apart."""
SEED_SHAPES = ("point", "block", "line")
LAUNCHES = ("circle", "box")
STATUSES = ("ok", "boundary", "step_limit", "exhausted", "error")
"""Growth outcomes; the index is the integer code kernels return and the dataset's ``status`` holds
(``error``: a sweep's task that failed)."""
Status = enum.IntEnum("Status", [(name, code) for code, name in enumerate(STATUSES)])
"""``STATUSES`` as named codes: ``Status.ok`` is 0, ``Status[cluster.status]`` a cluster's code."""


def is_integer(value) -> bool:
    """Whether ``value`` is an integer and not a bool (``True`` is an ``int`` to Python, not to a user)."""
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)


def is_number(value) -> bool:
    """Whether ``value`` is a real number and not a bool."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


@dataclass(frozen=True)
class Parameter:
    """One model parameter as a user reads it: the one place it is spelled.

    Attributes
    ----------
    kind : type
        ``bool``, ``int``, ``float`` or ``str``: what ``resolve`` converts
        to and ``coerce`` parses a command-line string as.
    default
        The value ``resolve`` fills in.
    values : tuple or str
        The allowed values: every one (tuple), or their range as a user
        writes it (str). ``checks`` (and for strings, the tuple) is what
        enforces them.
    meaning : str
        One line, a noun phrase: ``grow --help``, the netCDF ``long_name``
        and the README's table use it.
    checks : tuple of callable
        Each ``check(value, p, given)`` returns what is wrong with a value
        (``resolve`` prefixes the parameter's name), or None, given ``p``
        (every parameter, typed) and ``given`` (what the caller set).
    units : str or None
        The netCDF ``units`` of its variable; None for strings.
    shown : str, optional
        The default as a user reads it, where ``default`` is a placeholder
        that ``fill`` replaces.
    fill : callable, optional
        ``fill(value, p)``: the value made explicit (a placeholder default
        replaced), before the checks.
    note : str
        More for the README's table, beyond ``meaning``.
    shortcut : str
        For a method parameter, the shortcut a value other than the
        default takes away from the exact method (``SHORTCUTS``); empty for
        the model (stickiness, box size, ...): a scene to compare methods
        in, never a method that fails.
    """

    kind: type
    default: object
    values: tuple | str
    meaning: str
    checks: tuple = ()
    units: str | None = "1"
    shown: str | None = None
    fill: Callable | None = None
    note: str = ""
    shortcut: str = ""


MIN_SIZE = 8
"""Smallest box side to grow in."""
MAX_SIZE = 100_000
"""Largest box side: wider than any cluster of ``spec.MAX_PARTICLES`` (about 5e4 across in 2D); a box
launch releases walkers on its walls, and a wider box makes even the first particles slow to arrive
(docs/performance.md, "Parameter bounds")."""
MAX_STEP = 100.0
"""Largest Gaussian step (particle diameters). A step far longer than the cluster jumps over it: a walker
returned to the launch circle hits with a chance of about 1 / step**2 per step (at 1e9, never; docs/performance.md,
"Parameter bounds")."""
MIN_STICKINESS = 1e-4
"""Smallest stickiness: a particle takes about 1/stickiness contacts to stick (at 1e-300, never;
docs/performance.md, "Parameter bounds")."""
MAX_RADIUS_FACTOR = 100.0
"""Largest launch_factor, launch_margin and kill_factor: farther launch and kill circles give the same
clusters (the return to the launch circle is exact) more slowly, and at 1e200 the walk's squared radii
overflow to inf and it never ends."""
MAX_WALKERS = 1_000_000
"""Most lockstep walkers (their positions: 24 bytes each)."""
MAX_NOISE_REDUCTION = 1000
"""Largest noise_reduction: a particle takes that many walkers, so a cluster of N particles takes
about 1000 N walks."""
MIN_CONTACT_DISTANCE = 0.5
"""Smallest contact_distance: particles come no closer than it, so that the walk's neighbour lists
(``kernels.offlattice.walker.LCAP_CLOSE``) hold every centre within their radius (3D: about 1600 at 0.5)."""
MAX_DRIFT = 1.0
"""Largest drift (1/sites, 1/diameters): beyond length 1/drift the walk is ballistic, so at 1 a walker goes
nearly straight from its first site; on the lattice a larger tilt would give a move a negative probability."""
MAX_COUNT = 2 ** 62
"""Largest step budget: the kernels count steps in int64."""
MAX_SEED = 2 ** 63 - 1
"""Largest seed (a cluster's, a sweep's root): datasets store it as int64."""


def _below(low, shown, why=""):
    """A check: a value below ``low`` (written ``shown``) is refused, with ``why``."""
    return lambda v, p, given: f"{v} is below {shown}{why}" if v < low else None


def _above(high, shown, why=""):
    """A check: a value above ``high`` (written ``shown``) is refused, with ``why``."""
    return lambda v, p, given: f"{v} is above {shown}{why}" if v > high else None


def _negative(v, p, given):
    return f"{v} is negative" if v < 0 else None


def drift_vector(p):
    """The drift as a vector, ``drift`` times the unit vector of ``drift_angle`` and ``drift_azimuth``
    (x, y, z; z 0 in 2D), in 1/sites or 1/diameters: the walk's mean velocity over twice its diffusion
    constant."""
    theta, phi = math.radians(p["drift_angle"]), math.radians(p["drift_azimuth"])
    if p["dim"] == 2:
        unit = (math.sin(theta), -math.cos(theta), 0.0)
    else:
        unit = (math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), -math.cos(theta))
    return tuple(p["drift"] * c for c in unit)


def _tilt_problem(v, p):
    """What is wrong with a lattice drift ``v`` whose tilt gives some move a negative probability:
    ``1 + drift u.m`` must stay >= 0 for every move m of the neighbourhood."""
    if v == 0.0 or p["model"] != "lattice":
        return None
    mu = drift_vector({**p, "drift": v})
    moore = p["neighbours"] != 2 * p["dim"]
    steepest = sum(map(abs, mu)) if moore else max(map(abs, mu))  # the largest u.m over the moves
    if steepest > 1.0 + 1e-12:
        return (f"{v} tilts a move of neighbours={p['neighbours']} to a negative probability in this direction "
                f"(1 - {steepest:.3g} < 0; nearest neighbours allow up to 1)")
    return None


def _neighbourhood(nb, p):
    """``neighbours`` made explicit: 0 stands for the nearest neighbours, 2*dim."""
    return 2 * p["dim"] if nb == 0 else nb


PARAMETERS = {
    "model": Parameter(str, "lattice", MODELS, "particle positions: square/cubic lattice sites, or unit-diameter "
                                               "disks/spheres in continuous space", units=None),
    "dim": Parameter(int, 2, (2, 3), "dimension of space",
                     checks=(lambda d, p, given: None if d in (2, 3) else f"{d} is not 2 or 3",)),
    "stickiness": Parameter(float, 1.0, f"[{MIN_STICKINESS:g}, 1]", "probability to stick at each contact",
                            checks=(lambda s, p, given: None if MIN_STICKINESS <= s <= 1.0
                                    else f"{s} is not in [{MIN_STICKINESS:g}, 1] (about 1/stickiness contacts a "
                                         f"particle)",)),
    "neighbours": Parameter(
        int, 0, "2*dim or 3**dim-1", "lattice moves and contacts: nearest or Moore neighbours", shown="2*dim",
        fill=_neighbourhood,
        checks=(lambda nb, p, given: None if nb in (2 * p["dim"], 3 ** p["dim"] - 1)
                else f"{nb} is not {2 * p['dim']} or {3 ** p['dim'] - 1} for dim={p['dim']}",
                lambda nb, p, given: "only lattice models have a neighbourhood"
                if p["model"] == "offlattice" and "neighbours" in given and nb != 2 * p["dim"] else None)),
    "seed_shape": Parameter(
        str, "point", SEED_SHAPES, "seed: one particle, a 2**dim block, or a substrate (line in 2D, plane in 3D; "
                                   "periodic sides of width size)", units=None,
        note="the substrate is not counted in the points",
        checks=(lambda v, p, given: "'line' needs size > 0 (the substrate's periodic width)"
                if v == "line" and p["size"] == 0 else None,)),
    "size": Parameter(int, 0, f"0 or an integer in [{MIN_SIZE}, {MAX_SIZE}]",
                      "box side in lattice spacings (particle diameters off the lattice), 0 = unbounded",
                      checks=(_negative, lambda v, p, given: f"{v} is below {MIN_SIZE}, too small to grow in"
                              if 0 < v < MIN_SIZE else None, _above(MAX_SIZE, MAX_SIZE))),
    "launch": Parameter(str, "circle", LAUNCHES, "release on a circle/sphere of radius launch_factor*r_max + "
                                                 "launch_margin, or uniformly on the box surface (needs size > 0)",
                        units=None,
                        checks=(lambda v, p, given: "'box' needs size > 0" if v == "box" and p["size"] == 0
                                else None,)),
    "launch_factor": Parameter(float, 1.0, f"[1, {MAX_RADIUS_FACTOR:g}]",
                               "launch radius over the cluster's largest radius r_max",
                               checks=(_below(1.0, "1", " (the launch circle must enclose the cluster)"),
                                       _above(MAX_RADIUS_FACTOR, f"{MAX_RADIUS_FACTOR:g}"))),
    "launch_margin": Parameter(float, 2.0, f"[1, {MAX_RADIUS_FACTOR:g}]", "launch radius beyond launch_factor*r_max",
                               checks=(_below(1.0, "1"), _above(MAX_RADIUS_FACTOR, f"{MAX_RADIUS_FACTOR:g}"))),
    "kill_factor": Parameter(
        float, 0.0, f"0 or in (1, {MAX_RADIUS_FACTOR:g}]",
        "kill radius over the launch radius; 0 = exact return to the launch circle, none killed",
        shortcut="kill circle",
        note="the exact return draws from the Poisson kernel (2D) or escapes with probability 1-R/r (3D); > 1: "
             "killed and relaunched beyond kill_factor * launch radius",
        checks=(lambda kf, p, given: f"{kf} must be 0 (exact return) or > 1" if kf != 0.0 and kf <= 1.0 else None,
                _above(MAX_RADIUS_FACTOR, f"{MAX_RADIUS_FACTOR:g}"),
                lambda kf, p, given: "a kill circle needs launch='circle' (box launches start outside it)"
                if kf != 0.0 and p["launch"] == "box" else None)),
    "jumps": Parameter(bool, True, "true or false", "exact first-passage jumps far from the cluster (true), or "
                                                    "single steps everywhere (false)",
                       shortcut="single steps"),
    "step": Parameter(float, 0.0, f"0 or in (0, {MAX_STEP:g}]",
                      "off-lattice step: 0 = move to exact contact, > 0 = standard deviation of fixed Gaussian steps "
                      "with overlap checks (can tunnel)", shortcut="Gaussian steps",
                      checks=(_negative, _above(MAX_STEP, f"{MAX_STEP:g}",
                                                " diameters (a step far longer than the cluster jumps over it)"),
                              lambda st, p, given: "a step length applies only to model='offlattice'"
                              if st > 0.0 and p["model"] == "lattice" else None)),
    "walkers": Parameter(int, 1, f"an integer in [1, {MAX_WALKERS}]",
                         "walkers at once; more than 1 start uniformly in the box and move in lockstep, none "
                         "relaunched",
                         note="lockstep walkers take single steps", shortcut="lockstep walkers",
                         checks=(_below(1, "1"), _above(MAX_WALKERS, MAX_WALKERS),
                                 lambda w, p, given: "more than one walker needs size > 0 (they start uniformly in the "
                                 "box)" if w > 1 and p["size"] == 0 else None)),
    "noise_reduction": Parameter(
        int, 1, f"an integer in [1, {MAX_NOISE_REDUCTION}]",
        "lattice noise reduction: touches a perimeter site takes before it is occupied (1 = plain DLA)",
        note="each touch is counted at the site and its walker relaunched; the m-th touch occupies it",
        checks=(_below(1, "1"), _above(MAX_NOISE_REDUCTION, MAX_NOISE_REDUCTION),
                lambda m, p, given: "noise reduction applies only to model='lattice' (off the lattice: "
                "contact_distance)" if m > 1 and p["model"] == "offlattice" else None,
                lambda m, p, given: "noise reduction needs walkers=1 (it relaunches the walker)"
                if m > 1 and p["walkers"] > 1 else None)),
    "neighbour_alpha": Parameter(
        float, 1.0, "(0, 1]",
        "lattice attachment by occupied neighbours: stickiness * alpha**(B_full - B) at a site with B occupied "
        "neighbours (1 = constant stickiness)",
        note="B_full = neighbours - 1 (3 on the square lattice: Aukrust et al. 1989's alpha**(3-B)); the "
             "substrate counts as occupied",
        checks=(lambda a, p, given: None if 0.0 < a <= 1.0 else f"{a} is not in (0, 1]",
                lambda a, p, given: "attachment by neighbours applies only to model='lattice'"
                if a != 1.0 and p["model"] == "offlattice" else None,
                lambda a, p, given: f"{a} gives a site with one occupied neighbour a sticking probability "
                f"{p['stickiness'] * a ** (p['neighbours'] - 2):.3g}, below {MIN_STICKINESS:g} (about 1/that "
                f"contacts a particle)" if a < 1.0 and p["stickiness"] * a ** (p["neighbours"] - 2) < MIN_STICKINESS
                else None)),
    "contact_distance": Parameter(
        float, 1.0, f"[{MIN_CONTACT_DISTANCE:g}, 1]",
        "off-lattice noise reduction: a particle's centre distance from the one it touched, in diameters "
        "(1 = plain DLA)",
        note="the walker that touches is moved along the line of centres (fastDLA's noiseReductionFactor); at the "
             "substrate it stays",
        checks=(lambda f, p, given: None if MIN_CONTACT_DISTANCE <= f <= 1.0
                else f"{f} is not in [{MIN_CONTACT_DISTANCE:g}, 1] (closer particles overflow the walk's neighbour "
                     f"lists)",
                lambda f, p, given: "contact_distance applies only to model='offlattice' (on the lattice: "
                "noise_reduction)" if f != 1.0 and p["model"] == "lattice" else None,
                lambda f, p, given: "contact_distance needs walkers=1" if f != 1.0 and p["walkers"] > 1 else None)),
    "drift": Parameter(
        float, 0.0, f"[0, {MAX_DRIFT:g}]",
        "uniform drift of the walkers: v / (2 D), the inverse of the length beyond which the walk is ballistic "
        "(1/sites, 1/diameters; 0 = plain DLA)",
        note="a point or block seed needs kill_factor > 1 or a box (no exact return against a drift); on the "
             "lattice a step goes along move m with probability (1 + drift u.m) / M",
        checks=(_negative, _above(MAX_DRIFT, f"{MAX_DRIFT:g}", " (ballistic within a site)"),
                lambda v, p, given: _tilt_problem(v, p),
                lambda v, p, given: "drift needs walkers=1 (lockstep walkers take unbiased steps)"
                if v > 0.0 and p["walkers"] > 1 else None,
                lambda v, p, given: f"drift with seed_shape={p['seed_shape']!r} needs kill_factor > 1 or size > 0 "
                "(the exact return to the launch circle assumes no drift)"
                if v > 0.0 and p["seed_shape"] != "line" and p["kill_factor"] == 0.0 and p["size"] == 0 else None)),
    "drift_angle": Parameter(
        float, 0.0, "[0, 180]",
        "the drift's direction: degrees from down (-y in 2D, -z in 3D) towards +x", units="degree",
        checks=(lambda a, p, given: None if 0.0 <= a <= 180.0 else f"{a} is not in [0, 180]",
                lambda a, p, given: f"{a} points the drift away from the substrate (above 90 degrees walkers "
                "escape upwards)" if a > 90.0 and p["drift"] > 0.0 and p["seed_shape"] == "line" else None)),
    "drift_azimuth": Parameter(
        float, 0.0, "[0, 360)",
        "3D: the drift's direction about the vertical axis, degrees from +x towards +y", units="degree",
        checks=(lambda a, p, given: None if 0.0 <= a < 360.0 else f"{a} is not in [0, 360)",
                lambda a, p, given: "an azimuth applies only to dim=3 (2D: drift_angle alone)"
                if a != 0.0 and p["dim"] == 2 else None)),
    "max_steps": Parameter(int, 0, "an integer in [0, 2**62]", "walk-step budget per cluster (0 = none); growth "
                                                               "stops with status step_limit when it runs out",
                           checks=(_negative, _above(MAX_COUNT, "2**62"))),
}
"""Every model parameter a cluster depends on (README, "The model"), once: its type,
default, allowed values, checks, meaning and units. ``resolve``, ``coerce``, the
command line's options and help (``cli``), the spec's checks (``spec``, through
``resolve``), the dataset's attributes (``schema.SCHEMA``) and the README's table
(``markdown_table``, checked by a test) derive from it."""

DEFAULTS = {name: p.default for name, p in PARAMETERS.items()}
"""Model parameters and their defaults, as ``resolve`` fills them in."""
SHORTCUTS = {name: p.shortcut for name, p in PARAMETERS.items() if p.shortcut}
"""The method parameters, each named by the shortcut it takes away from the exact method."""
EXACT_METHOD = {name: DEFAULTS[name] for name in SHORTCUTS}
"""The exact method: every method parameter at its default."""


def _kind(name, value, kind):
    if kind is bool:
        if isinstance(value, bool):
            return value
        raise ValueError(f"{name}: expected true or false, got {value!r}")
    if kind is int:
        try:
            if isinstance(value, str):  # a spec's "5": text is the command line's to parse
                raise ValueError(f"expected an integer, got {value!r}")
            return integer(value)
        except ValueError as err:
            raise ValueError(f"{name}: {err}") from None
    if kind is float:
        if not is_number(value):
            raise ValueError(f"{name}: expected a number, got {value!r}")
        value = float(value)
        if not math.isfinite(value):
            raise ValueError(f"{name}: expected a finite number, got {value!r}")
        return value
    if not isinstance(value, str):
        raise ValueError(f"{name}: expected a string, got {value!r}")
    return value


def _choice(name, value, choices):
    if value not in choices:
        raise ValueError(f"{name}: {value!r} is not one of {', '.join(map(repr, choices))}")
    return value


def resolve(**params) -> dict:
    """Validate model parameters and fill in defaults, from ``PARAMETERS``.

    Every value is first converted to its parameter's type (and a string
    checked against its choices), then each parameter is made explicit
    (``fill``) and checked (``checks``), in the table's order.

    Parameters
    ----------
    **params
        Any subset of ``DEFAULTS``.

    Returns
    -------
    dict
        Every parameter, typed, with ``neighbours`` made explicit.

    Raises
    ------
    ValueError
        On an unknown parameter or an invalid value; the message names it.
    """
    try:
        # A sweep grows thousands of clusters from a few configurations: each is checked once.
        key = tuple((name, type(value), value) for name, value in params.items())
        return dict(_resolved(key))
    except TypeError:  # an unhashable value: checked afresh (and refused)
        return _resolve(params)


@functools.lru_cache(maxsize=256)
def _resolved(key) -> dict:
    return _resolve({name: value for name, _, value in key})


def _resolve(params) -> dict:
    unknown = sorted(set(params) - set(DEFAULTS))
    if unknown:
        raise ValueError(f"{unknown[0]}: unknown model parameter (known: {', '.join(DEFAULTS)})")
    p = {**DEFAULTS, **params}
    for name, par in PARAMETERS.items():
        p[name] = _kind(name, p[name], par.kind)
        if par.kind is str:
            _choice(name, p[name], par.values)
    for name, par in PARAMETERS.items():
        if par.fill is not None:
            p[name] = par.fill(p[name], p)
        for check in par.checks:
            problem = check(p[name], p, params)
            if problem:
                raise ValueError(f"{name}: {problem}")
    return p


def one_line(err) -> str:
    """An exception's message on one line (its type's name when it has none): error messages stay one line."""
    return " ".join(str(err).split()) or err.__class__.__name__


def counted(n: int, noun: str) -> str:
    """``n`` and the noun, plural unless n is 1: ``1 cluster``, ``1,800 particles``."""
    return f"{n:,} {noun}{'' if n == 1 else 's'}"


def text(value) -> str:
    """A value (numpy scalars too) as a user writes it on the command line or in a spec: ``true``, not ``True``."""
    value = value.item() if hasattr(value, "item") else value
    return str(value).lower() if isinstance(value, bool) else str(value)


def allowed(name) -> str:
    """The allowed values of a parameter as a user reads them: ``lattice, offlattice`` or ``(0, 1]``."""
    values = PARAMETERS[name].values
    return ", ".join(map(text, values)) if isinstance(values, tuple) else values


def shown_default(name) -> str:
    """The default of a parameter as a user reads it (``2*dim`` for the neighbourhood)."""
    par = PARAMETERS[name]
    return par.shown or text(par.default)


def markdown_table() -> str:
    """The README's table of the model parameters (section "The model"), from ``PARAMETERS``."""
    lines = ["| name | default | values | meaning |", "|---|---|---|---|"]
    for name, par in PARAMETERS.items():
        meaning = f"{par.meaning}; {par.note}" if par.note else par.meaning
        lines.append(f"| {name} | {shown_default(name)} | {allowed(name)} | {meaning} |")
    return "\n".join(lines) + "\n"


def coerce(name: str, text: str):
    """Parse a command-line string into the type of parameter ``name``.

    Raises ``ValueError`` naming the parameter for an unknown name or a
    value of the wrong type.
    """
    if name not in DEFAULTS:
        raise ValueError(f"{name}: unknown model parameter (known: {', '.join(DEFAULTS)})")
    kind = PARAMETERS[name].kind
    if kind is bool:
        low = text.strip().lower()
        if low in ("true", "1", "yes"):
            return True
        if low in ("false", "0", "no"):
            return False
        raise ValueError(f"{name}: expected true or false, got {text!r}")
    if kind is int:
        try:
            return integer(text)
        except ValueError as err:
            raise ValueError(f"{name}: {err}") from None
    if kind is float:
        try:
            return float(text)
        except ValueError:
            raise ValueError(f"{name}: expected a number, got {text!r}") from None
    return text


_INTEGER_DIGITS = 400
"""Longest integer ``integer`` expands from exponent notation: longer than any finite float (309 digits), so
that every number a spec holds gets its range checked, yet int() never expands a text like 1e999999999."""


def integer(value) -> int:
    """An integer, written as digits or as an integral number: ``1e5``, ``1.5e3``, ``100000.0``.

    The one rule for every integer a user gives: command-line text, or a
    number from a spec (TOML reads ``1e5`` as a float). Its range is the
    caller's to check, so that ``1e20`` gets the range, not this message.

    Raises
    ------
    ValueError
        For anything else (``2.5``, ``1e5.5``, ``nan``, ``true``, a list, a
        string in a spec); the caller names the key or option.
    """
    if is_integer(value):
        return int(value)
    if isinstance(value, str):
        with contextlib.suppress(ValueError):
            return int(value)
    try:
        number = Decimal(value) if isinstance(value, (str, float)) and not isinstance(value, bool) else None
    except InvalidOperation:
        number = None
    if number is None or not number.is_finite() or number != number.to_integral_value():
        raise ValueError(f"expected an integer, got {value!r}")
    if number.adjusted() >= _INTEGER_DIGITS:  # not expanded: int() of 1e999999999 would take minutes
        raise ValueError(f"{value} has more than {_INTEGER_DIGITS} digits, far beyond any range")
    return int(number)
