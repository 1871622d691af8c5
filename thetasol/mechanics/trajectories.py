"""Trajectories of every body of a configuration on a time grid, and their files.

The split solution and the unsplit multibody reference return the same :class:`Trajectories`
layout so that they compare directly; :func:`write_trajectories` writes them to ``.npz`` or
``.csv`` atomically.
"""
from __future__ import annotations

import io
import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["Trajectories", "write_trajectories"]


@dataclass(frozen=True, eq=False)
class Trajectories:
    """Trajectories of every body of a configuration on a time grid.

    Produced by the split solution (:class:`thetasol.scenes.pipeline.ConfigurationSolution`) and by the
    unsplit reference (:func:`thetasol.integrators.multibody.integrate_multibody`) in the same layout,
    so that they compare directly.

    Attributes
    ----------
    t : ndarray (T,)
    names : tuple of str
        Body names, root first (the order of the first axis below).
    position, velocity : ndarray (N, T, 3)
        Each body's own mass centre in space and its velocity.
    attitude : ndarray (N, T, 3, 3)
        Body to space (``x = Q r + origin``).
    omega : ndarray (N, T, 3)
        Body-frame angular velocities.
    mass_center, mass_center_velocity : ndarray (T, 3)
        The system mass centre ``q(t)`` and ``qdot(t)``.
    info : dict
        What produced them (models, tolerances, timings, constraint residuals...).
    """

    t: np.ndarray
    names: tuple
    position: np.ndarray
    velocity: np.ndarray
    attitude: np.ndarray
    omega: np.ndarray
    mass_center: np.ndarray
    mass_center_velocity: np.ndarray
    info: dict = field(default_factory=dict)

    def body(self, name: str) -> dict[str, np.ndarray]:
        """``{"position", "velocity", "attitude", "omega"}`` of one body."""
        try:
            i = self.names.index(name)
        except ValueError:
            raise ValueError(f"unknown body {name!r}; bodies are {list(self.names)}") from None
        return {"position": self.position[i], "velocity": self.velocity[i],
                "attitude": self.attitude[i], "omega": self.omega[i]}

    def deviation(self, other: Trajectories) -> dict[str, float]:
        """Max deviations from another set on the same grid: position, velocity, attitude, omega, mass centre."""
        if self.names != other.names or self.t.shape != other.t.shape or np.any(self.t != other.t):
            raise ValueError("trajectories must share body names and time grid to be compared")
        return {
            "position": float(np.max(np.abs(self.position - other.position), initial=0.0)),
            "velocity": float(np.max(np.abs(self.velocity - other.velocity), initial=0.0)),
            "attitude": float(np.max(np.abs(self.attitude - other.attitude), initial=0.0)),
            "omega": float(np.max(np.abs(self.omega - other.omega), initial=0.0)),
            "mass_center": float(np.max(np.abs(self.mass_center - other.mass_center), initial=0.0)),
        }

    def save(self, path: str | Path) -> None:
        """Write to ``.npz`` or ``.csv`` atomically (see :func:`write_trajectories`)."""
        write_trajectories(self, path)


def _umask() -> int:
    """The process's umask (read by setting it and restoring it at once)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _atomic_write(path: Path, write) -> None:
    path = Path(path)
    directory = path.parent if str(path.parent) else Path(".")
    if not directory.is_dir():
        raise ValueError(f"output directory {str(directory)!r} does not exist")
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=directory)
    try:
        # mkstemp creates the file 0600; the result gets the mode open() would give it (0666 less the umask)
        os.fchmod(fd, 0o666 & ~_umask())
        with os.fdopen(fd, "wb") as fh:
            write(fh)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def _csv_columns(traj: Trajectories):
    cols = ["t"] + [f"q_{c}" for c in "xyz"] + [f"qdot_{c}" for c in "xyz"]
    for n in traj.names:
        cols += [f"{n}.{c}" for c in "xyz"] + [f"{n}.v{c}" for c in "xyz"]
        cols += [f"{n}.Q{i}{j}" for i in range(1, 4) for j in range(1, 4)]
        cols += [f"{n}.w{c}" for c in "xyz"]
    T = traj.t.size
    data = [traj.t[:, None], traj.mass_center, traj.mass_center_velocity]
    for i in range(len(traj.names)):
        data += [traj.position[i], traj.velocity[i], traj.attitude[i].reshape(T, 9), traj.omega[i]]
    return cols, np.hstack(data)


def write_trajectories(traj: Trajectories, path: str | Path, report: str | None = None) -> list[Path]:
    """Write trajectories to ``.npz`` or ``.csv``, atomically; optionally the report beside them.

    ``.npz`` arrays: ``t`` (T,), ``names`` (N,), ``mass_center``/``mass_center_velocity`` (T, 3),
    ``position``/``velocity``/``omega`` (N, T, 3), ``attitude`` (N, T, 3, 3) and ``report``.
    ``.csv``: one row per time; columns ``t, q_x.., qdot_x.., <body>.x.., <body>.vx..,
    <body>.Q11..Q33, <body>.wx..`` with 17 significant digits.  With ``report``, it is also
    written to ``<stem>.report.txt``.  Returns the paths written.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".npz", ".csv"):
        raise ValueError(f"output file must end in .npz or .csv, got {str(path)!r}")
    if suffix == ".npz":
        arrays = {"t": traj.t, "names": np.array(traj.names), "mass_center": traj.mass_center,
                  "mass_center_velocity": traj.mass_center_velocity, "position": traj.position,
                  "velocity": traj.velocity, "attitude": traj.attitude, "omega": traj.omega,
                  "report": np.array(report or "")}
        payload = io.BytesIO()
        np.savez(payload, **arrays)
        blob = payload.getvalue()
    else:
        cols, data = _csv_columns(traj)
        text = io.StringIO()
        text.write(",".join(cols) + "\n")
        np.savetxt(text, data, delimiter=",", fmt="%.17g")
        blob = text.getvalue().encode()
    written = []
    if report is not None:
        rpath = path.with_name(path.stem + ".report.txt")
        # Validate both destinations before writing either.
        for p in (path, rpath):
            if p.exists() and p.is_dir():
                raise ValueError(f"{str(p)!r} is a directory")
    _atomic_write(path, lambda fh: fh.write(blob))
    written.append(path)
    if report is not None:
        _atomic_write(rpath, lambda fh: fh.write(report.encode()))
        written.append(rpath)
    return written
