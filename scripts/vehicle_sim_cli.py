"""`vehicle-sim`: run the simulated vehicle as a MAVLink endpoint, like PX4 SITL.

Two UDP links on loopback, as PX4 SITL opens them: the offboard API link sends to 14540
(MAVSDK: ``udpin://127.0.0.1:14540``) and the GCS link sends to 14550 (MAVProxy / QGC /
pymavlink: ``udpin:127.0.0.1:14550``). Runs in real time or at ``--speed`` until SIGINT/SIGTERM
(or ``--duration-s``). With ``--log FILE.csv`` it also keeps the vehicle's own flight log, as
PX4 does on its SD card (measured acceleration and thrust, which MAVLink does not carry), and
writes it when it stops.

Usage:
    vehicle-sim                                        # iris, real time
    vehicle-sim --vehicle m100 --speed 2 --effect rotor_drag --effect wind.vel_ned_mps=[3,0,0]
    vehicle-sim --vehicle my_quad.toml --signing-key link.key
    vehicle-sim --vehicle iris_study --log onboard.csv   # fly it, then diagnose onboard.csv
    vehicle-sim --vehicle f450 --backend jsbsim          # JSBSim's F450 under the same control
    vehicle-sim config-from-log flight.ulg --out my_vehicle.toml   # your tuning, your hover
    vehicle-sim --vehicle husky_50kg                     # a ground rover, as PX4's rover speaks

A rover preset (vehicle_sim.rover: husky_50kg, roc6_150kg, dmrv_600kg) runs the rover endpoint
(MAV_TYPE_GROUND_ROVER; offboard velocity + yaw rate) in real time on the offboard link only
(MAVSDK and pymavlink: ``udpin://127.0.0.1:14540``); the multirotor-only options are refused.
"""

from __future__ import annotations

import argparse
import math
import signal
import sys
import threading
import time
import tomllib
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from companion.realtime import MAX_RT_PRIORITY, raise_to_realtime
from flightlog.atomic_output import OutputError, check_not_an_input, check_writable_file
from flightlog.flight_log_files import check_csv_log_name, keep_earlier_log, restore_earlier_log
from flightlog.schema import sidecar_path
from scripts.one_line_parser import output_path
from vehicle_sim import EFFECT_NAMES, SimConfigError, Simulator, load_sim_config
from vehicle_sim.backends import BACKEND_NAMES
from vehicle_sim.config import PRESET_NAMES, no_such_config
from vehicle_sim.mavlink import (
    EndpointConfig,
    MavlinkEndpoint,
    PortTakenError,
    SigningKeyError,
    load_signing_key,
    px4_sitl_links,
)
from vehicle_sim.onboard_log import OnboardLogger
from vehicle_sim.rover import PRESETS as ROVER_PRESETS
from vehicle_sim.rover import RoverSim, rover_preset
from vehicle_sim.rover.mavlink_rover import RoverMavlinkEndpoint

PROG = "vehicle-sim"
MAX_UDP_PORT = 65535


class UsageError(ValueError):
    """Bad command-line input; the message is one line."""


@dataclass(frozen=True)
class VehicleSimCliConfig:
    """What to run.

    Attributes:
        vehicle: preset name ("iris", "m100") or path of a config TOML file.
        effects: effect name -> parameter overrides ({} for the effect's defaults).
        backend: physics backend ("builtin" or "jsbsim"); None: the config's ``[sim] backend``.
        seed: simulator seed.
        speed: simulated seconds per wall-clock second.
        host: address the links bind to and send to (loopback by default).
        offboard_port, gcs_port: where the offboard API and GCS links send first.
        offboard_bind_port, gcs_bind_port: the links' own ports (0: any free port).
        signing_key_path: key file to require MAVLink 2 signing on both links, or None.
        duration_s: stop after this wall-clock time [s]; None runs until a signal.
        world_path: obstacle world file (planners.world_file): trunks the vehicle can hit
            (a crash disarms it) and its range sensor streams as OBSTACLE_DISTANCE; or None.
        log_path: where to write the onboard flight log (schema v1 CSV, 50 Hz of simulated
            time) when the endpoint stops; None keeps none.
        realtime_priority: SCHED_FIFO priority (1-99) of the simulation loop's thread, as a
            stand-in for a flight controller on a processor of its own (companion.realtime;
            not permitted: said in one line, normal priority); 0 (default) leaves it normal.
    """

    vehicle: str = "iris"
    effects: tuple[tuple[str, tuple[tuple[str, Any], ...]], ...] = ()
    backend: str | None = None
    seed: int = 0
    speed: float = 1.0
    host: str = "127.0.0.1"
    offboard_port: int = 14540
    gcs_port: int = 14550
    offboard_bind_port: int = 14580
    gcs_bind_port: int = 18570
    signing_key_path: str | None = None
    duration_s: float | None = None
    world_path: str | None = None
    log_path: str | None = None
    realtime_priority: int = 0


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line instead of usage + message
        raise UsageError(message)


