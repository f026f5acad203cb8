"""Reading quantities with units (pint) from configuration text.

Quantities are written as text, for example ``"17.5 mm"`` or ``"24.7 GN*s/m^2.5"``,
and converted to SI floats inside camdyn. Cam speeds need care: pint treats the
radian as dimensionless, so ``"11.55 Hz"`` would silently become 11.55 rad/s.
:func:`parse_speed` therefore reads speeds itself: Hz and 1/s mean revolutions
per second, rpm means revolutions per minute, rad/s means radians per second.
"""

from __future__ import annotations

import math
import numbers
import re
from functools import lru_cache

import pint

from camdyn.errors import ParameterError, UnitError

__all__ = ["registry", "parse_quantity", "parse_speed", "angular_speed", "speed_text_rad_s", "format_quantity"]


@lru_cache(maxsize=1)
def registry() -> pint.UnitRegistry:
    """The shared pint unit registry."""
    try:  # pint caches its parsed definitions on disk (about 0.2 s saved per process)
        return pint.UnitRegistry(autoconvert_offset_to_baseunit=True, cache_folder=":auto:")
    except Exception:  # pragma: no cover - read-only home or an older pint
        return pint.UnitRegistry(autoconvert_offset_to_baseunit=True)


#: ``3,5 mm``: a decimal comma, which pint would read as 35 mm.
_DECIMAL_COMMA = re.compile(r"\d,\d")
#: ``3 4 mm``: two numbers side by side, which pint would multiply.
_NUMBERS_SIDE_BY_SIDE = re.compile(r"^[-+]?[\d.]+(?:[eE][-+]?\d+)?\s+[-+]?[\d.]+(?:[eE][-+]?\d+)?(?=\s|$|[a-zA-Z])")


def _math_finite_text(text: str) -> bool:
    """False for text that reads as nan or inf (with or without a unit)."""
    head = text.split()[0].lower() if text.split() else ""
    return head.lstrip("+-") not in ("nan", "inf", "infinity")


def _quantity(text, key: str):
    reg = registry()
    if isinstance(text, bool):
        raise UnitError(f"{key}: expected a number with a unit, got {text!r}")
    if isinstance(text, (int, float)):
        return reg.Quantity(float(text), "")
    if not isinstance(text, str) or not text.strip():
        raise UnitError(f"{key}: expected a quantity such as '17.5 mm', got {text!r}")
    cleaned = text.strip().replace("·", "*").replace("^", "**").replace("µ", "u")
    if _DECIMAL_COMMA.search(cleaned):
        raise UnitError(f"{key}: {text!r} has a comma in its number; write the decimal point as '.'")
    if _NUMBERS_SIDE_BY_SIDE.match(cleaned):
        raise UnitError(f"{key}: {text!r} holds two numbers side by side; write one number and its unit")
    if not _math_finite_text(cleaned):
        raise UnitError(f"{key}: {text!r} is not a finite number")
    try:
        q = reg.Quantity(cleaned)
    except Exception as exc:  # pint raises several unrelated types here
        raise UnitError(f"{key}: cannot read the quantity {text!r} ({exc.__class__.__name__})") from None
    if not isinstance(q, reg.Quantity):  # a bare number parses to a float
        q = reg.Quantity(float(q), "")
    return q


def parse_quantity(text, unit: str, key: str = "value") -> float:
    """Read ``text`` as a quantity and return its magnitude in ``unit``.

    Parameters
    ----------
    text : str or float
        For example ``"17.5 mm"``. A bare number is accepted only when ``unit`` is
        dimensionless, or is taken to be in ``unit`` already when it is a float
        given programmatically.
    unit : str
        Target unit understood by pint, for example ``"m"`` or ``"N*s/m**2.5"``.
    key : str
        Parameter name used in error messages.

    Returns
    -------
    float
        Magnitude in ``unit``.
    """
    reg = registry()
    if not isinstance(unit, str):
        raise ParameterError(f"{key}: the target unit must be text such as 'm' or 'N*s/m**2.5', got {unit!r}")
    try:
        target = reg.Unit(unit) if unit else reg.Unit("")
    except Exception as exc:  # pint raises several unrelated types here
        raise UnitError(f"{key}: cannot read the unit {unit!r} ({exc.__class__.__name__})") from None
    q = _quantity(text, key)
    if q.unitless and not target.dimensionless:
        if isinstance(text, (int, float)):
            return float(text)
        raise UnitError(f"{key}: {text!r} has no unit; write it with one, e.g. '{text} {unit}'")
    try:
        value = q.to(target).magnitude
    except pint.DimensionalityError:
        raise UnitError(
            f"{key}: {text!r} is not convertible to {unit} "
            f"(it has dimension {q.dimensionality}, expected {target.dimensionality})"
        ) from None
    return float(value)


def parse_speed(text, key: str = "speed") -> float:
    """Read a cam speed and return it in revolutions per second [Hz].

    ``"11.55Hz"``, ``"693 rpm"``, ``"72.6 rad/s"`` and ``"11.55 1/s"`` are understood.
    A bare number is taken as Hz.
    """
    if isinstance(text, (int, float)) and not isinstance(text, bool):
        return float(text)
    q = _quantity(text, key)
    reg = registry()
    if q.unitless:
        return float(q.magnitude)
    units = str(q.units)
    if "revolution" in units or "rpm" in units:
        return float(q.to(reg.revolution / reg.second).magnitude)
    if "radian" in units:
        return float(q.to(reg.radian / reg.second).magnitude) / (2.0 * math.pi)
    if q.dimensionality == reg.Unit("Hz").dimensionality:
        return float(q.to("Hz").magnitude)
    raise UnitError(f"{key}: {text!r} is not a rotational speed; use Hz, rpm or rad/s")


def speed_text_rad_s(text: str, key: str = "speed") -> float:
    """Read text with a speed's unit (``"600 rpm"``, ``"10 Hz"``, ``"62.8 rad/s"``) and return
    it in rad/s, of either sign; text in rad/s keeps its number exactly. Bare numbers in
    text are Hz, as for :func:`parse_speed`."""
    q = _quantity(text, key)
    if not q.unitless and "radian" in str(q.units):
        try:
            return float(q.to(registry().radian / registry().second).magnitude)
        except pint.DimensionalityError:
            raise UnitError(f"{key}: {text!r} is not a rotational speed; use Hz, rpm or rad/s") from None
    return 2.0 * math.pi * parse_speed(text, key)


def angular_speed(speed, key: str = "speed") -> float:
    """Read a cam speed given at a public entry and return omega [rad/s].

    ``speed`` is a number of Hz (revolutions per second) or text with units read by
    :func:`parse_speed` (``"358 rpm"``, ``"37.5 rad/s"``, ``"6 Hz"``). Text in rad/s
    keeps its number exactly. A speed that is not positive and finite raises
    :class:`~camdyn.errors.ParameterError`.
    """
    if isinstance(speed, bool) or not isinstance(speed, (numbers.Real, str)):
        raise ParameterError(f"{key} must be a number of Hz or text such as '358 rpm', got {speed!r}")
    omega = speed_text_rad_s(speed, key) if isinstance(speed, str) else 2.0 * math.pi * parse_speed(speed, key)
    if not (math.isfinite(omega) and omega > 0.0):
        raise ParameterError(f"{key} must be positive and finite, got {speed!r} (a number is read as Hz)")
    return omega


def format_quantity(value: float, unit: str) -> str:
    """Format ``value`` [unit] as text that :func:`parse_quantity` reads back exactly."""
    return f"{value!r} {unit}" if unit else repr(value)
