"""The service's values that need no gRPC: TLS settings, models and the
geodesic triangulation (what :class:`geodex.Client` returns; importable,
and usable in type hints, without the client's dependencies)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Dict, NamedTuple, Optional, Tuple

import numpy as np

from ._arrays import SurfacePoints

__all__ = ["Tls", "Model", "Triangulation"]


@dataclass(frozen=True)
class Tls:
    """TLS settings of :func:`connect`.

    Attributes
    ----------
    ca_file : str, optional
        PEM roots that verify the server's certificate; None: the system's.
    cert_file, key_file : str, optional
        The client's PEM certificate chain and private key (mutual TLS).
    server_name : str, optional
        The name checked against the server's certificate, when it is not
        the address's host (tests with self-signed certificates).
    """

    ca_file: Optional[str] = None
    cert_file: Optional[str] = None
    key_file: Optional[str] = None
    server_name: Optional[str] = None


@dataclass(frozen=True, repr=False)
class Model:
    """A model as the server describes it (GetModel, ListModels).

    ``state`` is "LOADING", "SERVING" or "FAILED" (then ``reason`` says
    why); vertex and face counts are those of the mesh file;
    ``build_report`` holds the builder's validation and accuracy figures
    ("key" -> "value"); ``report`` the same report as a structured dict
    (``Client.info``), empty when the server sends none.

    Printed, a model is one line (``repr``): its name, version, state,
    counts, size and the error target's verdict; the whole report is
    ``model.report`` (or ``client.info(model.name)``).
    """

    name: str
    version: int
    available_versions: Tuple[int, ...]
    state: str
    reason: str
    num_vertices: int
    num_faces: int
    num_samples: int
    num_triangles: int
    bbox_min: Tuple[float, ...]
    bbox_max: Tuple[float, ...]
    requested_samples: int
    seed: int
    samples_added_by_repair: int
    builder_version: str
    build_report: Dict[str, str] = field(default_factory=dict)
    mapped_bytes: int = 0
    mesh_hash: int = 0
    report: Dict[str, Any] = field(default_factory=dict)

    @property
    def verdict(self) -> str:
        """The build report's verdict on the error target ("0.500% met in 1
        round ..."); empty without a report."""
        target = self.report.get("target") if self.report else None
        return str(target.get("verdict", "")) if isinstance(target, dict) else ""

    def __repr__(self) -> str:
        head = f"geodex.Model({self.name!r}, version {self.version}, {self.state}"
        if self.state != "SERVING":
            return head + (f": {self.reason})" if self.reason else ")")
        size = f", {self.mapped_bytes / 1048576:.2f} MiB" if self.mapped_bytes else ""
        verdict = self.verdict
        if len(verdict) > 60:
            verdict = verdict[:57].rstrip() + "..."
        return (
            f"{head}: {self.num_vertices} vertices, {self.num_faces} faces, "
            f"m = {self.num_samples}{size}"
            + (f"; error target {verdict}" if verdict else "")
            + ")"
        )


class Triangulation(NamedTuple):
    """The geodesic triangulation of a model's index (GetTriangulation).

    Attributes
    ----------
    sample_vertices : numpy.ndarray
        (m,) int32 the mesh vertex of each sample (-1 for a sample on the
        midpoint of a long edge, which is no vertex of the mesh).
    sample_positions : numpy.ndarray
        (m, 3) float64.
    sample_points : SurfacePoints
        The samples as surface points.
    triangle_corners : numpy.ndarray
        (t, 3) int32 sample ids of each geodesic triangle's corners.
    triangle_neighbors : numpy.ndarray
        (t, 3) int32: across side (k, k+1 mod 3) of triangle t lies
        ``triangle_neighbors[t, k]`` (-1: none).
    vertex_triangles : numpy.ndarray
        (n,) int32 the geodesic triangle holding each mesh vertex (-1 for
        vertices no face uses).
    version : int
        The model version.
    """

    sample_vertices: np.ndarray
    sample_positions: np.ndarray
    sample_points: SurfacePoints
    triangle_corners: np.ndarray
    triangle_neighbors: np.ndarray
    vertex_triangles: np.ndarray
    version: int
