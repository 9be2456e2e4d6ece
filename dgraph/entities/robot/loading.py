"""Robot sources: an example-robot-data name (``talos``, ``panda``, ``ur5``) or the path of a URDF file.

:func:`load_model` gives the Pinocchio model of either (cached per process, shared, never to be
modified; a URDF file is known by its real path, size and modification time, so an edited file
is read again); :func:`load_robot` the model with its visual and collision geometry (meshes read
once per process, for a 3D view). A source is a path when it ends in ``.urdf`` or names a file;
anything else is a robot name, checked against example-robot-data's list (an unknown name is
refused with the closest names).

A URDF given by path gives a **fixed-base** model (its root link welded to the world, as MuJoCo
imports it) with no reference configuration and no rotor parameters; its meshes are found
relative to the file, or, for ``package://PKG/...``, in ``PKG`` under the file's folder or one
of its ancestors, or under a folder of ``package_dirs``.
"""

from __future__ import annotations

import difflib
import functools
import os
from pathlib import Path
from typing import Any

import pinocchio as pin

from dgraph.errors import ParamError


def is_urdf_path(source: str) -> bool:
    """True if ``source`` names a URDF file (ends in ``.urdf`` or is a file), not a robot name."""
    return source.lower().endswith(".urdf") or os.sep in source or os.path.isfile(source)


@functools.lru_cache(maxsize=1)
def robot_names() -> tuple[str, ...]:
    """The names ``example_robot_data.load`` knows, sorted."""
    from example_robot_data.robots_loader import ROBOTS

    return tuple(sorted(ROBOTS))


def check_source(source: Any, entity: str | None = None, param: str = "model") -> str:
    """``source`` if it is a known robot name or an existing URDF file, else a :class:`ParamError`
    naming ``entity`` and ``param`` (with the closest robot names for a near miss)."""
    prefix = f"{entity}: " if entity else ""
    if not isinstance(source, str) or not source:
        raise ParamError(f"{prefix}parameter {param!r} must be an example-robot-data robot name or a URDF path, "
                         f"got {source!r}", entity=entity)
    if is_urdf_path(source):
        if not os.path.isfile(source):
            raise ParamError(f"{prefix}cannot load robot model {source!r} (parameter {param!r}): no such URDF file",
                             entity=entity)
        return source
    if source not in robot_names():
        close = difflib.get_close_matches(source, robot_names(), n=3)
        hint = f"; did you mean {' or '.join(repr(c) for c in close)}?" if close else ""
        raise ParamError(f"{prefix}cannot load robot model {source!r} (parameter {param!r}): unknown robot{hint} "
                         "(an example-robot-data name such as 'talos', 'panda', 'ur5', or the path of a URDF file)",
                         entity=entity)
    return source


def load_model(model: Any, entity: str | None = None) -> pin.Model:
    """A Pinocchio model from an example-robot-data name (e.g. ``talos``), a URDF path or a ``pin.Model``.

    Models loaded by name or path are cached per process (loading TALOS takes ~0.8 s) and shared:
    entities must not modify them. A bad value raises :class:`ParamError` naming ``entity``.
    """
    if isinstance(model, pin.Model):
        return model
    prefix = f"{entity}: " if entity else ""
    if not isinstance(model, str):
        raise ParamError(f"{prefix}model must be a robot name or a pinocchio.Model, got {type(model).__name__} (a "
                         "name: example-robot-data's, or a URDF path)", entity=entity)
    source = check_source(model, entity)
    try:
        return _urdf_model(os.path.realpath(source)) if is_urdf_path(source) else describe_robot(source).model
    except Exception as exc:  # Pinocchio and example-robot-data raise plain exceptions
        raise ParamError(f"{prefix}cannot load robot model {model!r}: {exc}", entity=entity) from None


def file_stamp(path: str) -> tuple[int, int]:
    """The size and modification time (ns) of the file at ``path``: with its real path, the key
    under which what is read from it is cached, so that an edited file is read again."""
    status = os.stat(path)
    return status.st_size, status.st_mtime_ns


def _urdf_model(path: str) -> pin.Model:
    """The kinematics and dynamics of the URDF file at the real path ``path`` (fixed base; no
    meshes are read), cached on the file's size and modification time: an edited file is parsed
    again."""
    return _parsed_urdf(path, file_stamp(path))


@functools.lru_cache(maxsize=8)
def _parsed_urdf(path: str, stamp: tuple[int, int]) -> pin.Model:
    """:func:`_urdf_model`, cached (``stamp``: a key only)."""
    return pin.buildModelFromUrdf(path)


def has_free_flyer(model: pin.Model) -> bool:
    """True if ``model``'s first joint is a free flyer: a floating base (7 coordinates, 6
    velocities), as example-robot-data builds humanoids and quadrupeds."""
    return model.njoints > 1 and model.joints[1].shortname() == "JointModelFreeFlyer"


