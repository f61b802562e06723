"""The MAVLink parameter protocol (PARAM_REQUEST_LIST / _READ / PARAM_SET -> PARAM_VALUE).

Every parameter travels with PX4's type: MAV_PARAM_TYPE_REAL32, or MAV_PARAM_TYPE_INT32 encoded
bytewise in the float field, as PX4 does (the endpoint advertises
MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE). A PARAM_SET is applied only when its type is
the parameter's type and its value is finite and within PX4's bounds; anything else is answered
with the unchanged PARAM_VALUE and a reason for a STATUSTEXT, never applied ([PX4-params]; a
float gain set with INT32 bits would otherwise be a wildly wrong number in flight). Unknown
names get no PARAM_VALUE (as PX4), only a counted miss.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

from pymavlink.dialects.v20 import common as mavlink2

_FACTORY = mavlink2.MAVLink(None)

PARAM_TYPE_INT32 = mavlink2.MAV_PARAM_TYPE_INT32
PARAM_TYPE_REAL32 = mavlink2.MAV_PARAM_TYPE_REAL32
_WIRE_TYPE = {"FLOAT": PARAM_TYPE_REAL32, "INT32": PARAM_TYPE_INT32}
_TYPE_NAMES = {
    value: name.removeprefix("MAV_PARAM_TYPE_")
    for name, value in vars(mavlink2).items()
    if name.startswith("MAV_PARAM_TYPE_") and name != "MAV_PARAM_TYPE_ENUM_END"
}


class ParamStore(Protocol):
    """The simulator's parameter interface."""

    def get_param(self, name: str) -> float: ...

    def set_param(self, name: str, value: float) -> None: ...

    def param_type(self, name: str) -> str:
        """ "FLOAT" or "INT32"."""
        ...

    def param_names(self) -> Sequence[str]: ...


@dataclass(frozen=True)
class ParamReply:
    """PARAM_VALUE messages to send, and a STATUSTEXT-worthy problem ("" if none)."""

    values: tuple[mavlink2.MAVLink_message, ...]
    problem: str = ""


def int32_as_float(value: int) -> float:
    """The float whose bytes are ``value`` as int32 (MAVLink's bytewise parameter encoding)."""
    return struct.unpack("<f", struct.pack("<i", value))[0]


def float_as_int32(value: float) -> int:
    """The int32 whose bytes are the float32 ``value`` (inverse of :func:`int32_as_float`)."""
    return struct.unpack("<i", struct.pack("<f", value))[0]


def param_value_msg(store: ParamStore, name: str) -> mavlink2.MAVLink_message:
    """PARAM_VALUE for a known parameter, with its PX4 type, its index and the count."""
    names = list(store.param_names())
    wire_type = _WIRE_TYPE[store.param_type(name)]
    value = float(store.get_param(name))
    if wire_type == PARAM_TYPE_INT32:
        value = int32_as_float(int(value))
    return _FACTORY.param_value_encode(
        param_id=name.encode("ascii"),
        param_value=value,
        param_type=wire_type,
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
    """Apply PARAM_SET if its type, value and range are right; answer with the (possibly
    unchanged) value and, when refused, the reason."""
    name = _name_of(param_id)
    if name not in list(store.param_names()):
        return ParamReply((), f"Param {name} unknown")
    expected = _WIRE_TYPE[store.param_type(name)]
    problem = ""
    if param_type != expected:
        sent = _TYPE_NAMES.get(param_type, str(param_type))
        problem = f"Param {name}: type {sent} refused, it is {_TYPE_NAMES[expected]}; not applied"
    else:
        if param_type == PARAM_TYPE_INT32:
            value = float(float_as_int32(value))
        if not math.isfinite(value):
            problem = f"Param {name}: value not finite; not applied"
        else:
            try:
                store.set_param(name, float(value))
            except ValueError as exc:
                problem = f"Param {name}: {exc}; not applied"
    return ParamReply((param_value_msg(store, name),), problem)
