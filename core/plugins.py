"""The registries of racf's parts that a user can bring their own of: estimators (defences),
attacks, stop-sign detectors, scenarios, metrics and car stages.

Each registry is filled from one entry-point group of the installed distributions, racf's own
parts registering the same way as a user's:

=====================  ==========================================================  ==========
group                  an entry point names                                         registry
=====================  ==========================================================  ==========
``racf.estimators``    a ``DistanceEstimator`` class (``racf.controllers``)         ESTIMATORS
``racf.attacks``       an ``AttackWrapper`` subclass (``racf.sim.attacks``)         ATTACKS
``racf.detectors``     a class or factory whose objects have ``detect(rgb)``        DETECTORS
``racf.scenarios``     a ``Scenario`` subclass (``racf.experiments.scenarios``)     SCENARIOS
``racf.metrics``       a ``Metric`` subclass (``racf.experiments.metrics``)         METRICS
``racf.car_stages``    a ``CarStage`` subclass (``racf.experiments.car.stage``)     CAR_STAGES
=====================  ==========================================================  ==========

A user who has not packaged their code loads a file instead (``--plugin path/to/file.py`` on the
commands that run episodes, or :func:`load_plugin_file`): every class defined in it with a
``name`` and the shape of one of the three kinds is registered under that name. The files
loaded are remembered in ``RACF_PLUGINS`` (an environment variable), so the worker processes
a sweep spawns load them too.

A plug-in's source enters the ids of the results it makes (:meth:`Registry.source_id`): editing
it never lets a resumed run reuse a result the old code made. racf's own parts are covered by
the code version instead.

Example:
    >>> from racf.plugins import ATTACKS, ESTIMATORS
    >>> "odca" in ESTIMATORS and "depth_bias" in ATTACKS
    True
"""

from __future__ import annotations

import hashlib
import importlib.util
import inspect
import os
import sys
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from importlib.metadata import entry_points
from pathlib import Path
from typing import Any

from racf.errors import UserError
from racf.provenance import source_version

__all__ = ["Plugin", "PluginError", "Registry", "ESTIMATORS", "ATTACKS", "DETECTORS", "SCENARIOS", "METRICS", "CAR_STAGES", "REGISTRIES",
           "load_plugin_file", "plugin_files", "PLUGIN_ENV", "PART_KIND"]

#: The environment variable that lists the plug-in files this process and its workers load.
PLUGIN_ENV = "RACF_PLUGINS"
_OWN = "racf"


class PluginError(UserError):
    """A plug-in that cannot be loaded or used: the message names it and what is wrong."""


@dataclass(frozen=True)
class Plugin:
    """One registered part.

    Attributes:
        name: its key (what settings, specs and the CLI call it).
        obj: the class (or factory) that makes it.
        origin: ``racf``, the distribution that registered it, or the file it was loaded from.
        source: what its source is hashed from: None for racf's own (the code version covers
            it), else a module or package name, or a file's path.
    """

    name: str
    obj: Any
    origin: str
    source: str | None

    @property
    def builtin(self) -> bool:
        return self.origin == _OWN


