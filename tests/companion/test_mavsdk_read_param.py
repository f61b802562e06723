"""A parameter MAVSDK cannot read is "not reported" (None), whatever its param plugin raises;
an operator's Ctrl-C during the read still stops the flight."""

from __future__ import annotations

import pytest
from mavsdk import MavsdkError
from mavsdk.plugins.param import ParamError, ParamResult

from companion.mavsdk_link import MavsdkLink


class FakeParamPlugin:
    """Stands in for MAVSDK's ``Param`` plugin: the float getter raises ``float_error``, the
    int getter returns ``int_value`` or raises ``int_error``."""

    def __init__(
        self, float_error: BaseException, int_error: BaseException | None = None, int_value=0
    ) -> None:
        self.float_error, self.int_error, self.int_value = float_error, int_error, int_value

    def get_param_float(self, name: str) -> float:
        raise self.float_error

    def get_param_int(self, name: str) -> int:
        if self.int_error is not None:
            raise self.int_error
        return self.int_value


def link_with(plugin: FakeParamPlugin) -> MavsdkLink:
    """A MavsdkLink as connect() leaves it, with ``plugin`` as its param plugin."""
    link = MavsdkLink("udpin://127.0.0.1:14540")
    link._mavsdk, link._param = object(), plugin
    return link


@pytest.mark.parametrize(
    "error",
    [
        ParamError(ParamResult.TIMEOUT, "get_param_float()", "MPC_XY_VEL_MAX"),
        MavsdkError("no system"),
        RuntimeError("Param has been destroyed (its system or Mavsdk was destroyed)"),
        TimeoutError(),
        OSError("connection reset"),
    ],
    ids=["ParamError", "MavsdkError", "destroyed plugin", "timeout", "OSError"],
)
def test_any_failure_of_the_param_plugin_reads_as_not_reported(error: Exception) -> None:
    link = link_with(FakeParamPlugin(error, int_error=error))
    assert link.read_param("MPC_XY_VEL_MAX") is None


def test_an_int_parameter_is_read_when_the_float_getter_fails() -> None:
    wrong_type = ParamError(ParamResult.WRONG_TYPE, "get_param_float()", "COM_RC_IN_MODE")
    assert link_with(FakeParamPlugin(wrong_type, int_value=4)).read_param("COM_RC_IN_MODE") == 4.0


@pytest.mark.parametrize("stop", [KeyboardInterrupt(), SystemExit(1)], ids=["Ctrl-C", "exit"])
def test_ctrl_c_or_exit_during_the_read_is_not_swallowed(stop: BaseException) -> None:
    with pytest.raises(type(stop)):
        link_with(FakeParamPlugin(stop)).read_param("MPC_XY_VEL_MAX")
