"""The MAVLink parameter protocol (PARAM_REQUEST_LIST / _READ / PARAM_SET -> PARAM_VALUE).

All parameters travel as MAV_PARAM_TYPE_REAL32 with their index and the total count. A PARAM_SET
sent as INT32 (bytewise-encoded, as PX4 clients do for integer parameters) is decoded to its
integer value. Unknown names get no PARAM_VALUE (as PX4), only a counted miss.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

from pymavlink.dialects.v20 import common as mavlink2

_FACTORY = mavlink2.MAVLink(None)

PARAM_TYPE_INT32 = 6
PARAM_TYPE_REAL32 = 9


class ParamStore(Protocol):
    """The simulator's parameter interface."""

    def get_param(self, name: str) -> float: ...

    def set_param(self, name: str, value: float) -> None: ...

    def param_names(self) -> Sequence[str]: ...


@dataclass(frozen=True)
class ParamReply:
    """PARAM_VALUE messages to send, and a STATUSTEXT-worthy problem ("" if none)."""

    values: tuple[mavlink2.MAVLink_message, ...]
    problem: str = ""


def param_value_msg(store: ParamStore, name: str) -> mavlink2.MAVLink_message:
    """PARAM_VALUE for a known parameter, with its index and the count."""
    names = list(store.param_names())
    return _FACTORY.param_value_encode(
        param_id=name.encode("ascii"),
        param_value=float(store.get_param(name)),
        param_type=PARAM_TYPE_REAL32,
        param_count=len(names),
        param_index=names.index(name),
    )


def _name_of(raw: str | bytes) -> str:
    if isinstance(raw, bytes):
        raw = raw.decode("ascii", errors="replace")
    return raw.rstrip("\x00")


def request_list(store: ParamStore) -> ParamReply:
    """Answer PARAM_REQUEST_LIST: every parameter in index order."""
    return ParamReply(tuple(param_value_msg(store, name) for name in store.param_names()))


def request_read(store: ParamStore, param_id: str | bytes, param_index: int) -> ParamReply:
    """Answer PARAM_REQUEST_READ: by index when ``param_index`` >= 0, else by name."""
    names = list(store.param_names())
    if param_index >= 0:
        if param_index >= len(names):
            return ParamReply((), f"Param index {param_index} out of range")
        return ParamReply((param_value_msg(store, names[param_index]),))
    name = _name_of(param_id)
    if name not in names:
        return ParamReply((), f"Param {name} unknown")
    return ParamReply((param_value_msg(store, name),))


def param_set(
    store: ParamStore, param_id: str | bytes, value: float, param_type: int
) -> ParamReply:
    """Apply PARAM_SET and answer with the (possibly unchanged) value."""
    name = _name_of(param_id)
    if name not in list(store.param_names()):
        return ParamReply((), f"Param {name} unknown")
    if param_type == PARAM_TYPE_INT32:
        value = float(struct.unpack("<i", struct.pack("<f", value))[0])
    problem = ""
    if not math.isfinite(value):
        problem = f"Param {name}: value not finite"
    else:
        try:
            store.set_param(name, float(value))
        except ValueError as exc:
            problem = f"Param {name}: {exc}"
    return ParamReply((param_value_msg(store, name),), problem)
