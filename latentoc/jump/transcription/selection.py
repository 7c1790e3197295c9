"""Which of the jump's inequality rows enter its NLP, and where its samples sit: the exchange's state.

Rows only where they can bind: the contact nodes carry their equality and placement rows always,
but a torque limit (Eq. 34) or a polygon edge (ZMP, COM; Eq. 35-36) only where it is within a
margin of binding or was violated. Between the nodes, a **contact sample** is a time with its own
friction-pyramid edge weights (the wrench split is part of the solution there), its base rows and
the torque and polygon rows chosen for it; a **flight sample** a time with its own pitch rate and
base accelerations, the free-fall rows and chosen torque rows; the **tube** a set of times where
sigma^2 <= delta (Eq. 29). :mod:`..solve.exchange` decides what is chosen; :mod:`.nlp` builds it.
"""
from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

__all__ = ["Selection", "POLYGON_EDGES", "FLIGHT_SAMPLE"]

POLYGON_EDGES = 4  # support polygon edges: each of the ZMP's and the COM's rows (zmp_polygon, com_polygon)
FLIGHT_SAMPLE = ("pd", "ax", "az", "pdd")  # a flight sample's variables (:mod:`..rows.flight`)


def _key(t: np.ndarray) -> np.ndarray:
    return np.round(np.asarray(t, float), 9)


@dataclass
class Selection:
    """The chosen rows (module doc). Masks are bool; torque masks are over the joints whose torque
    rows the NLP keeps (:attr:`latentoc.jump.robot.jump_robot.JumpRobot.unmirrored`), polygon masks over the
    ZMP's edges then the COM's (2 x :data:`POLYGON_EDGES`)."""

    node_torque: np.ndarray  # (contact nodes, joints)
    node_polygon: np.ndarray  # (contact nodes, 8)
    contact: np.ndarray  # contact sample times
    contact_torque: np.ndarray  # (contact samples, joints)
    contact_polygon: np.ndarray  # (contact samples, 8)
    flight: np.ndarray  # flight sample times
    flight_torque: np.ndarray  # (flight samples, joints)
    tube: np.ndarray  # tube times

    def __post_init__(self) -> None:
        for f in fields(self):
            dtype = float if f.name in ("contact", "flight", "tube") else bool
            setattr(self, f.name, np.asarray(getattr(self, f.name), dtype))
        for times, *masks in (("contact", "contact_torque", "contact_polygon"), ("flight", "flight_torque")):
            for m in masks:
                if getattr(self, m).shape[0] != len(getattr(self, times)):
                    raise ValueError(f"Selection.{m} has {getattr(self, m).shape[0]} rows for "
                                     f"{len(getattr(self, times))} {times} samples")

    @classmethod
    def empty(cls, n_nodes: int, n_joints: int, tube: np.ndarray) -> "Selection":
        """No torque or polygon rows, no samples; the tube at ``tube``."""
        z = np.zeros(0)
        return cls(np.zeros((n_nodes, n_joints)), np.zeros((n_nodes, 2 * POLYGON_EDGES)), z,
                   np.zeros((0, n_joints)), np.zeros((0, 2 * POLYGON_EDGES)), z, np.zeros((0, n_joints)), tube)

    @classmethod
    def every_node_row(cls, n_nodes: int, n_joints: int, tube: np.ndarray) -> "Selection":
        """Every torque and polygon row at the contact nodes, no samples: the full transcription."""
        s = cls.empty(n_nodes, n_joints, tube)
        s.node_torque[:], s.node_polygon[:] = True, True
        return s

    @property
    def n_joints(self) -> int:
        return self.node_torque.shape[1]

    def merged(self, other: "Selection") -> "Selection":
        """Both selections' rows: node masks or-ed, samples united (a time in both: masks or-ed)."""
        if self.node_torque.shape != other.node_torque.shape:
            raise ValueError("selections of different node grids or joints cannot be merged")
        contact, ct, cp = _union(self.contact, other.contact, (self.contact_torque, other.contact_torque),
                                 (self.contact_polygon, other.contact_polygon))
        flight, ft = _union(self.flight, other.flight, (self.flight_torque, other.flight_torque))
        return Selection(self.node_torque | other.node_torque, self.node_polygon | other.node_polygon,
                         contact, ct, cp, flight, ft, np.union1d(_key(self.tube), _key(other.tube)))

    def with_samples(self, contact: np.ndarray, flight: np.ndarray) -> "Selection":
        """This selection with contact samples at ``contact`` and flight samples at ``flight``, each with
        every torque row (and the contact samples every polygon row that applies)."""
        nj, npoly = self.n_joints, 2 * POLYGON_EDGES
        return self.merged(Selection(np.zeros_like(self.node_torque), np.zeros_like(self.node_polygon),
                                     contact, np.ones((len(contact), nj)), np.ones((len(contact), npoly)),
                                     flight, np.ones((len(flight), nj)), np.zeros(0)))

    def rows(self) -> int:
        """Chosen torque and polygon rows, and samples' rows of the tube."""
        return int(self.node_torque.sum() + self.node_polygon.sum() + self.contact_torque.sum()
                   + self.contact_polygon.sum() + self.flight_torque.sum() + len(self.tube))

    def covers(self, other: "Selection") -> bool:
        """Whether every row of ``other`` is in this selection."""
        return self.merged(other).rows() == self.rows() and len(self.merged(other).contact) == len(self.contact) \
            and len(self.merged(other).flight) == len(self.flight)

    def summary(self) -> dict[str, int]:
        return {"node_torque_rows": int(self.node_torque.sum()), "node_polygon_rows": int(self.node_polygon.sum()),
                "contact_samples": int(len(self.contact)), "contact_sample_rows": int(self.contact_torque.sum()
                                                                                      + self.contact_polygon.sum()),
                "flight_samples": int(len(self.flight)), "flight_torque_rows": int(self.flight_torque.sum()),
                "tube_points": int(len(self.tube))}


def _union(ta: np.ndarray, tb: np.ndarray, *masks: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, ...]:
    """Sorted union of sample times ``ta`` and ``tb`` (to 1 ns) with each pair of masks or-ed."""
    t = np.union1d(_key(ta), _key(tb))
    out: list[np.ndarray] = [t]
    for a, b in masks:
        m = np.zeros((len(t), a.shape[1]), bool)
        m[np.searchsorted(t, _key(ta))] |= a
        m[np.searchsorted(t, _key(tb))] |= b
        out.append(m)
    return tuple(out)