def _effect_overrides(specs: Sequence[str]) -> tuple[tuple[str, tuple[tuple[str, Any], ...]], ...]:
    """``NAME`` or ``NAME.KEY=TOML_VALUE`` specs -> ((name, ((key, value), ...)), ...)."""
    effects: dict[str, dict[str, Any]] = {}
    for spec in specs:
        name, _, assignment = spec.partition(".")
        if name not in EFFECT_NAMES:
            raise UsageError(
                f"--effect {spec}: unknown effect {name!r}; choose from {', '.join(EFFECT_NAMES)}"
            )
        params = effects.setdefault(name, {})
        if not assignment:
            continue
        key, eq, raw = assignment.partition("=")
        if not eq or not key:
            raise UsageError(f"--effect {spec}: use NAME or NAME.KEY=VALUE")
        try:
            params[key] = tomllib.loads(f"v = {raw}")["v"]
        except tomllib.TOMLDecodeError:
            raise UsageError(
                f"--effect {spec}: {raw!r} is not a TOML value (e.g. 0.3 or [3, 0, 0])"
            ) from None
    return tuple((name, tuple(params.items())) for name, params in effects.items())


def parse_args(argv: Sequence[str] | None) -> VehicleSimCliConfig:
    parser = _Parser(
        prog=PROG,
        description=__doc__.splitlines()[0],
        epilog="Also: vehicle-sim config-from-log LOG --out my_vehicle.toml (a config with a "
        "PX4 log's tuning and hover thrust; --help there). Exit codes: 0 stopped (Ctrl-C, "
        "SIGTERM or --duration-s), 1 the simulation loop died or the onboard log could not be "
        "written, 2 bad input (options, config, world, signing key, a port taken, --log).",
    )
    parser.add_argument(
        "--vehicle",
        default="iris",
        help="multirotor preset or config TOML path, or a rover preset "
        f"({', '.join(ROVER_PRESETS)}) (default %(default)s)",
    )
    parser.add_argument(
        "--effect",
        action="append",
        default=[],
        metavar="NAME[.KEY=VALUE]",
        help="switch an effect on, optionally setting one parameter (repeatable)",
    )
    parser.add_argument(
        "--backend",
        choices=BACKEND_NAMES,
        help="physics backend (default: the config's [sim] backend, else builtin)",
    )
    parser.add_argument(
        "--seed",
        type=int,
        default=0,
        help="seed of the vehicle's random draws: gusts, a rover's rate noise "
        "(default %(default)s)",
    )
    parser.add_argument(
        "--speed",
        type=float,
        default=1.0,
        help="simulated seconds per wall-clock second (default %(default)g)",
    )
    parser.add_argument("--host", default="127.0.0.1", help="address to bind and send to")
    parser.add_argument(
        "--offboard-port",
        type=int,
        default=14540,
        help="port the companion listens on, as PX4 SITL's offboard link (default 14540)",
    )
    parser.add_argument(
        "--gcs-port",
        type=int,
        default=14550,
        help="port a ground station listens on (default 14550)",
    )
    parser.add_argument(
        "--offboard-bind-port",
        type=int,
        default=14580,
        help="the simulator's own port on the offboard link (default 14580; 0: any free one)",
    )
    parser.add_argument(
        "--gcs-bind-port",
        type=int,
        default=18570,
        help="the simulator's own port on the GCS link (default 18570; 0: any free one)",
    )
    parser.add_argument(
        "--signing-key",
        metavar="FILE",
        help="require MAVLink 2 signing with this key (64 hex digits or a passphrase)",
    )
    parser.add_argument("--duration-s", type=float, help="stop after this wall-clock time")
    parser.add_argument(
        "--world",
        metavar="WORLD.toml",
        help="obstacle world (cylinders, spheres, boxes): contact crashes the vehicle; its "
        "range sensor streams OBSTACLE_DISTANCE",
    )
    parser.add_argument(
        "--log",
        type=output_path,
        metavar="FILE.csv",
        help="write the vehicle's onboard flight log (with acceleration and thrust) here, row "
        "by row as it flies (complete on exit); a log already there is kept as FILE.1.csv",
    )
    parser.add_argument(
        "--realtime-priority",
        type=int,
        default=0,
        metavar="N",
        help="run the simulation loop at SCHED_FIFO priority N (1-99), as a flight controller "
        "on its own processor would not wait for other programs; 0 (default): normal priority",
    )
    args = parser.parse_args(argv)
    if not (math.isfinite(args.speed) and 0.01 <= args.speed <= 100.0):
        raise UsageError(f"--speed {args.speed}: must be within [0.01, 100]")
    if args.duration_s is not None and not (math.isfinite(args.duration_s) and args.duration_s > 0):
        raise UsageError(f"--duration-s {args.duration_s}: must be > 0")
    if args.seed < 0:
        raise UsageError(f"--seed {args.seed}: must be >= 0")
    for option, port, lowest in (
        ("--offboard-port", args.offboard_port, 1),
        ("--gcs-port", args.gcs_port, 1),
        ("--offboard-bind-port", args.offboard_bind_port, 0),
        ("--gcs-bind-port", args.gcs_bind_port, 0),
    ):
        if not lowest <= port <= MAX_UDP_PORT:
            raise UsageError(f"{option} {port}: must be a UDP port, {lowest}..{MAX_UDP_PORT}")
    if not 0 <= args.realtime_priority <= MAX_RT_PRIORITY:
        raise UsageError(
            f"--realtime-priority {args.realtime_priority}: must be 0 (off) or 1..{MAX_RT_PRIORITY}"
        )
    return VehicleSimCliConfig(
        vehicle=args.vehicle,
        effects=_effect_overrides(args.effect),
        backend=args.backend,
        seed=args.seed,
        speed=args.speed,
        host=args.host,
        offboard_port=args.offboard_port,
        gcs_port=args.gcs_port,
        offboard_bind_port=args.offboard_bind_port,
        gcs_bind_port=args.gcs_bind_port,
        signing_key_path=args.signing_key,
        duration_s=args.duration_s,
        world_path=args.world,
        log_path=None if args.log is None else str(args.log),
        realtime_priority=args.realtime_priority,
    )