class Registry(Mapping[str, Any]):
    """Parts of one kind by name, read from the entry-point group ``group`` on first use.

    It is a read-only mapping of name -> class (or factory), racf's own first, then the
    others, each by name; :meth:`register` adds one at run time.

    Args:
        group: the entry-point group.
        kind: what one part is called in messages (``estimator``, ``attack``, ``detector``).
        accepts: whether an object can be a part of this kind (a file plug-in's classes are
            sorted by it; an entry point that fails it is refused by name).
    """

    def __init__(self, group: str, kind: str, accepts: Callable[[Any], bool]) -> None:
        self.group, self.kind, self.accepts = group, kind, accepts
        self._plugins: dict[str, Plugin] | None = None
        self._broken: dict[str, str] = {}

    # --- the mapping -------------------------------------------------------------------------
    def __getitem__(self, name: str) -> Any:
        plugins = self._all()
        if name in self._broken:
            raise PluginError(self._broken[name])
        return plugins[name].obj

    def __iter__(self) -> Iterator[str]:
        return iter(self._all())

    def __contains__(self, name: object) -> bool:
        return name in self._all()

    def __len__(self) -> int:
        return len(self._all())

    def __repr__(self) -> str:
        return f"Registry({self.group!r}: {list(self)})"

    def names(self) -> tuple[str, ...]:
        """The names in the registry's order, importing no part not loaded yet (the entry points'
        names; plug-in files are loaded: only they know theirs). For flags' choices and help."""
        if self._plugins is not None or plugin_files():
            return tuple(self._all())
        found = sorted(entry_points(group=self.group), key=lambda ep: (not _is_own(ep), ep.name))
        return tuple(dict.fromkeys(ep.name for ep in found))

    # --- lookups -----------------------------------------------------------------------------
    @property
    def broken(self) -> dict[str, str]:
        """The installed parts that failed to load, by name, with what is wrong: left out of the
        registry (a command that needs one says so; the others run), listed by ``racf list``."""
        self._all()
        return dict(self._broken)

    def plugin(self, name: str) -> Plugin:
        """The part called ``name``; PluginError names the choices, or what is wrong with a broken one."""
        plugins = self._all()
        if name in self._broken:
            raise PluginError(self._broken[name])
        if name not in plugins:
            raise PluginError(f"unknown {self.kind} {name!r}; choose from {tuple(plugins)} "
                              f"(a plug-in registers under the entry-point group {self.group!r}, "
                              f"or is loaded with --plugin FILE.py)")
        return plugins[name]

    def source_id(self, name: str) -> str | None:
        """A hash of the part's source, read now (None for racf's own parts)."""
        plugin = self.plugin(name)
        if plugin.source is None:
            return None
        if plugin.source.startswith(_CODE):  # defined where no file holds it: versioned by its compiled code
            return f"{plugin.origin}:{plugin.source[len(_CODE):]}"

        return f"{plugin.origin}:{source_version(plugin.source)}"

    # --- registration ------------------------------------------------------------------------
    def register(self, obj: Any, name: str | None = None, *, origin: str | None = None) -> Plugin:
        """Adds ``obj`` under ``name`` (default: its ``name`` attribute) and returns its entry.

        Registering the same object again is a no-op; another object under a taken name is
        refused (PluginError), so a plug-in never silently replaces a part.
        """
        name = name or getattr(obj, "name", None)
        if not isinstance(name, str) or not name.isidentifier():
            raise PluginError(f"a {self.kind} needs a name that is an identifier (its 'name' attribute), "
                              f"got {name!r} for {obj!r}")
        if not self.accepts(obj):
            raise PluginError(f"{obj!r} is not {_an(self.kind)}: {_SHAPES[self.kind]}")
        plugins = self._all()
        if name in plugins:
            if plugins[name].obj is obj:
                return plugins[name]
            old = plugins[name]
            if old.origin == _INTERACTIVE and getattr(old.obj, "__qualname__", None) == getattr(obj, "__qualname__", ""):
                del plugins[name]  # the same class defined again in a session (edited): the new one replaces it
                return self.register(obj, name, origin=origin)
            raise PluginError(f"{self.kind} {name!r} is already registered by {plugins[name].origin}; "
                              f"choose another name")
        origin, source = _provenance(obj) if origin is None else (origin, _provenance(obj)[1])
        plugins[name] = Plugin(name, obj, origin, source)
        return plugins[name]

    def _all(self) -> dict[str, Plugin]:
        if self._plugins is None:
            found: dict[str, Plugin] = {}
            broken: dict[str, str] = {}
            # racf's own first, then the others; each by name: the same on every machine (and
            # the order attacks take in a setting's name).
            for ep in sorted(entry_points(group=self.group), key=lambda ep: (not _is_own(ep), ep.name)):
                if ep.name not in found and ep.name not in broken:  # seen twice on the path: the first wins
                    try:
                        found[ep.name] = self._load(ep)
                    except PluginError as err:  # one broken install must not stop what does not need it
                        broken[ep.name] = str(err)
                        _report_once(str(err))
            self._plugins, self._broken = found, broken
            try:
                for path in plugin_files():
                    load_plugin_file(path)
            except PluginError:
                self._plugins = None  # never a half-filled registry
                raise
        return self._plugins

    def _load(self, ep) -> Plugin:
        """One entry point's part; PluginError names a plug-in that fails to load or is no part."""
        dist = ep.dist.name if ep.dist is not None else "?"
        where = f"{self.kind} plug-in {ep.name!r} ({ep.value}, from {dist})"
        try:
            obj = ep.load()
        except Exception as err:  # a user's broken plug-in: name it, never a traceback
            raise PluginError(f"{where} failed to load: {type(err).__name__}: {err}") from None
        if inspect.isclass(obj) and getattr(obj, "name", ep.name) != ep.name:
            raise PluginError(f"{where} calls itself {obj.name!r}: the entry point's name and the class's "
                              f"'name' must agree")
        if not self.accepts(obj):
            raise PluginError(f"{where} is not {_an(self.kind)}: {_SHAPES[self.kind]}")
        return Plugin(ep.name, obj, dist, None if dist == _OWN else ep.module.split(".")[0])


