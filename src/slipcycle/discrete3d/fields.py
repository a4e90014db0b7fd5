"""Contact fields of the steady cycle for ParaView: an XDMF time series and a VTU series.

The contact nodes are written as points (one ``vertex`` cell each) at their coordinates,
one time step per load sample of the last cycle (time = θ in rad). Point data, global
Cartesian components from the node frames (t1, t2, n):

- ``slip`` [m] (3-vector, in the tangent plane), ``separation`` w [m];
- ``tangential_reaction`` [N] (3-vector), ``normal_reaction`` p [N] (compressive > 0),
  ``tangential_traction`` [Pa] and ``pressure`` [Pa] (divided by the node area);
- ``node_state`` (0 stick, 1 slip, 2 separated), ``friction_limit`` f p [N];
- ``dissipation`` D_j of the cycle [J] and ``dissipation_per_area`` D_j / area [J/m²]
  (the same at every step).

Files (:func:`write_fields`): ``interface.xdmf`` (meshio's XDMF time series, data inline
as XML) and ``interface.pvd`` with ``interface_NNNN.vtu``; ParaView opens either.
"""

from __future__ import annotations

from pathlib import Path
from xml.sax.saxutils import quoteattr

import meshio
import numpy as np

__all__ = ["field_steps", "write_fields", "write_xdmf", "write_pvd"]


def field_steps(coordinates, normals, tangents, area, friction, theta, x, r, modes,
                dissipation) -> tuple[np.ndarray, list[dict]]:
    """Point data of every sample of one cycle (module docstring).

    Parameters
    ----------
    coordinates : (N, 3) array [m]
    normals : (N, 3) array
    tangents : (N, 2, 3) array
    area : (N,) array [m²]
    friction : (N,) array
    theta : (S,) array [rad]
    x, r : (S, 3N) arrays
        States [v, w] [m] and reactions [q, p] [N] at the samples.
    modes : (S, N) int array
    dissipation : (N,) array [J]

    Returns
    -------
    times : (S,) array
    data : list of dict
        Name -> (N,) or (N, 3) array for each sample.
    """
    n = coordinates.shape[0]
    out = []
    for k in range(len(theta)):
        v = x[k, :2 * n].reshape(n, 2)
        q = r[k, :2 * n].reshape(n, 2)
        p = r[k, 2 * n:]
        slip = np.einsum("na,nad->nd", v, tangents)
        qg = np.einsum("na,nad->nd", q, tangents)
        out.append({
            "slip": slip, "separation": x[k, 2 * n:].copy(),
            "tangential_reaction": qg, "normal_reaction": p.copy(),
            "tangential_traction": qg / area[:, None], "pressure": p / area,
            "node_state": np.asarray(modes[k], np.int32),
            "friction_limit": friction * p,
            "dissipation": np.asarray(dissipation, float),
            "dissipation_per_area": np.asarray(dissipation, float) / area,
        })
    return np.asarray(theta, float), out


def _cells(n: int):
    return [("vertex", np.arange(n).reshape(n, 1))]


def write_xdmf(path: Path, points: np.ndarray, times, data: list[dict]) -> None:
    """An XDMF time series (``path``, data inline as XML) with one step per sample."""
    path = Path(path)
    with meshio.xdmf.TimeSeriesWriter(str(path), data_format="XML") as writer:
        writer.write_points_cells(points, _cells(points.shape[0]))
        for t, d in zip(times, data, strict=True):
            writer.write_data(float(t), point_data=d)


def write_pvd(path: Path, points: np.ndarray, times, data: list[dict]) -> None:
    """A ParaView collection ``path`` (.pvd) of ``<stem>_NNNN.vtu`` files beside it."""
    path = Path(path)
    entries = []
    for k, (t, d) in enumerate(zip(times, data, strict=True)):
        name = f"{path.stem}_{k:04d}.vtu"
        meshio.Mesh(points, _cells(points.shape[0]), point_data=d).write(
            path.parent / name, binary=True)
        entries.append(f'    <DataSet timestep="{float(t):.12g}" part="0" '
                       f'file={quoteattr(name)}/>')
    path.write_text('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n'
                    "  <Collection>\n" + "\n".join(entries) + "\n  </Collection>\n"
                    "</VTKFile>\n", encoding="utf-8")


def write_fields(directory: Path, system, theta, x, r, modes, dissipation,
                 formats: tuple[str, ...] = ("xdmf", "pvd")) -> list[Path]:
    """Write the fields of one cycle of a :class:`FrictionalSystem3D` into ``directory``.

    Parameters
    ----------
    directory : Path
    system : FrictionalSystem3D
        Coordinates, frames, areas and friction of the nodes.
    theta, x, r, modes, dissipation
        As :func:`field_steps`.
    formats : tuple of str
        ``"xdmf"`` and/or ``"pvd"``.

    Returns
    -------
    list of Path
        The collection files written.
    """
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    times, data = field_steps(system.coordinates, system.normals, system.tangents,
                              system.area, system.friction, theta, x, r, modes, dissipation)
    points = np.asarray(system.coordinates, float)
    written = []
    if "xdmf" in formats:
        write_xdmf(directory / "interface.xdmf", points, times, data)
        written.append(directory / "interface.xdmf")
    if "pvd" in formats:
        write_pvd(directory / "interface.pvd", points, times, data)
        written.append(directory / "interface.pvd")
    return written
