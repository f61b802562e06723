"""The whole diagnosis (docs/design.md section 8) as one pure function of logs and config.

1. Identifiability checks drop causes the data cannot support (:mod:`.identifiability`).
2. Airframe causes: forward selection on the force residual (:mod:`.selection`).
3. Command-path causes: replay search on top of the force-extended config (:mod:`.command_path`).
4. Held-out replay of the config and of the extended config measures the gain, and so does
   closed-loop tracking of the logged setpoints (:mod:`.closed_loop`).
5. What stays large without a generalising cause is reported as ``unexplained`` (a stochastic
   disturbance such as gusts), and so is a held-out replay error that stays well above the log's
   own noise floor (:mod:`.noise_floor`): the report never says "the config explains the logs"
   beside a large error, and warns of that replay error also when the force residual is
   already ``unexplained``. With nothing to report the ranking starts with ``none``.
6. Honesty: causes that could not be examined (no thrust, no ground holds, ...) are listed in
   ``not_examined``; fits on a search bound in ``at_bound`` (never named).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.ndimage import uniform_filter1d

from diagnosis.candidates import FORCE_CAUSES
from diagnosis.cause import Cause, flatten_params
from diagnosis.closed_loop import NEAR_GROUND_ALT_M, ClosedLoopResult, closed_loop
from diagnosis.command_path import (
    COMMAND_CAUSES,
    FLIGHT_CONTROL,
    ReplayThresholds,
    configured,
    select_command_causes,
)
from diagnosis.force_model import (
    BatteryModel,
    flight_time_from_voltage,
    gust_intensity_mps,
    predicted_residual,
)
from diagnosis.forces import GRAVITY_MPS2, ForceData, ForceDataError, force_data, with_thrust_n
from diagnosis.identifiability import FLIGHT_FOR, NotIdentifiable, check_identifiability
from diagnosis.noise_floor import white_noise_std
from diagnosis.replay import ReplayResult, replay, windows
from diagnosis.selection import (
    ForceSelection,
    SelectionConfig,
    select_causes,
    train_test_masks,
)
from diagnosis.thrust_response import (
    THRUST_RESPONSE_CAUSES,
    produced_thrust,
    select_thrust_response,
)
from diagnosis.warm_up import LEAD_IN_S
from flightlog.schema import FlightLog
from flightlog.ulog import damage_note, rows_left_out_note
from flightlog.vehicle_identity import airframe_mismatch, mixed_vehicle_fields
from vehicle_sim import SimConfig
from vehicle_sim.effects import EFFECT_CLASSES, BatterySag
from vehicle_sim.effects.base import effect_as_mapping

Progress = Callable[[str], None]
AT_BOUND_WARN_FRACTION = 0.25  # a fit on its bound that explains this much is worth a headline
# A force cause is kept if the held-out replay with it is at most this much worse than without:
# slow thrust effects (battery sag) barely move a noisy replay, whose controller compensates them;
# a wrong cause (a thrust telemetry error fitted as payload) makes it 30 % worse.
REPLAY_WORSE_TOLERANCE = 0.05


@dataclass(frozen=True)
class DiagnosisConfig:
    """Knobs of the diagnosis.

    Attributes:
        selection: held-out split and thresholds of the force selection.
        window_s: replay window length [s].
        search_log_s: log time [s] whose training windows the command-path search replays.
        replay: acceptance thresholds of command-path causes.
        unexplained_force_fraction: held-out force residual RMS [fraction of the weight] above
            which what is left is reported as ``unexplained``.
        persistence_s: moving-average window [s] applied to that residual first, so white
            sensor noise does not count as a disturbance.
        unexplained_replay_ratio: the extended held-out replay RMSE above this multiple of the
            replay noise floor (and above the force-free floor of 0.05 m/s) is ``unexplained``.
    """

    selection: SelectionConfig = field(default_factory=SelectionConfig)
    window_s: float = 2.0
    search_log_s: float = 60.0
    replay: ReplayThresholds = field(default_factory=ReplayThresholds)
    unexplained_force_fraction: float = 0.01
    persistence_s: float = 1.0
    unexplained_replay_ratio: float = 3.0


@dataclass(frozen=True, kw_only=True)
class Diagnosis:
    """Outcome of :func:`diagnose`.

    Attributes:
        causes: ranked, strongest first (accepted causes first, in order of acceptance).
        verdict: names of the accepted causes (and ``unexplained``), () if none.
        added_effects: effects (name -> parameters) the extended config adds or replaces.
        baseline, extended: held-out replay of the config and of the extended config.
        closed_loop: closed-loop tracking by both, scored on the held-out rows.
        not_identifiable: causes the data cannot support.
        force: airborne rows with the force residual (None without a thrust column).
        base_effects, final_effects: the config's effects and the extended ones.
        battery: voltage model of the config.
        noise_floor: the log's own noise: ``force_n`` (3,) std of the white force residual per
            NED axis [N], ``vel_mps`` (3,) std of the white velocity noise [m/s] and
            ``replay_rmse_mps``, the replay RMSE that noise alone leaves [m/s].
        explained_of_explainable: fraction of the force residual above the noise floor that the
            named causes remove (None without a force residual).
        warnings: sentences the report must show in its headline.
        thrust_sources: per log, where its thrust came from (see ``forces.with_thrust_n``).
    """

    causes: tuple[Cause, ...]
    verdict: tuple[str, ...]
    added_effects: dict[str, dict[str, object]]
    baseline: ReplayResult
    extended: ReplayResult
    closed_loop: ClosedLoopResult
    not_identifiable: tuple[NotIdentifiable, ...]
    force: ForceData | None
    base_effects: dict[str, dict[str, object]]
    final_effects: dict[str, dict[str, object]]
    battery: BatteryModel
    noise_floor: dict[str, object] = field(default_factory=dict)
    explained_of_explainable: float | None = None
    warnings: tuple[str, ...] = ()
    thrust_sources: tuple[str, ...] = ()

    @property
    def not_examined(self) -> tuple[str, ...]:
        """Causes the logs could not examine (each with why in ``not_identifiable``)."""
        return tuple(n.name for n in self.not_identifiable)

    @property
    def at_bound(self) -> tuple[str, ...]:
        """Causes whose best fit sits on a search bound (not named)."""
        return tuple(c.name for c in self.causes if c.at_bound)

    @property
    def gain(self) -> float:
        """Baseline / extended held-out replay velocity RMSE (1 when nothing was added; NaN
        when the replay was not examined: no held-out window, so no gain was measured)."""
        if not np.isfinite(self.baseline.rmse_mps()):
            return float("nan")
        if not self.added_effects:
            return 1.0
        return self.baseline.rmse_mps() / max(self.extended.rmse_mps(), 1e-9)


def diagnose(
    logs: Sequence[FlightLog],
    sim_config: SimConfig,
    config: DiagnosisConfig = DiagnosisConfig(),
    progress: Progress = lambda msg: None,
) -> Diagnosis:
    """Diagnose what ``sim_config`` gets wrong about the vehicle that flew ``logs``."""
    vehicle = sim_config.vehicle
    max_thrust_n = len(vehicle.rotor_spin) * vehicle.max_rotor_thrust_n
    thrust = [
        with_thrust_n(
            log,
            max_thrust_n,
            vehicle.thrust_coeff_n_per_radps2,
            len(vehicle.rotor_spin),
            sim_config.mass_kg,
        )
        for log in logs
    ]
    logs = [log for log, _ in thrust]
    thrust_sources = tuple(source for _, source in thrust)
    for i, source in enumerate(thrust_sources):
        progress(f"log {i + 1} thrust: {source}")
    base_names = {e.name for e in sim_config.effects}
    battery = BatteryModel(vehicle.battery_full_v, vehicle.battery_empty_v)
    not_ident = check_identifiability(logs, base_names, battery)
    excluded = {n.name for n in not_ident}
    for n in not_ident:
        progress(f"not identifiable: {n.name} ({n.reason})")
    base = {e.name: effect_as_mapping(e) for e in sim_config.effects}
    causes: list[Cause] = []
    rejected: list[Cause] = []
    effects = {k: dict(v) for k, v in base.items()}
    data = None
    selection = None
    force_names = [n for n in FORCE_CAUSES if n not in excluded]
    if force_names:
        data = force_data(logs, sim_config.mass_kg)
        _require_held_out_rows(data, config.selection.block_s)
        progress(f"force residual: {data.n_rows} airborne rows")
        selection = select_causes(data, base, battery, force_names, config.selection, progress)
        effects = _complete(selection.effects, data, battery)
        causes, rejected = _force_causes(selection, effects)
    added = _added(base, effects)
    force_config = configured(sim_config, added)
    wins = windows(logs, config.window_s)
    block = config.selection.block_s
    test = [w for w in wins if (int(w.t_anchor_s // block) + w.log_index) % 2 == 1]
    train = [w for w in wins if w not in test]
    search = [w for w in train if w.t_anchor_s < config.search_log_s]
    progress(f"replay: {len(train)} training and {len(test)} held-out windows")
    vel_noise = _velocity_noise(logs)
    replay_floor_mse = float(np.sum(vel_noise**2))
    baseline = replay(sim_config, logs, test)
    current = replay(force_config, logs, test) if added else baseline
    progress(
        f"baseline held-out replay RMSE {baseline.rmse_mps():.4f} m/s"
        if test
        else "replay not examined: no held-out window"
    )
    moved: list[Cause] = []
    force_fits = ({c.name: c for c in causes}, {k: dict(v) for k, v in effects.items()})
    if added:
        causes, moved, effects, current = _physics_check(
            sim_config, logs, test, causes, effects, base, current, baseline, progress
        )
        rejected += moved
        force_config = configured(sim_config, _added(base, effects))
    current, accepted, tried = select_command_causes(
        force_config,
        logs,
        search,
        test,
        current,
        baseline,
        effects,
        [n for n in COMMAND_CAUSES if n not in excluded],
        config.replay,
        progress,
        replay_floor_mse,
        regression=train,
    )
    causes += accepted
    if FLIGHT_CONTROL in effects and moved:
        restored, effects, current = _recheck_with_fitted_control(
            sim_config, logs, test, moved, force_fits, effects, base, current, progress
        )
        causes += restored
        rejected = [c for c in rejected if c.name not in {r.name for r in restored}]
    by_thrust = [c.name for c in tried if c.name in THRUST_RESPONSE_CAUSES]
    if by_thrust and produced_thrust(thrust_sources):
        response_config = configured(sim_config, _added(base, effects))
        named, not_named = select_thrust_response(
            response_config, logs, search, test, vel_noise, by_thrust
        )
        for c in named + not_named:
            progress(f"  {c.name} from the thrust response: {c.params} ({c.evidence})")
        tried = [c for c in tried if c.name not in by_thrust] + not_named
        for c in named:
            causes.append(c)
            effects[c.name] = dict(c.params)
        if named:
            current = replay(configured(sim_config, _added(base, effects)), logs, test)
    tried = [
        replace(c, evidence=f"{c.evidence}; not named; to tell it apart, fly: {FLIGHT_FOR[c.name]}")
        if c.name in FLIGHT_FOR
        else c
        for c in tried
    ]
    rejected = [c for c in rejected if c.name not in {t.name for t in tried}] + tried
    added = _added(base, effects)
    extended = current
    progress("closed-loop tracking of the logged setpoints")
    extended_config = configured(sim_config, added)
    tracking = closed_loop(sim_config, extended_config, logs, test)
    verdict = [c.name for c in causes]
    if selection is not None and data is not None:
        named = [c.name for c in causes if c.name in FORCE_CAUSES]
        extra = _unexplained(selection, data, base, effects, named, battery, config)
        if extra is not None:
            causes.append(extra)
            verdict.append(extra.name)
    mismatch = airframe_mismatch(dict(sim_config.px4_params), logs)
    warnings: list[str] = [mismatch] if mismatch else []
    floor_rmse = float(np.sqrt(replay_floor_mse))
    left_rmse = extended.rmse_mps()
    limit = max(config.unexplained_replay_ratio * floor_rmse, 0.05)
    if np.isfinite(left_rmse) and left_rmse > limit:
        ratio = left_rmse / max(floor_rmse, 1e-9)
        named = [n for n in verdict if n != "unexplained"]
        after = f"after the causes named ({', '.join(named)})" if named else "with no cause named"
        evidence = (
            f"held-out replay velocity RMSE {left_rmse:.3f} m/s stays {ratio:.1f}x "
            f"the log's noise floor ({floor_rmse:.3f} m/s) {after}: the "
            "simulation does not reproduce this flight (another controller, an effect outside "
            "the vocabulary, or disturbances)"
        )
        if "unexplained" not in verdict:  # else the force residual's row already names it
            left = min((left_rmse / max(baseline.rmse_mps(), 1e-12)) ** 2, 1.0)
            causes.append(Cause("unexplained", {"replay_rmse_mps": left_rmse}, 0.0, left, evidence))
            verdict.append("unexplained")
        warnings.append(evidence)
    if not test:
        warnings.append(
            f"replay not examined: no airborne run of more than {config.window_s + LEAD_IN_S:g} s "
            "in which the logged command drives the vehicle (OFFBOARD, or a position-controlled "
            "PX4 mode); fly longer position-controlled segments"
        )
    if test and tracking.segments and not tracking.scored.any():
        why = (
            f"{tracking.reanchored} of {tracking.segments} segments re-anchored: the config's "
            "vehicle touched down where the real one flew; check its mass and thrust"
            if tracking.reanchored
            else f"the held-out rows are all ground holds below {NEAR_GROUND_ALT_M} m"
        )
        warnings.append(
            f"closed-loop tracking not examined: no held-out row of a whole flight segment ({why})"
        )
    warnings += [note for note in map(damage_note, logs) if note]
    warnings += [note for note in map(rows_left_out_note, logs) if note]
    mixed = mixed_vehicle_fields(logs)
    if mixed:
        warnings.append(
            f"the logs are from different vehicles or configs ({'; '.join(mixed)}); one "
            "diagnosis fits one config to all of them: diagnose each vehicle's logs on their own"
        )
    if not_ident:
        warnings.append(
            "not examined (the logs cannot identify them): " + ", ".join(n.name for n in not_ident)
        )
    for c in (*causes, *rejected):
        if c.at_bound and c.explained_fraction > AT_BOUND_WARN_FRACTION:
            warnings.append(f"{c.name}: fit at the bound (search wider / the cause may be another)")
    if not verdict:
        nothing = "no candidate cause generalises to held-out data above the noise floor"
        causes.insert(0, Cause("none", {}, 0.0, 1.0, nothing))
    rejected.sort(key=lambda c: -c.explained_fraction)
    ranked = (
        causes
        + rejected
        + [
            Cause(n.name, {}, 0.0, 0.0, f"not identifiable: {n.reason}; fly: {n.flight}")
            for n in not_ident
        ]
    )
    noise_floor: dict[str, object] = {
        "vel_mps": [float(v) for v in vel_noise],
        "replay_rmse_mps": floor_rmse,
    }
    if selection is not None:
        noise_floor["force_n"] = list(selection.noise_std_n)
    return Diagnosis(
        causes=tuple(ranked),
        verdict=tuple(verdict),
        added_effects=added,
        baseline=baseline,
        extended=extended,
        closed_loop=tracking,
        not_identifiable=not_ident,
        force=data,
        base_effects=base,
        final_effects=effects,
        battery=battery,
        noise_floor=noise_floor,
        explained_of_explainable=(
            selection.explained_of_explainable() if selection is not None else None
        ),
        warnings=tuple(warnings),
        thrust_sources=thrust_sources,
    )


def _velocity_noise(logs: Sequence[FlightLog]) -> np.ndarray:
    """(3,) std of the white velocity noise in the logs [m/s] (:func:`white_noise_std`)."""
    vel = np.vstack([log.stack("vel_n_mps", "vel_e_mps", "vel_d_mps") for log in logs])
    seg = np.concatenate([np.full(log.n_rows, i) for i, log in enumerate(logs)])
    return white_noise_std(vel, seg)


def _physics_check(sim_config, logs, test, causes, effects, base, current, baseline, progress):
    """Keep a force cause only if the held-out replay is not worse with it (within
    ``REPLAY_WORSE_TOLERANCE``; issue 18: a fit of the force residual that makes the vehicle fly
    worse is not the vehicle's dynamics).

    A payload that fails this is a thrust telemetry error: with the logged thrust c times the
    true one, m (a - g) = F_T / c + D, which the payload fit reads as mass_ratio = c; it changes
    the force residual but not how the vehicle flies. It is named ``thrust_scale`` with
    ``logged_over_true`` = c.
    ``baseline``: the held-out replay of ``sim_config`` (the replay without the only cause).
    Returns (kept causes, moved-out causes, effects, held-out replay of the kept effects).
    """
    kept, moved = [], []
    effects = {k: dict(v) for k, v in effects.items()}
    for cause in causes:
        without = {k: dict(v) for k, v in effects.items() if k != cause.name}
        if cause.name in base:
            without[cause.name] = dict(base[cause.name])
        added_without = _added(base, without)
        other = (
            replay(configured(sim_config, added_without), logs, test) if added_without else baseline
        )
        if current.rmse_mps() <= (1.0 + REPLAY_WORSE_TOLERANCE) * other.rmse_mps():
            kept.append(cause)
            continue
        progress(f"physics check: {cause.name} does not improve the replay; not named")
        note = (
            f"; fits the force residual but the replay is not better with it "
            f"({other.rmse_mps():.4f} -> {current.rmse_mps():.4f} m/s): not named"
        )
        moved.append(replace(cause, evidence=cause.evidence + note, confidence=0.0))
        if cause.name == "payload":
            rho = float(cause.params.get("mass_ratio", 1.0))
            kept.append(
                Cause(
                    "thrust_scale",
                    {"logged_over_true": rho},
                    cause.explained_fraction,
                    cause.confidence,
                    "the logged thrust is off by this factor: the force residual looks like a "
                    f"payload (mass ratio {rho:.3f}) but the replay does not get better with it "
                    f"({other.rmse_mps():.4f} vs {current.rmse_mps():.4f} m/s); "
                    "recalibrate the thrust telemetry",
                    cause.statistic,
                )
            )
        effects, current = without, other
    return kept, moved, effects, current


def _force_causes(
    selection: ForceSelection, final: dict[str, dict[str, object]]
) -> tuple[list[Cause], list[Cause]]:
    accepted, rejected = [], []
    for s in selection.scores:
        fitted = final if s.accepted else s.effects
        params = flatten_params(fitted.get(s.name, {}))
        fit_with = EFFECT_CLASSES[s.name].FIT_WITH
        if fit_with is not None and fit_with in fitted:
            params.update(flatten_params(fitted[fit_with]))
        if s.accepted:
            verb = "named"
        elif s.at_bound:
            verb = "at the bound (search wider / the cause may be another)"
        else:
            verb = (
                "not named: does not generalise enough above the noise floor; to tell it "
                f"apart, fly: {FLIGHT_FOR.get(s.name, 'a longer flight')}"
            )
        p = f", p {s.significance.p_value:.3g}" if s.significance is not None else ""
        cause = Cause(
            s.name,
            params,
            max(0.0, s.explained_fraction),  # one that made the error larger explains nothing
            max(0.0, s.step_gain_fraction),
            f"held-out force residual RMS {s.before_rms_n:.3f} -> {s.after_rms_n:.3f} N "
            f"({verb}{p})",
            s.significance.as_dict() if s.significance is not None else None,
            s.at_bound,
        )
        (accepted if s.accepted else rejected).append(cause)
    return accepted, rejected


def _complete(
    effects: dict[str, dict[str, object]], data: ForceData, battery: BatteryModel
) -> dict[str, dict[str, object]]:
    """Fill the parameters the force fit does not estimate: battery_sag's endurance from the
    logged voltage (within its valid range), the others with the effect's defaults."""
    out = {k: dict(v) for k, v in effects.items()}
    if "battery_sag" in out and "full_flight_time_s" not in out["battery_sag"]:
        spec = next(p for p in BatterySag.PARAMS if p.name == "full_flight_time_s")
        endurance = flight_time_from_voltage(data, battery) or BatterySag.full_flight_time_s
        out["battery_sag"]["full_flight_time_s"] = float(np.clip(endurance, spec.lo, spec.hi))
    for name, params in out.items():
        defaults = effect_as_mapping(EFFECT_CLASSES[name]())
        out[name] = {**params, **{k: v for k, v in defaults.items() if k not in params}}
    return out


def _recheck_with_fitted_control(
    sim_config, logs, test, moved, force_fits, effects, base, current, progress
):
    """Give the force causes the physics check moved out a second look once ``flight_control``
    is named: under a controller the config gets wrong, the replay errs by the controller and a
    true drag can make it worse (seen: body drag with other velocity gains, 0.42 -> 0.44 m/s);
    with the fitted gains it is judged as in :func:`_physics_check`. ``force_fits``: the force
    causes and effects before that check. Returns (restored causes, effects, held-out replay)."""
    originals, fitted = force_fits
    restored = []
    effects = {k: dict(v) for k, v in effects.items()}
    for cause in moved:
        if cause.name == "payload" or cause.name not in originals or cause.name not in fitted:
            continue  # a payload the check moved out is named thrust_scale instead
        trial = {**effects, cause.name: dict(fitted[cause.name])}
        with_it = replay(configured(sim_config, _added(base, trial)), logs, test)
        if with_it.rmse_mps() <= (1.0 + REPLAY_WORSE_TOLERANCE) * current.rmse_mps():
            progress(f"physics check with the fitted control: {cause.name} named")
            restored.append(originals[cause.name])
            effects, current = trial, with_it
    return restored, effects, current


def _require_held_out_rows(data: ForceData, block_s: float) -> None:
    """ForceDataError (one line) unless the airborne rows fall in both training and held-out
    blocks (selection.train_test_masks): a flight too short for that has nothing to judge a
    cause on, and its held-out force residual would be an empty array."""
    train, test = train_test_masks(data, block_s)
    if not (train.any() and test.any()):
        raise ForceDataError(
            f"too little flight to hold any out: the {data.n_rows} airborne rows all fall in "
            f"{'training' if train.any() else 'held-out'} blocks (the diagnosis alternates "
            f"{block_s:g} s blocks of each); use a longer flight (more than {2 * block_s:g} s "
            "in the air)"
        )


def _added(
    base: dict[str, dict[str, object]], effects: dict[str, dict[str, object]]
) -> dict[str, dict[str, object]]:
    return {k: v for k, v in effects.items() if base.get(k) != v}


def _unexplained(
    selection: ForceSelection,
    data: ForceData,
    base: dict[str, dict[str, object]],
    effects: dict[str, dict[str, object]],
    named: list[str],
    battery: BatteryModel,
    config: DiagnosisConfig,
) -> Cause | None:
    """``unexplained`` if the held-out force residual left over by ``effects`` (the config's
    ``base`` and the force causes ``named``), averaged over ``config.persistence_s`` to drop
    white sensor noise, stays above the threshold."""
    _, test_mask = train_test_masks(data, config.selection.block_s)
    test = data.take(test_mask)
    left = test.resid_ned_n - predicted_residual(effects, test, battery)
    before = test.resid_ned_n - predicted_residual(base, test, battery)
    dt = float(np.median(np.diff(test.t_s))) if test.n_rows > 1 else 1.0
    size = max(1, round(config.persistence_s / dt))
    smooth = np.vstack(
        [
            uniform_filter1d(left[test.segment == s], size, axis=0, mode="nearest")
            for s in np.unique(test.segment)
        ]
    )
    noise = np.asarray(selection.noise_std_n)
    # white noise averaged over ``size`` rows keeps sigma^2 / size per axis: not a disturbance
    mean_sq = float(np.mean(np.sum(smooth * smooth, axis=1)) - np.sum(noise**2) / size) / 3.0
    rms = float(np.sqrt(max(mean_sq, 0.0)))
    weight = data.mass_kg * GRAVITY_MPS2
    if rms < config.unexplained_force_fraction * weight:
        return None
    params = {"rms_force_n": rms}
    gust = gust_intensity_mps(effects, data, battery)
    if gust is not None:
        params["gust_intensity_mps"] = gust
    share = min(float(np.sum(left * left)) / max(float(np.sum(before * before)), 1e-12), 1.0)
    after = f"after the causes named ({', '.join(named)})" if named else "with no force cause named"
    return Cause(
        "unexplained",
        params,
        0.0,
        share,
        f"held-out force residual RMS {rms:.3f} N ({100 * rms / weight:.1f} % of the weight, "
        f"averaged over {config.persistence_s} s) stays {after}: {100 * share:.0f} % of the "
        "config's held-out squared error is left; a disturbance such as gusts, or a vehicle the "
        "config does not describe (another airframe or controller, its mass or thrust, an "
        "effect outside the vocabulary)",
    )
