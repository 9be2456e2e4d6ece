"""Robot sources: an example-robot-data name (``talos``, ``panda``, ``ur5``) or the path of a URDF file.

:func:`load_model` gives the Pinocchio model of either (cached per process, shared, never to be
modified); :func:`load_robot` the model with its visual and collision geometry (meshes read once
per process, for a 3D view). A source is a path when it ends in ``.urdf`` or names a file;
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
        return _urdf_model(os.path.realpath(source)) if is_urdf_path(source) else load_robot(source).model
    except Exception as exc:  # Pinocchio and example-robot-data raise plain exceptions
        raise ParamError(f"{prefix}cannot load robot model {model!r}: {exc}", entity=entity) from None


@functools.lru_cache(maxsize=8)
def _urdf_model(path: str) -> pin.Model:
    """The kinematics and dynamics of a URDF file (fixed base; no meshes are read)."""
    return pin.buildModelFromUrdf(path)


def package_dirs_of(urdf: str, extra: tuple[str, ...] = ()) -> list[str]:
    """Where the ``package://`` meshes of ``urdf`` are looked for: ``extra``, then the file's
    folder and each of its ancestors (example-robot-data's ``package://example-robot-data/robots/``
    sits under ``share``, an ancestor of its URDF files)."""
    folder = Path(urdf).resolve().parent
    return [*extra, str(folder), *(str(p) for p in folder.parents)]


@functools.lru_cache(maxsize=8)
def load_robot(name: str) -> Any:
    """The model with its collision and visual geometry, cached per process and shared by every
    entity that names the robot (the kinematics, the 3D view): reading TALOS's URDF and meshes
    takes ~0.6 s, once. Only read, never changed.

    ``name``: an example-robot-data name (``example_robot_data.load(name)``) or a URDF path (a
    ``pinocchio.RobotWrapper``, meshes looked for as :func:`package_dirs_of` says; its ``model``
    is :func:`load_model`'s, so the URDF is parsed once).
    """
    if is_urdf_path(name):
        path = os.path.realpath(check_source(name))
        model = _urdf_model(path)
        dirs = package_dirs_of(path)
        visual = pin.buildGeomFromUrdf(model, path, pin.GeometryType.VISUAL, package_dirs=dirs)
        collision = pin.buildGeomFromUrdf(model, path, pin.GeometryType.COLLISION, package_dirs=dirs)
        return pin.RobotWrapper(model, collision, visual)
    import example_robot_data as erd

    return erd.load(name)
