"""The small picklable description an environment is rebuilt from (`EnvSpec`)."""

from __future__ import annotations

import dataclasses
import json
import math
from typing import Any, Mapping, Sequence

OBSERVATIONS = ("candidates", "map", "graph")
#: The version of a pickled spec's layout (checked when it is unpickled).
SPEC_VERSION = 1
NEEDS = ("layout_gain", "layout")


@dataclasses.dataclass(frozen=True)
class EnvSpec:
    """Everything an environment is made of: plain data, picklable, so that a process pool or
    Ray's env runners can rebuild the same environment elsewhere (`spec.make()`).

    Attributes:
        buildings: where the buildings come from, one source or a list of them. A source is a
            building file (floorcast TOML, floor-plan XML, map_server YAML, Stage .world), a
            glob (``"maps/plans/*.xml"``), a suite's name (``"real-offices"``: looked for in
            ``$FLOORCAST_SUITES``, ``./suites`` and the clone the package was built from) or
            manifest path, or a generator spec ``"generate:KIND:AREA_M2:SEEDS"`` (KIND
            ``school`` or ``office``, AREA_M2 100 to 50000, SEEDS ``7`` or ``1-20``).
        settings: floorcast's run settings by name (``floorcast settings`` lists them with
            units, defaults and ranges), e.g. ``{"localization": "ground-truth", "time_limit_s":
            1800}``. Default: floorcast's defaults (SLAM with laser and odometry noise).
        observation: ``"candidates"`` (default), ``"map"`` or ``"graph"``.
        max_candidates: candidates mode: the padded length K (1 to 4096, default 32); a
            decision with more shows the K nearest by path.
        needs: what floorcast computes besides the baseline gains: ``"layout_gain"`` (each
            candidate's gain inside the predicted rooms) and/or ``"layout"`` (the predicted
            rooms: the feature ``in_robot_room``). Each costs time. Default: none.
        map_size: map mode: the crop's side in cells (8 to 1024, default 64).
        map_cell_m: map mode, egocentric: a crop cell's side (m, 0.01 to 10, default 0.5).
        map_frame: map mode: ``"egocentric"`` (default: centred on the robot's estimated
            position, axis-aligned) or ``"global"`` (the whole map, scaled to fit).
        graph_nodes: graph mode: N, the nodes padded to (2 to 4096, default 360, ARiADNE's).
        graph_k: graph mode: K, the edges per node (2 to 64, default 20, ARiADNE's).
        graph_spacing_m: graph mode: the node lattice's spacing (m, 0.1 to 20, default 1.5).
        graph_range_m: graph mode: how far a node sees frontier points for its utility (m, 0.1
            to 100; default ``None``: seven eighths of the laser's range).
        start: ``"building"`` (default: the building's own start, as ``floorcast explore``) or
            ``"random"`` (drawn from the episode's seed, as a grid's random starts).
        split: ``None`` (default: every building), ``"train"`` or ``"test"``: the fixed split
            by each building's content hash (about 20 % test), the same on every machine.
        base: the built-in strategy whose candidates, gains and stopping rules the policy
            chooses among (default ``"baseline"``, as for an external strategy program).
        label: the strategy's name in the run summaries (default ``"python-policy"``).
    """

    buildings: str | Sequence[str]
    settings: Mapping[str, Any] | None = None
    observation: str = "candidates"
    max_candidates: int = 32
    needs: Sequence[str] = ()
    map_size: int = 64
    map_cell_m: float = 0.5
    map_frame: str = "egocentric"
    graph_nodes: int = 360
    graph_k: int = 20
    graph_spacing_m: float = 1.5
    graph_range_m: float | None = None
    start: str = "building"
    split: str | None = None
    base: str = "baseline"
    label: str = "python-policy"

    def __post_init__(self):
        b = self.buildings
        if isinstance(b, str):
            object.__setattr__(self, "buildings", (b,))
        elif isinstance(b, (list, tuple)) and all(isinstance(x, str) for x in b) and b:
            object.__setattr__(self, "buildings", tuple(b))
        else:
            raise ValueError(
                f"buildings: {b!r}; expected a path, glob, suite name or generator spec, or a non-empty list of them"
            )
        if self.settings is not None and not isinstance(self.settings, Mapping):
            raise ValueError(f"settings: {self.settings!r}; expected a dict of settings by name")
        object.__setattr__(self, "settings", dict(self.settings or {}))
        if self.observation not in OBSERVATIONS:
            raise ValueError(
                f"observation: {self.observation!r}; expected one of {', '.join(OBSERVATIONS)}"
            )
        needs = (self.needs,) if isinstance(self.needs, str) else tuple(self.needs)
        for n in needs:
            if n not in NEEDS:
                raise ValueError(f"needs: {n!r}; expected a list of {', '.join(NEEDS)}")
        object.__setattr__(self, "needs", needs)
        for name, lo, hi in (("max_candidates", 1, 4096), ("map_size", 8, 1024), ("graph_nodes", 2, 4096), ("graph_k", 2, 64)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
                raise ValueError(f"{name}: {v!r}; expected an integer from {lo} to {hi}")
        for name, lo, hi, optional in (("map_cell_m", 0.01, 10, False), ("graph_spacing_m", 0.1, 20, False),
                                       ("graph_range_m", 0.1, 100, True)):
            c = getattr(self, name)
            if c is None and optional:
                continue
            if isinstance(c, bool) or not isinstance(c, (int, float)) or not math.isfinite(c) or not lo <= c <= hi:
                raise ValueError(f"{name}: {c!r}; expected a number from {lo} to {hi} (m)")

    def __reduce__(self):
        # Pickled as a versioned plain dict, checked when read back.
        fields = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        return (_load, (SPEC_VERSION, fields))

    def to_json(self) -> str:
        """The spec as the native module reads it."""
        d = dataclasses.asdict(self)
        d["buildings"] = list(self.buildings)
        d["needs"] = list(self.needs)
        return json.dumps(d)

    def make(self, **kwargs):
        """A new `ExploreEnv` of this spec (``kwargs``: ``reward``, ``render_mode``)."""
        from ._env import ExploreEnv

        return ExploreEnv(spec=self, **kwargs)


def spec_of(spec, localization, strategy_settings, kwargs) -> EnvSpec:
    """The spec an environment's arguments give: an `EnvSpec`, or its fields (``settings`` or
    its alias ``strategy_settings``; ``localization`` the shorthand for its setting)."""
    if spec is not None:
        if kwargs or localization is not None or strategy_settings is not None:
            raise ValueError("spec: give an EnvSpec or its fields, not both")
        return spec
    if strategy_settings is not None:
        if "settings" in kwargs:
            raise ValueError("settings: give settings or strategy_settings, not both")
        kwargs["settings"] = strategy_settings
    if localization is not None:
        kwargs["settings"] = dict(kwargs.get("settings") or {}, localization=localization)
    if "buildings" not in kwargs:
        raise ValueError("buildings: required (a path, glob, suite name or generator spec, or a list)")
    return EnvSpec(**kwargs)


def _load(version, fields):
    """A pickled spec, read back: its layout's version must be this package's."""
    if version != SPEC_VERSION:
        raise ValueError(
            f"EnvSpec: pickled with spec layout {version!r}; this floorcast reads {SPEC_VERSION}: "
            "rebuild the spec with this floorcast"
        )
    known = {f.name for f in dataclasses.fields(EnvSpec)}
    unknown = set(fields) - known
    if unknown:
        raise ValueError(f"EnvSpec: pickled with unknown fields {sorted(unknown)}")
    return EnvSpec(**fields)
