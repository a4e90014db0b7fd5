"""The result of an assembly-protocol study of a bolted joint (``model = "lap_joint"``).

Per protocol: the steady-state class, the dissipation per cycle (total and per bolt
region), the permanently stuck area, the slip map, the bolt forces after the assembly
and over the steady cycle; per mesh, each protocol's dissipation and its mesh convergence
(:func:`slipcycle.joints.convergence.mesh_convergence`). Written as summary.json,
result.nc, figures, ``report.md`` and the contact fields of every protocol.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
import xarray as xr

from slipcycle.coupled.case import certificate_entries
from slipcycle.coupled.driver import ACCELERATIONS
from slipcycle.joints.convergence import mesh_convergence
from slipcycle.joints.lap_joint_protocol import JointContact, StudySettings
from slipcycle.joints.lap_joint_report import report_markdown
from slipcycle.result import STEADY_STATES, RunResult, SteadyState

__all__ = ["LapJointResult", "MeshRuns", "BoltForces", "NODE_CLASSES", "SUMMARY_UNITS",
           "SUMMARY_FLAGS"]

#: classes of a node over the steady cycle (``node_class`` of the Dataset): stuck over the
#: whole cycle, slipping while in contact, or opening at some time (it may slip too)
NODE_CLASSES = ("stuck", "slipping", "separating")



@dataclass(frozen=True)
class BoltForces:
    """The bolt forces of one protocol.

    Attributes
    ----------
    assembled : (K,) array
        After the assembly, at θ = 0 of the service cycle [N].
    cycle : (S, K) array
        At the samples of the steady cycle [N] (constant for constant-force bolts).
    """

    assembled: np.ndarray
    cycle: np.ndarray


@dataclass(frozen=True)
class MeshRuns:
    """The dissipation of every protocol on each mesh (coarse → fine).

    Attributes
    ----------
    spacing : tuple of float
        Node spacing h of each mesh [m].
    dissipation : (M, P) array
        Steady dissipation per cycle [J] of protocol p on mesh m.
    steady_state : (M, P) array of str
    """

    spacing: tuple
    dissipation: np.ndarray
    steady_state: np.ndarray



def _worst(words: Sequence[str]) -> str:
    return SteadyState.worst(words).value



#: unit of every numeric summary entry
SUMMARY_UNITS = {
    "n_nodes": "1", "bolt_count": "1", "converged": "1", "residual": "1",
    "cycles_run": "1", "dissipation_per_cycle": "J", "preload": "N",
    "service_amplitude": "N", "friction": "1", "contact_area": "m^2",
    "protocol_dissipation_per_cycle": "J", "protocol_dissipation_per_region": "J",
    "protocol_stuck_area": "m^2", "protocol_stuck_fraction": "1",
    "bolt_stiffness": "N/m", "protocol_bolt_force": "N", "protocol_bolt_force_min": "N",
    "protocol_bolt_force_max": "N",
    "protocol_slipping_nodes": "1", "protocol_separating_nodes": "1",
    "protocol_cycles_run": "1", "protocol_residual": "1", "protocol_converged": "1",
    "protocol_energy_balance_error": "1", "protocol_certified_residual": "1",
    "protocol_memory_distance": "1", "protocol_dissipation_distance": "1",
    "dissipation_spread": "1", "dissipation_min": "J", "dissipation_max": "J",
    "orders_differ": "1", "difference_tol": "1", "mesh_spacing": "m",
    "mesh_dissipation": "J", "protocol_dissipation_extrapolated": "J",
    "protocol_dissipation_observed_order": "1", "protocol_dissipation_relative_error": "1",
    "protocol_dissipation_mesh_converged": "1", "dissipation_mesh_converged": "1",
    "mesh_rtol": "1", "wall_time_s": "s", "f_crit": "1",
}

#: every word of the categorical summary entries
SUMMARY_FLAGS = {"steady_state": STEADY_STATES, "steady_state_class": STEADY_STATES,
                 "protocol_steady_state": STEADY_STATES,
                 "protocol_acceleration": ACCELERATIONS}


@dataclass(frozen=True, kw_only=True, repr=False, eq=False)
class LapJointResult(RunResult):
    """Result of the tightening-order study of a bolted joint (``model = "lap_joint"``).

    The shared fields describe the study as a whole: ``steady_state`` is the most severe
    class over the protocols, ``dissipation_per_cycle`` the reference (first) protocol's
    [J], ``cycles_run`` and ``residual`` the largest, ``converged`` true when every
    protocol reached its steady state.

    Attributes
    ----------
    contact : JointContact
        The joint on the finest mesh.
    protocols : tuple of Protocol
    runs : tuple of DiscreteResult3D
        One per protocol, on the finest mesh (histories of the last cycle).
    mesh : MeshRuns
        Every protocol's dissipation on each mesh.
    convergence : tuple
        One :class:`~slipcycle.joints.convergence.MeshConvergence` per protocol (None with
        one mesh).
    settings : StudySettings
    bolt_forces : tuple of BoltForces
        One per protocol, on the finest mesh (empty: not recorded).
    """

    model: ClassVar[str] = "lap_joint"

    contact: JointContact
    protocols: tuple
    runs: tuple
    mesh: MeshRuns
    convergence: tuple
    settings: StudySettings
    bolt_forces: tuple = ()

    @classmethod
    def from_runs(cls, contact, protocols, runs, mesh, settings, wall,
                  bolt_forces: tuple = ()) -> LapJointResult:
        """Fill the shared fields from the per-protocol runs (class docstring)."""
        convergence = _mesh_convergence(mesh, settings.mesh_rtol)
        words = [r.solution.steady_state for r in runs]
        state = _worst(words)
        diss = np.array([r.solution.dissipation_per_cycle for r in runs])
        spread = _spread(diss)
        differ = spread > settings.difference_tol
        lines = [f"{len(protocols)} tightening protocols: {state}"
                 + ("" if len(set(words)) == 1 else f" (classes {', '.join(words)})"),
                 f"dissipation {diss.min():.4g}–{diss.max():.4g} J per cycle, spread "
                 f"{spread:.3g} ({'the orders differ' if differ else 'the orders agree'} "
                 f"at tolerance {settings.difference_tol:g})"]
        unconverged = [p.name for p, c in zip(protocols, convergence, strict=True)
                       if c is not None and not c.converged]
        if unconverged:
            lines.append("WARNING: dissipation not mesh-converged for "
                         + ", ".join(unconverged))
        elif all(c is None for c in convergence):
            lines.append("WARNING: dissipation not checked for mesh convergence (one mesh; "
                         "[lap_joint.convergence] coarsening adds coarser ones)")
        return cls(steady_state=SteadyState(state), steady_state_detail=state,
                   dissipation_per_cycle=float(diss[0]),
                   cycles_run=max(int(r.cycles_run) for r in runs),
                   residual=max(float(r.residual) for r in runs),
                   converged=all(r.converged for r in runs), message="; ".join(lines),
                   contact=contact, protocols=protocols, runs=runs, mesh=mesh,
                   convergence=convergence, settings=settings, wall_time_s=wall,
                   bolt_forces=tuple(bolt_forces))

    # -- per-protocol numbers ----------------------------------------------------------
    @property
    def dissipation(self) -> np.ndarray:
        """Steady dissipation per cycle of each protocol, (P,) [J]."""
        return np.array([r.solution.dissipation_per_cycle for r in self.runs])

    @property
    def dissipation_per_region(self) -> np.ndarray:
        """Dissipation per cycle of each protocol in each bolt region, (P, K) [J]."""
        k = self.contact.bolt_count
        return np.array([np.bincount(self.contact.bolt_region,
                                     weights=r.solution.dissipation_per_node, minlength=k)
                         for r in self.runs])

    @property
    def node_class(self) -> np.ndarray:
        """Class of each node over the steady cycle of each protocol, (P, N) int8
        (0 stuck, 1 slipping, 2 separating: :data:`NODE_CLASSES`)."""
        out = np.zeros((len(self.runs), self.contact.n_nodes), np.int8)
        for j, r in enumerate(self.runs):
            out[j, r.solution.slipping_nodes] = 1
            out[j, r.solution.separating_nodes] = 2
        return out

    @property
    def stuck_area(self) -> np.ndarray:
        """Permanently stuck area of each protocol (nodes stuck over the whole steady
        cycle), (P,) [m²]."""
        return np.array([float(self.contact.node_area[r.solution.permanently_stuck_nodes]
                               .sum()) for r in self.runs])

    @property
    def bolt_force(self) -> np.ndarray:
        """Bolt forces after the assembly of each protocol, (P, K) [N] (NaN: not
        recorded)."""
        k = self.contact.bolt_count
        if not self.bolt_forces:
            return np.full((len(self.runs), k), np.nan)
        return np.array([b.assembled for b in self.bolt_forces])

    @property
    def bolt_force_range(self) -> tuple[np.ndarray, np.ndarray]:
        """Least and largest force of each bolt over the steady cycle of each protocol,
        two (P, K) arrays [N] (NaN: not recorded)."""
        if not self.bolt_forces:
            nan = np.full((len(self.runs), self.contact.bolt_count), np.nan)
            return nan, nan.copy()
        return (np.array([b.cycle.min(axis=0) for b in self.bolt_forces]),
                np.array([b.cycle.max(axis=0) for b in self.bolt_forces]))

    @property
    def dissipation_spread(self) -> float:
        """(max − min)/max of the protocols' dissipation [1]."""
        return _spread(self.dissipation)

    @property
    def orders_differ(self) -> bool:
        """Whether the spread exceeds ``settings.difference_tol``."""
        return bool(self.dissipation_spread > self.settings.difference_tol)

    @property
    def flags(self) -> dict[str, tuple[str, ...]]:
        """Every word of the categorical summary entries."""
        return dict(SUMMARY_FLAGS)

    def summary(self) -> dict:
        """The summary dictionary (keys in docs/lap_joint.md), with ``units``.

        Per-protocol entries are lists in the order of ``protocols``.
        """
        c = self.contact
        conv = self.convergence
        have_conv = any(x is not None for x in conv)

        def per(attr):
            return [None if x is None else getattr(x, attr) for x in conv]

        certificates = [certificate_entries(r.solution.certificate) for r in self.runs]
        out = {
            "model": "lap_joint",
            "steady_state": self.steady_state_detail,
            "steady_state_class": self.steady_state.value,
            "converged": self.converged,
            "residual": self.residual,
            "cycles_run": self.cycles_run,
            "dissipation_per_cycle": self.dissipation_per_cycle,
            "n_nodes": c.n_nodes,
            "bolt_count": c.bolt_count,
            "contact_area": float(c.node_area.sum()),
            "preload": self.settings.preload,
            "service_amplitude": self.settings.service_amplitude,
            "friction": self.settings.friction,
            "f_crit": _finite(self.runs[0].case.system.critical_friction.f_crit),
            "protocols": [p.name for p in self.protocols],
            "protocol_orders": [p.label for p in self.protocols],
            "protocol_steady_state": [r.solution.steady_state for r in self.runs],
            "protocol_dissipation_per_cycle": self.dissipation,
            "protocol_dissipation_per_region": self.dissipation_per_region,
            "protocol_stuck_area": self.stuck_area,
            "bolt_stiffness": float(c.bolt_stiffness),
            "protocol_bolt_force": self.bolt_force,
            "protocol_bolt_force_min": self.bolt_force_range[0],
            "protocol_bolt_force_max": self.bolt_force_range[1],
            "protocol_stuck_fraction": self.stuck_area / c.node_area.sum(),
            "protocol_slipping_nodes": [len(r.solution.slipping_nodes) for r in self.runs],
            "protocol_separating_nodes": [len(r.solution.separating_nodes)
                                          for r in self.runs],
            "protocol_cycles_run": [int(r.cycles_run) for r in self.runs],
            "protocol_residual": [float(r.residual) for r in self.runs],
            "protocol_converged": [bool(r.converged) for r in self.runs],
            "protocol_energy_balance_error": [r.solution.energy_balance_error
                                              for r in self.runs],
            # the steady state's certificate per protocol (acceleration "none": plain)
            **{f"protocol_{k}": [c[k] for c in certificates] for k in certificates[0]},
            "dissipation_min": float(self.dissipation.min()),
            "dissipation_max": float(self.dissipation.max()),
            "dissipation_spread": self.dissipation_spread,
            "orders_differ": self.orders_differ,
            "difference_tol": self.settings.difference_tol,
            "mesh_spacing": list(self.mesh.spacing),
            "mesh_dissipation": self.mesh.dissipation,
            "protocol_dissipation_extrapolated": per("extrapolated") if have_conv else None,
            "protocol_dissipation_observed_order": (per("observed_order") if have_conv
                                                    else None),
            "protocol_dissipation_relative_error": (per("relative_error") if have_conv
                                                    else None),
            "protocol_dissipation_mesh_converged": per("converged") if have_conv else None,
            "dissipation_mesh_converged": (all(x.converged for x in conv) if have_conv
                                           else None),
            "mesh_convergence_messages": per("message") if have_conv else None,
            "mesh_rtol": self.settings.mesh_rtol,
            "message": self.message,
            "wall_time_s": self.wall_time_s,
            "units": dict(SUMMARY_UNITS),
        }
        return out

    def _build_dataset(self) -> xr.Dataset:
        """Per protocol: class, dissipation (total, per bolt region, per node), node
        classes and slip of the steady cycle; per mesh: the dissipation of each protocol."""
        c = self.contact
        n = c.n_nodes
        P = len(self.protocols)
        hist_len = max(len(r.solution.dissipation_history) for r in self.runs)
        hist = np.full((P, hist_len), np.nan)
        for j, r in enumerate(self.runs):
            h = r.solution.dissipation_history
            hist[j, :len(h)] = h
        start = np.array([r.solution.cycle_start_states[-1] for r in self.runs])
        p0 = np.array([r.solution.r[-1, 0, 2 * n:] for r in self.runs])
        conv = self.convergence
        extrap = np.array([np.nan if x is None or x.extrapolated is None else x.extrapolated
                           for x in conv])
        rel = np.array([np.nan if x is None or x.relative_error is None
                        else x.relative_error for x in conv])
        codes = np.array([SteadyState(r.solution.steady_state).code for r in self.runs],
                         np.int8)

        def var(dims, data, units, long_name, **extra):
            return (dims, data, {"units": units, "long_name": long_name, **extra})

        ds = xr.Dataset(
            {
                "steady_state": var(("protocol",), codes, "1", "steady-state class",
                                    flag_values=np.arange(len(STEADY_STATES), dtype=np.int8),
                                    flag_meanings=" ".join(STEADY_STATES)),
                "dissipation": var(("protocol",), self.dissipation, "J",
                                   "steady dissipation per cycle"),
                "dissipation_error": var(("protocol",), np.abs(rel * self.dissipation), "J",
                                         "estimated mesh error of the dissipation"),
                "dissipation_extrapolated": var(("protocol",), extrap, "J",
                                                "dissipation extrapolated to h -> 0"),
                "dissipation_per_region": var(("protocol", "bolt"),
                                              self.dissipation_per_region, "J",
                                              "dissipation per cycle in each bolt region"),
                "stuck_area": var(("protocol",), self.stuck_area, "m2",
                                  "permanently stuck area"),
                **self._bolt_variables(),
                "cycles_run": var(("protocol",), [r.cycles_run for r in self.runs], "1",
                                  "load cycles run after the assembly"),
                "dissipation_history": var(("protocol", "cycle"), hist, "J",
                                           "total dissipation of each cycle"),
                "dissipation_per_node": var(("protocol", "node"),
                                            np.array([r.solution.dissipation_per_node
                                                      for r in self.runs]), "J",
                                            "dissipation of each node over the steady cycle"),
                "dissipation_per_area": var(("protocol", "node"),
                                            np.array([r.solution.dissipation_per_node
                                                      for r in self.runs]) / c.node_area,
                                            "J m-2", "dissipation per cycle per unit area"),
                "node_class": var(("protocol", "node"), self.node_class, "1",
                                  "node class over the steady cycle",
                                  flag_values=np.arange(3, dtype=np.int8),
                                  flag_meanings=" ".join(NODE_CLASSES)),
                "slip_length": var(("protocol", "node"),
                                   np.array([r.solution.slip_length for r in self.runs]),
                                   "m", "slip length over the steady cycle"),
                "slip_at_start": var(("protocol", "node", "component"),
                                     start[:, :2 * n].reshape(P, n, 2), "m",
                                     "slip at the start of the steady cycle (theta = 0)"),
                "pressure_at_start": var(("protocol", "node"), p0 / c.node_area, "Pa",
                                         "contact pressure at the start of the steady cycle"),
                "node_area": var(("node",), c.node_area, "m2", "tributary area of the node"),
                "bolt_region": var(("node",), c.bolt_region.astype(np.int32), "1",
                                   "bolt region of the node (nearest bolt)"),
                "mesh_dissipation": var(("mesh", "protocol"), self.mesh.dissipation, "J",
                                        "steady dissipation per cycle on each mesh"),
            },
            coords=self._coordinates(),
        )
        ds.attrs["preload_N"] = float(self.settings.preload)
        ds.attrs["service_amplitude_N"] = float(self.settings.service_amplitude)
        ds.attrs["friction"] = float(self.settings.friction)
        ds.attrs["bolt_stiffness_N_per_m"] = float(c.bolt_stiffness)
        return ds

    def _bolt_variables(self) -> dict:
        """The bolt forces of the Dataset: after the assembly and their range over the
        steady cycle (protocol × bolt) [N]."""
        lo, hi = self.bolt_force_range
        dims = ("protocol", "bolt")
        return {"bolt_force": (dims, self.bolt_force, {
                    "units": "N", "long_name": "bolt force after the assembly"}),
                "bolt_force_min": (dims, lo, {
                    "units": "N", "long_name": "least bolt force over the steady cycle"}),
                "bolt_force_max": (dims, hi, {
                    "units": "N", "long_name": "largest bolt force over the steady cycle"})}

    def _coordinates(self) -> dict:
        """The coordinates of the Dataset (protocols, bolts, nodes, meshes, cycles)."""
        c = self.contact
        n, k = c.n_nodes, c.bolt_count
        coords = c.reduced.coordinates
        hist_len = max(len(r.solution.dissipation_history) for r in self.runs)
        return {
            "protocol": ("protocol", [p.name for p in self.protocols],
                         {"units": "1", "long_name": "assembly protocol"}),
            "order": ("protocol", [p.label for p in self.protocols],
                      {"units": "1", "long_name": "tightening order"}),
            "bolt": ("bolt", np.arange(k), {"units": "1", "long_name": "bolt (from 0)"}),
            "node": ("node", np.arange(n), {"units": "1", "long_name": "node (from 0)"}),
            "component": ("component", ["t1", "t2"],
                          {"units": "1", "long_name": "tangent direction"}),
            "cycle": ("cycle", np.arange(1, hist_len + 1),
                      {"units": "1", "long_name": "cycle"}),
            "mesh": ("mesh", np.arange(len(self.mesh.spacing)),
                     {"units": "1", "long_name": "mesh (coarse to fine)"}),
            "mesh_spacing": ("mesh", np.array(self.mesh.spacing),
                             {"units": "m", "long_name": "node spacing h"}),
            "x": ("node", coords[:, 0], {"units": "m", "long_name": "node coordinate x"}),
            "y": ("node", coords[:, 1], {"units": "m", "long_name": "node coordinate y"}),
            "z": ("node", coords[:, 2], {"units": "m", "long_name": "node coordinate z"}),
        }

    def figures(self, dataset: xr.Dataset | None = None) -> dict[str, Any]:
        """``dissipation_by_protocol`` (with mesh error bars), ``slip_maps``,
        ``dissipation_maps``, ``dissipation_by_bolt``, ``dissipation_history``."""
        from slipcycle.plot import joints as plots  # matplotlib only for figures

        ds = self.to_dataset() if dataset is None else dataset
        # partials of module-level functions: picklable, so drawn by the CLI's workers
        return {
            "dissipation_by_protocol": partial(plots.dissipation_by_protocol, ds,
                                               self.settings.difference_tol),
            # the geometry [m] outlines plates, holes and washers on the interface maps
            "slip_maps": partial(plots.slip_maps, ds, dict(self.contact.description)),
            "dissipation_maps": partial(plots.dissipation_maps, ds,
                                        dict(self.contact.description)),
            "dissipation_by_bolt": partial(plots.dissipation_by_bolt, ds),
            "dissipation_history": partial(plots.dissipation_history, ds),
        }

    def write_fields(self, directory: str | Path) -> list[Path]:
        """The steady cycle's contact fields of every protocol for ParaView
        (``directory/<protocol>/interface.xdmf`` …, :func:`~slipcycle.discrete3d.fields.
        write_fields`).

        Returns
        -------
        list of Path
        """
        files = []
        for p, r in zip(self.protocols, self.runs, strict=True):
            if r.case.fields:
                target = Path(directory) / p.name
                target.mkdir(parents=True, exist_ok=True)
                files += r.write_fields(target)
        return files

    def report(self) -> str:
        """A Markdown report comparing the protocols (``report.md``)."""
        return report_markdown(self)

    def to_outputs(self):
        """Summary, Dataset, figures, ``report.md`` and the field files under
        ``fields/<protocol>/``."""
        out = super().to_outputs()
        out.extra_files["report.md"] = lambda path: path.write_text(self.report(),
                                                                    encoding="utf-8")
        if any(r.case.fields for r in self.runs):
            out.extra_files["fields/README.txt"] = self._write_all_fields
        return out

    def _write_all_fields(self, path: Path) -> None:
        files = self.write_fields(path.parent)
        path.write_text("Contact fields of the steady cycle of each protocol (open in "
                        "ParaView):\n" + "".join(f"{f.relative_to(path.parent)}\n"
                                                 for f in files), encoding="utf-8")


def _finite(x) -> float | None:
    return None if x is None or not np.isfinite(x) else float(x)


def _spread(values: np.ndarray) -> float:
    vmax = float(np.max(values))
    return float((vmax - np.min(values)) / vmax) if vmax > 0 else 0.0


def _mesh_convergence(mesh: MeshRuns, rtol: float) -> tuple:
    """One MeshConvergence per protocol (None per protocol with one mesh)."""
    if len(mesh.spacing) < 2:
        return tuple(None for _ in range(mesh.dissipation.shape[1]))
    return tuple(mesh_convergence(mesh.spacing, tuple(float(v) for v in mesh.dissipation[:, j]),
                                  rtol=rtol, unit="J")
                 for j in range(mesh.dissipation.shape[1]))
