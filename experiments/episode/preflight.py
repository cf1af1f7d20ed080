"""Everything a batch of episodes names, built once before any episode is dispatched: a value
that racf or a user's plug-in refuses stops the batch with one line (a
:class:`~racf.errors.UserError`), not a worker's traceback after minutes of episodes.

Each distinct episode is also planned (pure, no simulator): a run-up its sign does not allow, a car
stage the mission names that is not registered, and a column a car stage or a world manager
declares that the step log already holds are refused here, not inside the episode."""

from __future__ import annotations

import dataclasses
import json

from racf.errors import UserError
from racf.experiments.car.estimators import make_estimator
from racf.experiments.episode.plan import plan_episode
from racf.experiments.episode.record import stage_columns, world_columns
from racf.experiments.episode.spec import TrialSpec
from racf.experiments.episode.stack import car_keys, wrap_attacks
from racf.plugins import CAR_STAGES, PluginError
from racf.sim.attacks.base import blank_env

__all__ = ["check_specs", "check_plan"]


def check_specs(specs: list[TrialSpec]) -> None:
    """Builds each distinct estimator (with its options) and attack stack (with its parameters and
    schedule) of ``specs``, and opens a session with each defence service they name; UserError
    names the first that fails and why."""
    estimators, attacks, services, plans = {}, {}, {}, {}
    for spec in specs:
        plans.setdefault(_key(dataclasses.replace(spec, seed=0).to_dict()), spec)
        estimators.setdefault(_key(spec.estimator, spec.estimator_options), spec)
        if spec.estimator_endpoint is not None:
            services.setdefault(_key(spec.estimator_endpoint, spec.estimator, spec.estimator_options), spec)
        if spec.attacks:
            attacks.setdefault(_key(spec.attacks, spec.attack_params, spec.t_atk, spec.rho,
                                    spec.attack_stable_steps), spec)
    for spec in plans.values():
        check_plan(spec)
    for spec in estimators.values():
        try:
            make_estimator(spec.estimator, spec.estimator_options)
        except PluginError:
            raise
        except Exception as err:  # a plug-in's constructor may raise anything: name it, one line
            raise UserError(f"estimator {spec.estimator!r} with options {spec.estimator_options} cannot be built: "
                            f"{_words(err)}") from None
    for spec in services.values():  # the service is there and serves the defence (it warms it now)
        from racf.experiments.link.remote import RemoteEstimator

        RemoteEstimator(spec.estimator_endpoint, spec.estimator, spec.estimator_options,
                        spec.estimator_timeout_ms, keys=car_keys(spec)).close()
    for spec in attacks.values():
        try:
            wrap_attacks(blank_env(), spec).close()
        except PluginError:
            raise
        except Exception as err:
            params = f" with {spec.attack_params}" if spec.attack_params else ""
            raise UserError(f"attack(s) {'+'.join(spec.attacks)}{params} and schedule (duration_s={spec.t_atk}, "
                            f"stable_steps={spec.attack_stable_steps}) cannot be built: {_words(err)}") from None


def check_plan(spec: TrialSpec) -> None:
    """Plans ``spec``'s episode and checks what the plan declares (the mission's car stages, their
    columns, the world managers' columns) against the step log; UserError names what is wrong."""
    where = f"episode {spec.trial_id.rsplit('_', 1)[0]} cannot be planned"
    try:
        plan = plan_episode(spec)
    except (PluginError, UserError):
        raise
    except ValueError as err:
        raise UserError(f"{where}: {err}") from None
    except Exception:  # a plug-in's bug, not a value: the episode reports it, naming the plug-in and its traceback
        return
    stages = [CAR_STAGES.plugin(name).obj for name in plan.mission.stages]
    try:
        stage_columns(stages)
        world_columns(plan.env_kwargs.get("world", ()))
    except ValueError as err:
        raise UserError(f"{where}: {err}") from None


def _key(*parts) -> str:
    return json.dumps(parts, sort_keys=True, default=str)


def _words(err: Exception) -> str:
    return str(err) if isinstance(err, ValueError) else f"{type(err).__name__}: {err}"
