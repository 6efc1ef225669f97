"""Model parameters: defaults, types and validation.

Every parameter a cluster depends on lives in ``PARAMETERS``, with its
default, allowed values and meaning; ``resolve`` fills in the defaults and
raises ``ValueError`` naming the offending parameter.
"""

from __future__ import annotations

import numbers
from decimal import Decimal, InvalidOperation
from dataclasses import dataclass

MODELS = ("lattice", "offlattice")
SEED_SHAPES = ("point", "block", "line")
LAUNCHES = ("circle", "box")
STATUSES = ("ok", "boundary", "step_limit", "exhausted", "error")
"""Growth outcomes; the index is the integer code kernels return."""


@dataclass(frozen=True)
class Parameter:
    """One model parameter as a user reads it.

    Attributes
    ----------
    default
        The value ``resolve`` fills in.
    values : tuple or str
        The allowed values: every one (tuple), or their range as a user
        writes it (str). ``resolve`` is what enforces them.
    meaning : str
        One line, a noun phrase: ``grow --help`` and the netCDF
        ``long_name`` both use it.
    shown : str, optional
        The default as a user reads it, where ``default`` is a placeholder
        that ``resolve`` replaces.
    """

    default: object
    values: tuple | str
    meaning: str
    shown: str | None = None


PARAMETERS = {
    "model": Parameter("lattice", MODELS, "particle positions: square/cubic lattice sites, or unit-diameter "
                                          "disks/spheres in continuous space"),
    "dim": Parameter(2, (2, 3), "dimension of space"),
    "stickiness": Parameter(1.0, "(0, 1]", "probability to stick at each contact"),
    "neighbours": Parameter(0, "2*dim or 3**dim-1", "lattice moves and contacts: nearest or Moore neighbours",
                            shown="2*dim"),
    "seed_shape": Parameter("point", SEED_SHAPES, "seed: one particle, a 2**dim block, or a substrate (line "
                                                  "in 2D, plane in 3D; periodic sides of width size)"),
    "size": Parameter(0, "0 or an integer >= 8", "box side in lattice spacings (particle diameters off the "
                                                 "lattice), 0 = unbounded"),
    "launch": Parameter("circle", LAUNCHES, "release on a circle/sphere of radius launch_factor*r_max + "
                                            "launch_margin, or uniformly on the box surface (needs size > 0)"),
    "launch_factor": Parameter(1.0, ">= 1", "launch radius over the cluster's largest radius r_max"),
    "launch_margin": Parameter(2.0, ">= 1", "launch radius beyond launch_factor*r_max"),
    "kill_factor": Parameter(0.0, "0 or > 1", "kill radius over the launch radius; 0 = exact return to the "
                                              "launch circle, none killed"),
    "jumps": Parameter(True, "true or false", "exact first-passage jumps far from the cluster (true), or "
                                              "single steps everywhere (false)"),
    "step": Parameter(0.0, "0 or > 0", "off-lattice step: 0 = move to exact contact, > 0 = standard deviation "
                                       "of fixed Gaussian steps with overlap checks (can tunnel)"),
    "walkers": Parameter(1, "an integer >= 1", "walkers at once; more than 1 start uniformly in the box and "
                                               "move in lockstep, none relaunched"),
    "max_steps": Parameter(0, "an integer >= 0", "walk-step budget per cluster (0 = none); growth stops with "
                                                 "status step_limit when it runs out"),
}
"""Every model parameter a cluster depends on (README, "The model")."""

DEFAULTS = {name: p.default for name, p in PARAMETERS.items()}
"""Model parameters and their defaults, as ``resolve`` fills them in."""