def _report_once(message: str) -> None:
    """Says on stderr, once for a process and the workers it starts, that an installed part is left out."""
    said = os.environ.get(_REPORTED_ENV, "")
    key = hashlib.sha256(message.encode()).hexdigest()[:12]
    if key in said.split(","):
        return
    os.environ[_REPORTED_ENV] = ",".join(filter(None, [said, key]))
    print(f"racf: warning: {message}; it is left out (`racf list` shows it)", file=sys.stderr)


#: The broken installed parts this process (or the one that started it) has reported already.
_REPORTED_ENV = "RACF_REPORTED_BROKEN"


def _an(kind: str) -> str:
    return f"{'an' if kind[0] in 'aeiou' else 'a'} {kind}"


def _is_own(ep) -> bool:
    return ep.dist is not None and ep.dist.name == _OWN


def _provenance(obj: Any) -> tuple[str, str | None]:
    """Where a part registered at run time comes from, and what to hash for its source."""
    module = getattr(obj, "__module__", "") or ""
    top = module.split(".")[0]
    if top == _OWN:
        return _OWN, None
    if module in _FILE_MODULES:
        return _FILE_MODULES[module], _FILE_MODULES[module]
    file = getattr(sys.modules.get(module), "__file__", None)
    if top and top != "__main__" and importlib.util.find_spec(top) is not None and file:
        return top, top
    if file:
        return str(Path(file).resolve()), str(Path(file).resolve())
    # Defined in a notebook or exec'd code: no file to hash, so its compiled code is the version.
    return _INTERACTIVE, _CODE + _code_hash(obj)


def _code_hash(obj: Any) -> str:
    """A hash of a class's (or function's) compiled code and plain class attributes: the same
    code gives the same hash on any machine with the same Python."""
    import marshal

    h = hashlib.sha256()
    members = vars(obj).items() if inspect.isclass(obj) else [("", obj)]
    for key, value in sorted(members, key=lambda kv: kv[0]):
        function = getattr(value, "__func__", value)
        code = getattr(function, "__code__", None)
        if code is not None:
            h.update(key.encode() + marshal.dumps(code))
        elif isinstance(value, (str, int, float, bool, tuple)) and not key.startswith("__"):
            h.update(f"{key}={value!r}".encode())
    return h.hexdigest()[:16]


# --- the kinds --------------------------------------------------------------------------------
def _is_estimator(obj: Any) -> bool:
    return inspect.isclass(obj) and isinstance(getattr(obj, "name", None), str) and all(
        callable(getattr(obj, m, None)) for m in _ESTIMATOR_METHODS)


#: The class attribute a part's base class sets to the kind it is the base of (``AttackWrapper``:
#: ``attack``, ``Scenario``: ``scenario``, ``Metric``: ``metric``). The floor reads it from the class:
#: it never names, or imports, the packages above it.
PART_KIND = "racf_part"


def _subclass_of(kind: str) -> Callable[[Any], bool]:
    """Whether an object is a proper subclass of the base class that declares itself the base of
    ``kind`` (``racf_part = kind`` in its own body)."""
    def accepts(obj: Any) -> bool:
        return inspect.isclass(obj) and any(
            base is not obj and vars(base).get(PART_KIND) == kind for base in obj.__mro__[1:])
    return accepts


_is_attack = _subclass_of("attack")
_is_scenario = _subclass_of("scenario")
_is_metric = _subclass_of("metric")
_is_car_stage = _subclass_of("car stage")


def _is_detector(obj: Any) -> bool:
    if inspect.isclass(obj):
        return callable(getattr(obj, "detect", None))
    return callable(obj)


