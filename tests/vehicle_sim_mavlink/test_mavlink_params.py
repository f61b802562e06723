"""The PARAM_* protocol over a minimal in-memory parameter store."""

from __future__ import annotations

import struct

import pytest

from vehicle_sim.mavlink import params


class Store:
    """A parameter store with the simulator's interface (stable order, ValueError on bad)."""

    def __init__(self) -> None:
        self.values = {"COM_OBL_RC_ACT": 0.0, "COM_OF_LOSS_T": 1.0, "MIS_TAKEOFF_ALT": 2.5}

    def param_type(self, name):
        return "INT32" if name == "COM_OBL_RC_ACT" else "FLOAT"

    def param_names(self):
        return tuple(self.values)

    def get_param(self, name):
        return self.values[name]

    def set_param(self, name, value):
        if value < 0:
            raise ValueError("must be >= 0")
        self.values[name] = value


def fields(msg):
    return msg.param_id, msg.param_value, msg.param_type, msg.param_count, msg.param_index


def test_request_list_sends_every_param_with_count_and_index():
    reply = params.request_list(Store())
    assert [fields(m) for m in reply.values] == [
        ("COM_OBL_RC_ACT", 0.0, 6, 3, 0),  # INT32 (bytewise: 0 is 0.0 either way)
        ("COM_OF_LOSS_T", 1.0, 9, 3, 1),
        ("MIS_TAKEOFF_ALT", 2.5, 9, 3, 2),
    ]


def test_request_read_by_name_and_by_index():
    store = Store()
    assert fields(params.request_read(store, b"MIS_TAKEOFF_ALT", -1).values[0])[:2] == (
        "MIS_TAKEOFF_ALT",
        2.5,
    )
    assert fields(params.request_read(store, "", 1).values[0])[0] == "COM_OF_LOSS_T"
    missing = params.request_read(store, "NOPE", -1)
    assert missing.values == () and "NOPE unknown" in missing.problem
    assert params.request_read(store, "", 7).values == ()
    # [MAVLink] PARAM_REQUEST_READ: param_index -1 reads by name, any index from 0 by index:
    # index 0 is the first parameter, index 3 (= param_count) is past the last
    assert fields(params.request_read(store, "", 0).values[0])[0] == "COM_OBL_RC_ACT"
    past = params.request_read(store, "", 3)
    assert past.values == () and "out of range" in past.problem


def test_param_set_applies_and_echoes_the_value():
    store = Store()
    reply = params.param_set(store, "COM_OF_LOSS_T", 0.5, params.PARAM_TYPE_REAL32)
    assert store.values["COM_OF_LOSS_T"] == 0.5
    assert fields(reply.values[0])[:2] == ("COM_OF_LOSS_T", 0.5) and reply.problem == ""


def test_param_set_int32_is_decoded_bytewise():
    store = Store()
    as_float = struct.unpack("<f", struct.pack("<i", 4))[0]
    params.param_set(store, "COM_OBL_RC_ACT", as_float, params.PARAM_TYPE_INT32)
    assert store.values["COM_OBL_RC_ACT"] == 4.0


@pytest.mark.parametrize(
    ("value", "problem"),
    [(-1.0, "must be >= 0"), (float("nan"), "finite"), (float("inf"), "finite")],
)
def test_rejected_set_echoes_the_old_value_and_says_why(value, problem):
    store = Store()
    reply = params.param_set(store, "MIS_TAKEOFF_ALT", value, params.PARAM_TYPE_REAL32)
    assert reply.values[0].param_value == 2.5
    assert problem in reply.problem


def test_int32_parameter_value_is_encoded_bytewise():
    store = Store()
    store.values["COM_OBL_RC_ACT"] = 4.0
    msg = params.request_read(store, b"COM_OBL_RC_ACT", -1).values[0]
    assert msg.param_type == params.PARAM_TYPE_INT32
    assert params.float_as_int32(msg.param_value) == 4


@pytest.mark.parametrize(
    ("name", "sent_type"),
    [("COM_OF_LOSS_T", params.PARAM_TYPE_INT32), ("COM_OBL_RC_ACT", params.PARAM_TYPE_REAL32)]
    + [("COM_OF_LOSS_T", t) for t in (1, 2, 3, 4, 5, 7, 8, 10)],
)
def test_param_set_of_the_wrong_type_is_refused_and_not_applied(name, sent_type):
    store = Store()
    before = dict(store.values)
    reply = params.param_set(store, name, params.int32_as_float(1), sent_type)
    assert store.values == before
    assert "refused" in reply.problem and "not applied" in reply.problem
    assert reply.values[0].param_id == name
