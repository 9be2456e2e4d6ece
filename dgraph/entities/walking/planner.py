"""FootstepPlanner: one footstep plan, from the robot's standing sole placements and a walk description."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

import dgraph as dg
from dgraph.entities.estimators.leg_odometry import frame_id, standing_configuration
from dgraph.entities.robot.loading import has_free_flyer, load_model
from dgraph.entities.walking.footsteps import (
    GAITS,
    FootstepPlan,
    footstep_from_plain,
    lateral_walk,
    straight_walk,
    terrain_walk,
    turning_walk,
)
from dgraph.entities.walking.terrain import Terrain, flat

TIMING = ("single_support", "double_support", "initial_double_support", "final_double_support")
"""The durations every walk takes."""

WALK_PARAMETERS: dict[str, tuple[str, ...]] = {
    "straight": ("steps", "length", "width", "first_side", "half_first", "half_last", "terrain", "gait",
                 "lateral_offset", *TIMING),
    "lateral": ("steps", "length", "width", *TIMING),
    "turning": ("steps", "angle_per_step", "length", "width", "first_side", *TIMING),
    "explicit": ("footsteps", *TIMING),
}
"""The parameters each kind of walk reads (another one given is refused)."""

WALK_PARAMETER_NAMES = set().union(*WALK_PARAMETERS.values())


def sole_placements(model: Any, left_frame: str, right_frame: str) -> tuple[np.ndarray, np.ndarray]:
    """The 4x4 world placements of the two sole frames at the model's standing configuration
    (half-sitting with the lower sole on z = 0: the configuration the MuJoCo device starts in)."""
    import pinocchio as pin

    q = standing_configuration(model, (left_frame, right_frame))
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    return (data.oMf[model.getFrameId(left_frame)].homogeneous.copy(),
            data.oMf[model.getFrameId(right_frame)].homogeneous.copy())


@dg.register
class FootstepPlanner(dg.Entity):
    """One footstep plan (:class:`~dgraph.entities.walking.footsteps.FootstepPlan`), laid out from
    the sole placements of the robot standing at half-sitting with its soles on z = 0 (tick 0 of
    the MuJoCo device), and the plan time.

    ``walk``: ``straight`` (:func:`~dgraph.entities.walking.footsteps.straight_walk`: ``steps``
    steps of ``length`` and a closing step, the first and the closing one half steps by default;
    6 x 0.2 m advance 1.2 m, thesis L4679-4686), ``lateral`` (``lateral_walk``: ``steps``
    sideways steps of the signed ``length``, > 0 to the left), ``turning`` (``turning_walk``:
    ``steps`` steps turning by ``angle_per_step`` rad, advancing ``length``, default 0) or
    ``explicit`` (``footsteps``: a list of ``{side, position: [x, y, z], yaw (rad, default 0),
    single_support?, double_support?}``, the durations defaulting to the parameters, the last
    step's double support to ``final_double_support``). A straight walk on a ``terrain`` (a name
    of ``TERRAINS``, e.g. ``stairs10``, ``platforms``, ``obstacles``, as the device's scene of the
    same name, or a terrain's plain data) is
    :func:`~dgraph.entities.walking.footsteps.terrain_walk`'s: its footsteps on the surfaces, with
    their heights and tilts, laid by ``gait`` (``alternate``, or ``step_to``: both feet on each
    tread), moved ``lateral_offset`` m to the left. Plan time ``s = t dt - start``: the
    plan's phases are in plan time, tick ``start / dt`` is its time 0; the plan carries
    ``start``, so the entities that follow it (scheduler, pattern generator, swings, view) agree.

    Parameters: ``walk``, ``steps``, ``length`` (m; default: the builder's, 0.2 straight, 0
    turning; required for lateral), ``width`` (m between the feet, default: the robot's, 0.17 m
    on TALOS), ``first_side``, ``half_first``, ``half_last``, ``angle_per_step`` (rad),
    ``footsteps``, ``single_support`` (0.9 s), ``double_support`` (0.115 s),
    ``initial_double_support`` (1 s), ``final_double_support`` (1 s), ``start`` (s), ``model``,
    ``left_frame``, ``right_frame`` (the sole frames), ``terrain``, ``gait``, ``lateral_offset``, ``dt``. A parameter
    the chosen walk does not read, or a plan the builder refuses, is a ParamError naming the
    parameter.
    Outputs: ``plan`` (constant), ``walked_terrain`` (constant: the terrain, the floor alone
    if none is given), ``time`` (``t dt - start``, s).
    """

    walk = dg.Param("straight", kind="str", choices=("straight", "lateral", "turning", "explicit"),
                    doc="the kind of walk: straight, lateral, turning, or the explicit footsteps")
    steps = dg.Param(6, kind="int", minimum=1, doc="number of steps (straight: before the closing step)")
    length = dg.Param(None, kind="float", doc="step length in m (lateral: signed, > 0 to the left; default: the "
                                              "builder's, 0.2 straight, 0 turning)")
    width = dg.Param(None, kind="float", doc="distance between the feet in m (default: the standing robot's)")
    first_side = dg.Param(None, kind="str", choices=("left", "right"),
                          doc="foot that steps first (default: left; turning: the side of the turn)")
    half_first = dg.Param(True, kind="bool", doc="straight: the first step is a half step (a stride of length)")
    half_last = dg.Param(True, kind="bool", doc="straight: the closing step is a half step (feet side by side)")
    angle_per_step = dg.Param(None, kind="float", doc="turning: yaw per step in rad (> 0: to the left)")
    footsteps = dg.Param(None, kind="object", doc="explicit: [{side, position: [x, y, z], yaw, single_support?, "
                                                  "double_support?}, ...]")
    single_support = dg.Param(0.9, kind="float", doc="single support (swing) duration of a step in s (> 0)")
    double_support = dg.Param(0.115, kind="float", minimum=0.0, doc="double support after a touch-down in s")
    initial_double_support = dg.Param(1.0, kind="float", minimum=0.0, doc="double support before the first lift-off "
                                                                          "in s")
    final_double_support = dg.Param(1.0, kind="float", doc="double support after the last touch-down in s (> 0)")
    terrain = dg.Param(None, kind="object", doc="straight: the terrain walked on, a name (stairs10, platforms, "
                                                 "obstacles) or its plain data (default: the floor)")
    gait = dg.Param("alternate", kind="str", choices=GAITS, doc="straight on a terrain: alternate, or step_to "
                                                                "(both feet on each tread)")
    lateral_offset = dg.Param(0.0, kind="float", doc="straight on a terrain: m the footsteps are moved to the left "
                                                     "of the walk's line")
    start = dg.Param(0.0, kind="float", minimum=0.0, doc="time in s (t dt) at which the plan starts")
    model = dg.Param("talos", kind="name_or_path", doc="example-robot-data robot name, URDF path or pinocchio.Model")
    left_frame = dg.Param("left_sole_link", kind="str", doc="left sole frame (z = sole normal, origin on the sole)")
    right_frame = dg.Param("right_sole_link", kind="str", doc="right sole frame")
    dt = dg.Param(None, kind="float", minimum=1e-6, doc="tick period in s (default: the graph's dt)")
    if TYPE_CHECKING:  # written by python -m dgraph.signatures from the parameters
        def __init__(
            self, name: str, *, walk: Literal["straight", "lateral", "turning", "explicit"] = "straight",
            steps: int = 6, length: float | None = None, width: float | None = None,
            first_side: Literal["left", "right"] | None = None, half_first: bool = True, half_last: bool = True,
            angle_per_step: float | None = None, footsteps: Any = None, single_support: float = 0.9,
            double_support: float = 0.115, initial_double_support: float = 1.0, final_double_support: float = 1.0,
            terrain: Any = None, gait: Literal["alternate", "step_to"] = "alternate", lateral_offset: float = 0.0,
            start: float = 0.0, model: str | Any = "talos", left_frame: str = "left_sole_link",
            right_frame: str = "right_sole_link", dt: float | None = None,
        ) -> None: ...

    def configure(self) -> None:
        """Check the parameters against the walk, read the standing sole placements, build the plan."""
        self._check_parameters()
        model = load_model(self.model, self.name)
        label = f"{self.name} ({self.type_name})"
        if not has_free_flyer(model):
            raise dg.ParamError(f"{label}: the model's first joint must be a free flyer", entity=self.name)
        for param in ("left_frame", "right_frame"):
            frame_id(model, getattr(self, param), self.name, param, label)
        self.initial_left, self.initial_right = sole_placements(model, self.left_frame, self.right_frame)
        self._terrain = self._read_terrain()
        self._plan = dataclasses.replace(self._build(), start=self.start)

    def _refuse(self, param: str, reason: str) -> dg.ParamError:
        return dg.ParamError(f"{self.name} ({self.type_name}): parameter {param!r}: {reason}", entity=self.name)

    def _check_parameters(self) -> None:
        """ParamError for a parameter the walk does not read, a missing one, a duration out of range."""
        reads = WALK_PARAMETERS[self.walk]
        for param in sorted((WALK_PARAMETER_NAMES - set(reads)) & set(self.given_params)):
            raise self._refuse(param, f"not used by walk {self.walk!r} (it reads {', '.join(reads)})")
        needed = {"lateral": "length", "turning": "angle_per_step", "explicit": "footsteps"}.get(self.walk)
        if needed and getattr(self, needed) is None:
            raise self._refuse(needed, f"walk {self.walk!r} needs it")
        for param in ("gait", "lateral_offset"):
            if param in self.given_params and self.terrain is None:
                raise self._refuse(param, "read only on a terrain (give the terrain parameter)")
        for param in ("single_support", "final_double_support", "width"):
            value = getattr(self, param)
            if value is not None and not value > 0.0:
                raise self._refuse(param, f"must be > 0, got {value}")

    def _read_terrain(self) -> Terrain:
        """The ``terrain`` parameter as a Terrain (the floor if None); a ParamError naming it."""
        if self.terrain is None:
            return flat()
        try:
            return Terrain.from_plain(self.terrain)
        except (TypeError, ValueError) as exc:
            raise self._refuse("terrain", str(exc)) from None

    def _build(self) -> FootstepPlan:
        """The plan of ``walk``; a builder's refusal as a ParamError (``footsteps`` for an explicit
        walk, else ``walk``)."""
        timing = {name: getattr(self, name) for name in TIMING}
        optional = {name: getattr(self, name) for name in ("length", "first_side") if getattr(self, name) is not None}
        feet = (self.initial_left, self.initial_right)
        try:
            if self.walk == "straight" and self.terrain is not None:
                return terrain_walk(self._terrain, *feet, steps=self.steps, width=self.width,
                                    half_first=self.half_first, half_last=self.half_last, gait=self.gait,
                                    lateral_offset=self.lateral_offset, **optional, **timing)
            if self.walk == "straight":
                return straight_walk(*feet, steps=self.steps, width=self.width, half_first=self.half_first,
                                     half_last=self.half_last, **optional, **timing)
            if self.walk == "lateral":
                return lateral_walk(*feet, steps=self.steps, length=self.length, width=self.width, **timing)
            if self.walk == "turning":
                return turning_walk(*feet, steps=self.steps, angle_per_step=self.angle_per_step, width=self.width,
                                    **optional, **timing)
            return FootstepPlan(*feet, self._explicit_steps(), self.initial_double_support,
                                self.final_double_support)
        except (TypeError, ValueError) as exc:
            raise self._refuse("footsteps" if self.walk == "explicit" else "walk", str(exc)) from None

    def _explicit_steps(self) -> tuple[Any, ...]:
        """The footsteps of the ``footsteps`` parameter, durations defaulting to the parameters."""
        footsteps = self.footsteps
        if isinstance(footsteps, (str, Mapping)) or not isinstance(footsteps, Sequence):
            raise TypeError(f"expected a list of footsteps, got {type(footsteps).__name__}")
        last = len(footsteps) - 1
        return tuple(footstep_from_plain(step, index, self.single_support,
                                         self.final_double_support if index == last else self.double_support)
                     for index, step in enumerate(footsteps))

    @dg.output(dtype=FootstepPlan, depends=())
    def plan(self, t: int) -> FootstepPlan:
        """The plan (constant)."""
        return self._plan

    @dg.output(dtype=Terrain, depends=())
    def walked_terrain(self, t: int) -> Terrain:
        """The terrain walked on (constant)."""
        return self._terrain

    @dg.output(shape=(), depends=("t",))
    def time(self, t: int) -> float:
        """Plan time in s: ``t dt - start``."""
        return self._plan.time(t * self.dt)