def _near_misses(module_name: str) -> str:
    """What the file's classes with a ``name`` lack, for the message: ``: class Foo (an estimator?)
    lacks would_pass()``; or the three shapes when none of its classes has a name."""
    module = sys.modules[module_name]
    said = []
    for cls_name, obj in inspect.getmembers(module, inspect.isclass):
        if obj.__module__ != module_name or not isinstance(getattr(obj, "name", None), str):
            continue
        missing = [m for m in _ESTIMATOR_METHODS if not callable(getattr(obj, m, None))]
        if len(missing) < len(_ESTIMATOR_METHODS):
            said.append(f"class {cls_name} (an estimator?) lacks {', '.join(m + '()' for m in missing)}")
        else:
            said.append(f"class {cls_name} has a 'name' but is none of: {'; '.join(_SHAPES.values())}")
    if not said:
        return f": it has no class with a 'name' attribute (one is needed, as in: {'; '.join(_SHAPES.values())})"
    return ": " + "; ".join(said)


_ESTIMATOR_METHODS = ("reset", "estimate", "diagnostics", "would_pass")

_SHAPES = {
    "estimator": "a class with a 'name' and reset(), estimate(sample, speed_mps, dt, yaw_rate_radps), "
                 "diagnostics() and would_pass(...) (racf.controllers.DistanceEstimator)",
    "attack": "a subclass of racf.sim.attacks.AttackWrapper with a 'name'",
    "detector": "a class (or factory) whose objects have detect(rgb) -> Detection | None",
    "scenario": "a subclass of racf.experiments.scenarios.Scenario with a 'name'",
    "metric": "a subclass of racf.experiments.metrics.Metric with a 'name'",
    "car stage": "a subclass of racf.experiments.car.stage.CarStage with a 'name'",
}

#: Every part a user can bring, by name.
ESTIMATORS = Registry("racf.estimators", "estimator", _is_estimator)
ATTACKS = Registry("racf.attacks", "attack", _is_attack)
DETECTORS = Registry("racf.detectors", "detector", _is_detector)
SCENARIOS = Registry("racf.scenarios", "scenario", _is_scenario)
METRICS = Registry("racf.metrics", "metric", _is_metric)
CAR_STAGES = Registry("racf.car_stages", "car stage", _is_car_stage)
REGISTRIES: dict[str, Registry] = {"estimator": ESTIMATORS, "attack": ATTACKS, "detector": DETECTORS,
                                   "scenario": SCENARIOS, "metric": METRICS, "car stage": CAR_STAGES}

_INTERACTIVE = "interactive"
_CODE = "code:"
#: Module name -> file of the plug-in files loaded in this process.
_FILE_MODULES: dict[str, str] = {}


def plugin_files() -> list[str]:
    """The plug-in files this process loads (``RACF_PLUGINS``, separated by ``os.pathsep``)."""
    return [p for p in os.environ.get(PLUGIN_ENV, "").split(os.pathsep) if p]


def load_plugin_file(path: str | os.PathLike) -> list[Plugin]:
    """Loads a Python file and registers every estimator, attack and detector class defined in
    it (classes with a ``name``); returns them. The file is added to ``RACF_PLUGINS`` so that
    worker processes load it too. PluginError: no such file, it fails to import, or it defines
    nothing racf can use."""
    file = Path(path).expanduser().resolve()
    what = ("no such file" if not file.exists() else "is a folder, not a file" if file.is_dir()
            else "is not a Python file (.py)" if file.suffix != ".py" else None)
    if what is not None:
        raise PluginError(f"--plugin {path}: {what}; give the path of a .py file that defines an estimator, an "
                          f"attack, a detector, a scenario, a metric or a car stage")
    module_name = f"racf_plugin_{file.stem}_{hashlib.sha256(str(file).encode()).hexdigest()[:8]}"
    if module_name not in sys.modules:
        spec = importlib.util.spec_from_file_location(module_name, file)
        module = importlib.util.module_from_spec(spec)
        sys.modules[module_name] = module
        _FILE_MODULES[module_name] = str(file)
        try:
            spec.loader.exec_module(module)
        except Exception as err:
            del sys.modules[module_name]
            raise PluginError(f"--plugin {path} failed to import: {type(err).__name__}: {err}") from None
    module = sys.modules[module_name]
    found = []
    for _, obj in inspect.getmembers(module, inspect.isclass):
        if obj.__module__ != module_name or not isinstance(getattr(obj, "name", None), str):
            continue
        for registry in REGISTRIES.values():
            if registry.accepts(obj):
                found.append(registry.register(obj, origin=str(file)))
                break
    if not found:
        raise PluginError(f"--plugin {path} defines no estimator, attack, detector, scenario, metric or car stage"
                          f"{_near_misses(module_name)}")
    listed = plugin_files()
    if str(file) not in listed:
        os.environ[PLUGIN_ENV] = os.pathsep.join([*listed, str(file)])
    return found
