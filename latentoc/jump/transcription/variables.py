"""The broad jump's decision vector: named blocks and their positions in w.

* ``P``: the free control points of the latent (or joint) spline (the end points stay on the
  training path);
* ``x_L``: the landing toe tip's ground point (the jump distance, Eq. 33);
* ``lam``: friction-pyramid edge weights at the contact nodes (heel, ball, toe, pad; body weights);
* ``c_to``, ``cd_to``, ``L_to``: the takeoff COM position, velocity and angular momentum;
* ``pitch_flight``: the base pitch at the flight nodes;
* ``lam_sample``: the contact samples' edge weights (:mod:`.selection`);
* ``flight_sample``: the flight samples' pitch rate and base accelerations (pd, ax, az, pdd).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from latentoc.jump.robot.feet import EDGES

__all__ = ["JumpVariables"]


@dataclass
class JumpVariables:
    """Shapes and positions (row-major within each block) of the decision blocks."""

    shapes: dict[str, tuple[int, ...]]

    def __post_init__(self) -> None:
        self.slices, off = {}, 0
        for name, shape in self.shapes.items():
            n = int(np.prod(shape))
            self.slices[name] = slice(off, off + n)
            off += n
        self.n = off

    @classmethod
    def layout(cls, n_control: int, d: int, n_contact: int, n_flight: int, n_contact_samples: int = 0,
               n_flight_samples: int = 0) -> "JumpVariables":
        return cls({"P": (n_control - 2, d), "x_L": (1,), "lam": (n_contact, EDGES), "c_to": (2,), "cd_to": (2,),
                    "L_to": (1,), "pitch_flight": (n_flight,), "lam_sample": (n_contact_samples, EDGES),
                    "flight_sample": (n_flight_samples, 4)})

    def index(self, name: str) -> np.ndarray:
        """Positions in w of block ``name``, in its shape."""
        return np.arange(self.slices[name].start, self.slices[name].stop).reshape(self.shapes[name])

    def latent_index(self) -> np.ndarray:
        """(n_control x d) positions of every control point of the path, -1 for the fixed end points."""
        P = self.index("P")
        fixed = -np.ones((1, P.shape[1]), np.int64)
        return np.vstack([fixed, P, fixed])

    def unpack(self, w: np.ndarray) -> dict[str, np.ndarray]:
        w = np.asarray(w, float).ravel()
        return {name: w[s].reshape(self.shapes[name]) for name, s in self.slices.items()}

    def pack(self, values: dict[str, Any]) -> np.ndarray:
        w = np.zeros(self.n)
        for name, v in values.items():
            w[self.slices[name]] = np.asarray(v, float).reshape(self.shapes[name]).ravel()
        return w
