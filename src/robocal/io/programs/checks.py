"""Checks that a robot program fits the robot it is corrected for: its language, its joint count."""

from __future__ import annotations

from ...errors import InputError

__all__ = ["ProgramMismatchError", "check_program"]

#: Controller language of each robot vendor (robot names start with the vendor).
_VENDOR_LANGUAGE = {"kuka": "krl", "abb": "rapid", "fanuc": "fanuc", "ur": "urscript"}
_LANGUAGE_NAME = {"krl": "KUKA KRL", "rapid": "ABB RAPID", "fanuc": "FANUC TP", "urscript": "UR script"}


class ProgramMismatchError(InputError):
    """The program does not fit the robot (language of another vendor, other joint count)."""


def _vendor(name: str):
    low = name.lower()
    for v in _VENDOR_LANGUAGE:
        if low.startswith(v + "_") or (v == "ur" and low[:2] == "ur" and low[2:3].isdigit()):
            return v
    return None


def check_program(program, model) -> None:
    """Raise :class:`ProgramMismatchError` when ``program`` is written in another vendor's language
    than ``model``'s, or a joint target has another number of axes than the model's joints."""
    vendor = _vendor(model.name)
    if vendor is not None and _VENDOR_LANGUAGE[vendor] != program.format:
        raise ProgramMismatchError(
            f"{program.path}: a {_LANGUAGE_NAME[program.format]} program cannot run on {model.name} (a "
            f"{_LANGUAGE_NAME[_VENDOR_LANGUAGE[vendor]]} controller); give the robot the program was written for")
    for t in program.targets:
        if t.kind == "joint" and len(t.joints) != model.n_joints:
            raise ProgramMismatchError(f"{program.path}, line {t.line}: joint target {t.name} has {len(t.joints)} "
                                       f"axes; {model.name} has {model.n_joints} ({', '.join(model.controller_joints)})")
