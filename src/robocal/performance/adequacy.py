"""Is the measuring instrument good enough to state a figure?

The instrument's maximum permissible error is declared in the form of ISO 10360-10 (laser
trackers) and ISO 10360-2 (CMMs): ``E_MPE = A + B·L`` — e.g. ``15um+6um/m`` for a tracker whose
length error is at most 15 µm plus 6 µm per metre of distance. ISO 9283 asks that the measurement
uncertainty of a test not exceed 25 % of the characteristic it measures (clause 6.3); we take the
instrument's MPE at the largest distance of the test as that uncertainty (an expanded, k ≈ 2,
bound) and state per figure whether the instrument is adequate.

This is why a laser tracker often cannot state the repeatability of a small robot: at 4 m a
``15um+6um/m`` tracker has an MPE of 39 µm, more than an RP of 30 µm itself.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

__all__ = ["InstrumentMPE", "parse_mpe", "figure_adequacy", "ISO9283_UNCERTAINTY_RATIO"]

#: ISO 9283 (6.3): the measurement uncertainty shall not exceed this share of the characteristic
ISO9283_UNCERTAINTY_RATIO = 0.25

_UNIT_MM = {"um": 1e-3, "µm": 1e-3, "μm": 1e-3, "mm": 1.0, "m": 1e3}
_PER_M = {"um/m": 1e-3, "µm/m": 1e-3, "μm/m": 1e-3, "mm/m": 1.0, "ppm": 1e-3}


@dataclass(frozen=True)
class InstrumentMPE:
    """``E_MPE(L) = A + B·L``.

    Attributes
    ----------
    A_mm : float
        Constant term [mm].
    B_mm_per_m : float
        Term proportional to the distance [mm per m].
    text : str
        The declaration as given.
    """

    A_mm: float
    B_mm_per_m: float
    text: str = ""

    def at(self, distance_mm: float) -> float:
        """MPE [mm] at a distance [mm] from the instrument."""
        return self.A_mm + self.B_mm_per_m * float(distance_mm) / 1000.0


def parse_mpe(text: str) -> InstrumentMPE:
    """Read an MPE declaration such as ``15um+6um/m``, ``0.015mm + 0.006mm/m`` or ``10um``.

    Raises
    ------
    robocal.errors.InputError
        If the text is not of the form ``A[unit] [+ B[unit]/m]`` (units um, µm, mm; ppm = µm/m).
    """
    from ..errors import InputError

    s = str(text).replace(" ", "").lower().replace("±", "")
    m = re.fullmatch(r"([0-9.]+(?:e-?\d+)?)(um|µm|μm|mm)(?:\+([0-9.]+(?:e-?\d+)?)(um/m|µm/m|μm/m|mm/m|ppm))?", s)
    if not m:
        raise InputError(f"instrument MPE {text!r}: expected 'A+B/m' with units, e.g. '15um+6um/m' "
                         "(ISO 10360-10 form), or a constant such as '10um'")
    a = float(m.group(1)) * _UNIT_MM[m.group(2)]
    b = float(m.group(3)) * _PER_M[m.group(4)] if m.group(3) else 0.0
    if a < 0 or b < 0:
        raise InputError(f"instrument MPE {text!r}: terms must be >= 0")
    return InstrumentMPE(a, b, str(text))


def figure_adequacy(value_mm: float, mpe: InstrumentMPE, distance_mm: float,
                    ratio: float = ISO9283_UNCERTAINTY_RATIO) -> dict:
    """The instrument's uncertainty for one figure and whether it is small enough to state it.

    Parameters
    ----------
    value_mm : float
        The figure (AP, RP, AD, RD, AT, RT, ...) [mm]; its magnitude is used.
    mpe : InstrumentMPE
    distance_mm : float
        Largest distance from the instrument to the measured points of the figure [mm].
    ratio : float
        Largest admissible uncertainty / figure (ISO 9283: 0.25).

    Returns
    -------
    dict
        ``U_mm`` (the MPE at the distance), ``ratio`` (U / |figure|; inf for a zero figure) and
        ``adequate`` (bool).
    """
    u = mpe.at(distance_mm)
    v = abs(float(value_mm))
    r = u / v if v > 0 else float("inf")
    return {"U_mm": float(u), "ratio": float(r), "adequate": bool(r <= ratio)}
