"""The companion's real-time priority: raised for a section where the system permits it, said
in one line either way, and given back afterwards; lockstep flights never ask for it."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

from companion.inprocess_link import InProcessLink
from companion.mission import load_mission
from companion.mission_reference import reference_of
from companion.planner_registry import make_planner
from companion.realtime import raise_to_realtime, realtime_section
from companion.runner import RunnerConfig, fly_mission

LINE = Path(__file__).resolve().parents[2] / "missions" / "line_20m.toml"

linux_only = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="SCHED_FIFO")


def policy() -> int:
    return os.sched_getscheduler(0) & ~os.SCHED_RESET_ON_FORK


@pytest.mark.parametrize("priority", [-1, 100])
def test_a_priority_outside_1_to_99_is_refused(priority):
    with pytest.raises(ValueError, match="real-time priority must be 1..99"):
        raise_to_realtime(priority)
    with pytest.raises(ValueError, match="realtime_priority must be 0"):
        RunnerConfig(realtime_priority=priority)


@linux_only
def test_section_raises_where_permitted_says_so_and_restores():
    before = os.sched_getscheduler(0), os.sched_getparam(0)
    lines: list[str] = []
    with realtime_section(7, "loop", lines.append):
        inside = policy(), os.sched_getparam(0).sched_priority
    assert len(lines) == 1 and lines[0].startswith("loop: ")
    if "not permitted" in lines[0]:
        assert inside == (before[0], before[1].sched_priority)
    else:
        assert lines[0] == "loop: real-time priority SCHED_FIFO 7"
        assert inside == (os.SCHED_FIFO, 7)
    assert (os.sched_getscheduler(0), os.sched_getparam(0)) == before


@linux_only
def test_priority_zero_changes_nothing_and_says_nothing():
    lines: list[str] = []
    with realtime_section(0, "loop", lines.append):
        assert policy() == os.SCHED_OTHER
    assert lines == []


def test_a_lockstep_flight_keeps_normal_priority():
    mission = load_mission(LINE)
    lines: list[str] = []
    outcome = fly_mission(
        InProcessLink.from_vehicle("iris", 0),
        make_planner("pd", 3.0),
        reference_of(mission),
        mission,
        RunnerConfig(realtime_priority=50),
        lambda _tick: None,
        lines.append,
    )
    assert outcome.status == "completed"
    assert not any("priority" in line for line in lines)