def _kind(name, value, kind):
    if kind is bool:
        if isinstance(value, bool):
            return value
        raise ValueError(f"{name}: expected true or false, got {value!r}")
    if kind is int:
        if isinstance(value, bool) or not isinstance(value, numbers.Integral):
            raise ValueError(f"{name}: expected an integer, got {value!r}")
        return int(value)
    if kind is float:
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            raise ValueError(f"{name}: expected a number, got {value!r}")
        value = float(value)
        if value != value or value in (float("inf"), float("-inf")):
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
    """Validate model parameters and fill in defaults.

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
    unknown = sorted(set(params) - set(DEFAULTS))
    if unknown:
        raise ValueError(f"{unknown[0]}: unknown model parameter (known: {', '.join(DEFAULTS)})")
    p = {**DEFAULTS, **params}
    p["model"] = _choice("model", _kind("model", p["model"], str), MODELS)
    dim = p["dim"] = _kind("dim", p["dim"], int)
    if dim not in (2, 3):
        raise ValueError(f"dim: {dim} is not 2 or 3")
    s = p["stickiness"] = _kind("stickiness", p["stickiness"], float)
    if not 0.0 < s <= 1.0:
        raise ValueError(f"stickiness: {s} is not in (0, 1]")
    nb = _kind("neighbours", p["neighbours"], int)
    if nb == 0:
        nb = 2 * dim
    if nb not in (2 * dim, 3**dim - 1):
        raise ValueError(f"neighbours: {nb} is not {2 * dim} or {3**dim - 1} for dim={dim}")
    if p["model"] == "offlattice" and "neighbours" in params and nb != 2 * dim:
        raise ValueError("neighbours: only lattice models have a neighbourhood")
    p["neighbours"] = nb
    p["seed_shape"] = _choice("seed_shape", _kind("seed_shape", p["seed_shape"], str), SEED_SHAPES)
    size = p["size"] = _kind("size", p["size"], int)
    if size < 0:
        raise ValueError(f"size: {size} is negative")
    p["launch"] = _choice("launch", _kind("launch", p["launch"], str), LAUNCHES)
    if p["launch"] == "box" and size == 0:
        raise ValueError("launch: 'box' needs size > 0")
    if p["seed_shape"] == "line" and size == 0:
        raise ValueError("seed_shape: 'line' needs size > 0 (the substrate's periodic width)")
    lf = p["launch_factor"] = _kind("launch_factor", p["launch_factor"], float)
    if lf < 1.0:
        raise ValueError(f"launch_factor: {lf} is below 1 (the launch circle must enclose the cluster)")
    lm = p["launch_margin"] = _kind("launch_margin", p["launch_margin"], float)
    if lm < 1.0:
        raise ValueError(f"launch_margin: {lm} is below 1")
    kf = p["kill_factor"] = _kind("kill_factor", p["kill_factor"], float)
    if kf != 0.0 and kf <= 1.0:
        raise ValueError(f"kill_factor: {kf} must be 0 (exact return) or > 1")
    if kf != 0.0 and p["launch"] == "box":
        raise ValueError("kill_factor: a kill circle needs launch='circle' (box launches start outside it)")
    p["jumps"] = _kind("jumps", p["jumps"], bool)
    st = p["step"] = _kind("step", p["step"], float)
    if st < 0.0:
        raise ValueError(f"step: {st} is negative")
    if st > 0.0 and p["model"] == "lattice":
        raise ValueError("step: a step length applies only to model='offlattice'")
    w = p["walkers"] = _kind("walkers", p["walkers"], int)
    if w < 1:
        raise ValueError(f"walkers: {w} is below 1")
    if w > 1 and size == 0:
        raise ValueError("walkers: more than one walker needs size > 0 (they start uniformly in the box)")
    if size > 0:
        minimum = 8
        if size < minimum:
            raise ValueError(f"size: {size} is below {minimum}, too small to grow in")
    ms = p["max_steps"] = _kind("max_steps", p["max_steps"], int)
    if ms < 0:
        raise ValueError(f"max_steps: {ms} is negative")
    return p


def coerce(name: str, text: str):
    """Parse a command-line string into the type of parameter ``name``.

    Raises ``ValueError`` naming the parameter for an unknown name or a
    value of the wrong type.
    """
    if name not in DEFAULTS:
        raise ValueError(f"{name}: unknown model parameter (known: {', '.join(DEFAULTS)})")
    default = DEFAULTS[name]
    if isinstance(default, bool):
        low = text.strip().lower()
        if low in ("true", "1", "yes"):
            return True
        if low in ("false", "0", "no"):
            return False
        raise ValueError(f"{name}: expected true or false, got {text!r}")
    if isinstance(default, int):
        try:
            return integer(text)
        except ValueError as err:
            raise ValueError(f"{name}: {err}") from None
    if isinstance(default, float):
        try:
            return float(text)
        except ValueError:
            raise ValueError(f"{name}: expected a number, got {text!r}") from None
    return text


_INTEGER_DIGITS = 30
"""Longest integer ``integer`` expands from exponent notation (far beyond any count)."""


def integer(text: str) -> int:
    """Parse an integer written as digits or as an integral number: ``1e5``, ``1.5e3``.

    Raises
    ------
    ValueError
        For anything else (``2.5``, ``1e5.5``, ``nan``); the caller names
        the option.
    """
    try:
        return int(text)
    except ValueError:
        pass
    try:
        value = Decimal(text)
    except InvalidOperation:
        value = Decimal("NaN")
    # The digit cap keeps int() from expanding a number like 1e999999999.
    if not value.is_finite() or value != value.to_integral_value() or value.adjusted() >= _INTEGER_DIGITS:
        raise ValueError(f"expected an integer, got {text!r}")
    return int(value)