def package_dirs_of(urdf: str, extra: tuple[str, ...] = ()) -> list[str]:
    """Where the ``package://`` meshes of ``urdf`` are looked for: ``extra``, then the file's
    folder and each of its ancestors (example-robot-data's ``package://example-robot-data/robots/``
    sits under ``share``, an ancestor of its URDF files)."""
    folder = Path(urdf).resolve().parent
    return [*extra, str(folder), *(str(p) for p in folder.parents)]


@functools.lru_cache(maxsize=8)
def describe_robot(name: str) -> pin.RobotWrapper:
    """An example-robot-data robot without its meshes: ``model`` (with the SRDF's reference
    configurations and rotor parameters, as ``example_robot_data.load`` sets them), ``q0`` (its
    reference posture) and ``urdf`` (the file), cached per process. Reading TALOS's meshes takes
    ~0.6 s and parsing its kinematics 3 ms: the controller needs only the latter, a 3D view both
    (:func:`load_robot` adds the meshes to this same model).

    A loader that builds its model itself (a reduced model such as ``talos_legs``) is run as it is,
    meshes included.
    """
    from example_robot_data.robots_loader import ROBOTS
    from example_robot_data.utils import RobotLoader

    loader = ROBOTS[name]
    if loader.__init__ is not RobotLoader.__init__ or not loader.urdf_filename:
        import example_robot_data as erd

        return erd.load(name)
    urdf, share = _loader_files(loader)
    root = (pin.JointModelFreeFlyer(),) if loader.free_flyer else ()
    model = pin.buildModelFromUrdf(urdf, *root)
    robot = pin.RobotWrapper(model)
    robot.urdf, robot.package_dir = urdf, share
    robot.q0 = _read_srdf(loader, model) if loader.srdf_filename else pin.neutral(model)
    if loader.free_flyer:  # as the loader bounds the free flyer's coordinates
        model.upperPositionLimit[:7], model.lowerPositionLimit[:7] = 1.0, -1.0
    return robot


def _loader_files(loader: type) -> tuple[str, str]:
    """The URDF file of an example-robot-data loader and the folder its ``package://`` paths start from."""
    from example_robot_data.utils import getModelPath

    relative = os.path.join(loader.path, loader.urdf_subpath, loader.urdf_filename)
    robots = loader.model_path or getModelPath(relative)
    return os.path.join(robots, relative), os.path.join(robots, "..", "..")


def _read_srdf(loader: type, model: pin.Model) -> Any:
    """Read the loader's SRDF into ``model`` (rotor parameters, armature, reference configurations);
    return its reference posture."""
    from example_robot_data.utils import readParamsFromSrdf

    robots = os.path.dirname(os.path.dirname(os.path.dirname(_loader_files(loader)[0])))
    srdf = os.path.join(robots, loader.path, loader.srdf_subpath, loader.srdf_filename)
    return readParamsFromSrdf(model, srdf, False, loader.has_rotor_parameters, loader.ref_posture)


def load_robot(name: str) -> Any:
    """The model with its collision and visual geometry, cached per process and shared by every
    entity that names the robot (the kinematics, the 3D view): reading TALOS's meshes takes
    ~0.6 s, once, and only when something draws the robot. Only read, never changed.

    ``name``: an example-robot-data name (the meshes of :func:`describe_robot`'s model, or
    ``example_robot_data.load(name)`` for a loader that builds its model itself) or a URDF path (a
    ``pinocchio.RobotWrapper``, meshes looked for as :func:`package_dirs_of` says; its ``model``
    is :func:`load_model`'s, so the URDF is parsed once; an edited file is read again, as by
    :func:`load_model`).
    """
    if is_urdf_path(name):
        path = os.path.realpath(check_source(name))
        return robots_with_meshes(path, file_stamp(path))
    return robots_with_meshes(name, None)


@functools.lru_cache(maxsize=8)
def robots_with_meshes(source: str, stamp: tuple[int, int] | None) -> Any:
    """:func:`load_robot`'s cache: ``source``, a robot name (``stamp`` None) or the real path of a
    URDF file (``stamp``: its size and modification time, a key only), with its meshes."""
    if stamp is not None:
        return _with_meshes(_urdf_model(source), source, package_dirs_of(source))
    described = describe_robot(source)
    if described.visual_model is not None:  # its loader read the meshes already
        return described
    robot = _with_meshes(described.model, described.urdf, [described.package_dir])
    robot.urdf, robot.q0 = described.urdf, described.q0
    return robot


def _with_meshes(model: pin.Model, urdf: str, package_dirs: list[str]) -> pin.RobotWrapper:
    """``model`` with the visual and collision geometry of its URDF."""
    visual = pin.buildGeomFromUrdf(model, urdf, pin.GeometryType.VISUAL, package_dirs=package_dirs)
    collision = pin.buildGeomFromUrdf(model, urdf, pin.GeometryType.COLLISION, package_dirs=package_dirs)
    return pin.RobotWrapper(model, collision, visual)