def build_endpoint(config: VehicleSimCliConfig) -> MavlinkEndpoint:
    """The simulator and its endpoint (not started); raises ValueError on bad config."""
    effects = {name: dict(params) for name, params in config.effects} or None
    sim = Simulator(
        load_sim_config(config.vehicle, effects=effects), seed=config.seed, backend=config.backend
    )
    if config.world_path is not None:
        from planners.world_file import load_world

        sim.set_world(load_world(config.world_path))
    key = load_signing_key(config.signing_key_path) if config.signing_key_path else None
    links = px4_sitl_links(
        offboard_port=config.offboard_port,
        gcs_port=config.gcs_port,
        host=config.host,
        signing_key=key,
        offboard_bind_port=config.offboard_bind_port,
        gcs_bind_port=config.gcs_bind_port,
    )
    stepped = OnboardLogger(sim, stream_path=config.log_path) if config.log_path else sim
    return MavlinkEndpoint(stepped, EndpointConfig(links=links, speed=config.speed))


def _announce(config: VehicleSimCliConfig, endpoint: MavlinkEndpoint) -> None:
    ports = endpoint.local_ports
    host = config.host
    signing = "on (unsigned commands refused)" if config.signing_key_path else "off"
    world = f", world {config.world_path} (OBSTACLE_DISTANCE)" if config.world_path else ""
    print(
        f"{PROG}: {config.vehicle} on {endpoint.sim.backend_name} at {config.speed:g}x "
        f"real time, seed {config.seed}, signing {signing}{world}"
    )
    print(f"MAVSDK: udpin://{host}:{config.offboard_port}")
    print(f"companion: --url udpin://{host}:{config.offboard_port} (--link mavsdk or pymavlink)")
    print(f"pymavlink: udpin:{host}:{config.gcs_port} (or udpout:{host}:{ports['gcs']})")
    print(f"MAVProxy: mavproxy.py --master udpin:{host}:{config.gcs_port}")
    print("Ctrl-C to stop", flush=True)


def serve(endpoint: MavlinkEndpoint, stop: threading.Event, duration_s: float | None) -> None:
    """Run until ``stop`` is set, the deadline passes or the endpoint's loop dies."""
    deadline = math.inf if duration_s is None else time.monotonic() + duration_s
    while not stop.is_set() and endpoint.running and time.monotonic() < deadline:
        stop.wait(min(0.2, max(0.0, deadline - time.monotonic())))


def _stop(endpoint: MavlinkEndpoint) -> str:
    """Stop the endpoint; the reason it failed ("" if it stopped cleanly)."""
    try:
        endpoint.stop()
    except RuntimeError as exc:
        return str(exc)
    return ""


def _write_onboard_log(endpoint: MavlinkEndpoint, path: str | None) -> str:
    """Write the onboard log if one was kept; the reason it failed ("" if written or none)."""
    if path is None or not isinstance(endpoint.sim, OnboardLogger):
        return ""
    log = endpoint.sim.to_log()
    try:
        written = endpoint.sim.write(Path(path))
    except OSError as exc:
        return f"onboard log not written: {exc}"
    print(f"{PROG}: onboard log {written} ({log.n_rows} rows)", flush=True)
    return ""


def main(argv: Sequence[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    if args[:1] == ["config-from-log"]:
        from scripts.config_from_log_cli import main as config_from_log_main

        return config_from_log_main(args[1:])
    try:
        config = parse_args(argv)
    except UsageError as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    stop = threading.Event()
    previous = {
        sig: signal.signal(sig, lambda *_: stop.set()) for sig in (signal.SIGINT, signal.SIGTERM)
    }
    try:
        return _run(config, stop)
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


def _undo_log(log_path: str | None, kept: Path | None) -> None:
    """A session that never started leaves no log of its own: the earlier one ``kept`` aside
    is put back, or the empty one it opened (with its sidecar) goes."""
    if log_path is None:
        return
    if kept is not None:
        restore_earlier_log(kept, Path(log_path))
    else:
        Path(log_path).unlink(missing_ok=True)
        sidecar_path(log_path).unlink(missing_ok=True)


def _run_rover(config: VehicleSimCliConfig, stop: threading.Event) -> int:
    """Serve a rover preset on the offboard link until ``stop``, the deadline or a dead loop."""
    defaults = VehicleSimCliConfig()
    refused = [
        flag
        for flag, used in (
            ("--effect", config.effects),
            ("--backend", config.backend),
            ("--speed", config.speed != 1.0),
            ("--signing-key", config.signing_key_path),
            ("--world", config.world_path),
            ("--log", config.log_path),
            ("--realtime-priority", config.realtime_priority),
            ("--gcs-port", config.gcs_port != defaults.gcs_port),
            ("--offboard-bind-port", config.offboard_bind_port != defaults.offboard_bind_port),
            ("--gcs-bind-port", config.gcs_bind_port != defaults.gcs_bind_port),
        )
        if used
    ]
    if refused:
        print(
            f"{PROG}: error: {', '.join(refused)}: not for the rover {config.vehicle} "
            "(real time, one offboard link)",
            file=sys.stderr,
        )
        return 2
    sim = RoverSim(rover_preset(config.vehicle), seed=config.seed)
    try:
        endpoint = RoverMavlinkEndpoint(sim, config.offboard_port, config.host, mode="udpout")
    except OSError as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    endpoint.start()
    print(f"{PROG}: rover {config.vehicle} at 1x real time, seed {config.seed}")
    print(f"MAVSDK: udpin://{config.host}:{config.offboard_port}")
    print(f"pymavlink: udpin:{config.host}:{config.offboard_port}")
    print("Ctrl-C to stop", flush=True)
    deadline = math.inf if config.duration_s is None else time.monotonic() + config.duration_s
    while not stop.is_set() and endpoint.running and time.monotonic() < deadline:
        stop.wait(min(0.2, max(0.0, deadline - time.monotonic())))
    died = not endpoint.running
    endpoint.close()
    if died:
        print(f"{PROG}: error: the rover's loop stopped", file=sys.stderr)
        return 1
    print(f"{PROG}: stopped at t = {sim.state.t_s:.1f} s sim", flush=True)
    return 0


def _run(config: VehicleSimCliConfig, stop: threading.Event) -> int:
    if config.vehicle in ROVER_PRESETS:
        return _run_rover(config, stop)
    if config.vehicle not in PRESET_NAMES and not Path(config.vehicle).is_file():
        rovers = f"a rover ({', '.join(ROVER_PRESETS)})"
        print(f"{PROG}: error: --vehicle {no_such_config(config.vehicle, rovers)}", file=sys.stderr)
        return 2
    if config.log_path is not None:
        try:  # found out now, not after a flight whose log would be lost
            check_csv_log_name(Path(config.log_path))
            check_writable_file(config.log_path)
            check_writable_file(sidecar_path(config.log_path))
            inputs = (config.vehicle, config.world_path, config.signing_key_path)
            check_not_an_input(config.log_path, [Path(f) for f in inputs if f is not None])
        except OutputError as exc:
            print(f"{PROG}: error: --log {exc}", file=sys.stderr)
            return 2
    try:  # an onboard log already there is moved aside (stem.N.csv), as the companion does
        kept = None if config.log_path is None else keep_earlier_log(Path(config.log_path))
    except OutputError as exc:
        print(f"{PROG}: error: --log {exc}", file=sys.stderr)
        return 2
    try:
        endpoint = build_endpoint(config)
        endpoint.start()
    except PortTakenError as exc:
        _undo_log(config.log_path, kept)
        option = f"--{exc.link_name}-bind-port"
        print(
            f"{PROG}: error: {exc}; another vehicle-sim or PX4 SITL may hold it: pass "
            f"{option} with a free port (0: any)",
            file=sys.stderr,
        )
        return 2
    except (SimConfigError, SigningKeyError, ValueError, OSError) as exc:
        _undo_log(config.log_path, kept)
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    if kept is not None:
        print(f"{PROG}: onboard log: {config.log_path} (the log there before is kept as {kept})")
    try:
        if config.realtime_priority and endpoint.loop_thread_id is not None:
            outcome = raise_to_realtime(config.realtime_priority, endpoint.loop_thread_id)
            print(f"{PROG}: simulation loop: {outcome}")
        _announce(config, endpoint)
        serve(endpoint, stop, config.duration_s)
    finally:
        stopped = _stop(endpoint)  # the log is written even when the loop died: rows kept
        failure = "; ".join(
            f for f in (stopped, _write_onboard_log(endpoint, config.log_path)) if f
        )
    if failure:
        print(f"{PROG}: error: {failure}", file=sys.stderr)
        return 1
    stats = endpoint.stats
    print(
        f"{PROG}: stopped at t = {endpoint.state.t_s:.1f} s sim; received "
        f"{stats.messages_received} messages, rejected {stats.garbage_datagrams} garbage "
        f"datagrams and {stats.setpoints_rejected} setpoints; caught up "
        f"{stats.caught_up_ms} ms after stalls, dropped time {stats.loop_overruns} times",
        flush=True,
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
