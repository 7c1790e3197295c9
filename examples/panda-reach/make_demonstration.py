"""Write reach.csv: a demonstration of the Panda arm reaching from one pose to another.

A stand-in for a recorded motion: 2.5 s at 100 Hz of the seven arm joints (the fingers are not
in the file, so latentoc locks them at the problem's fixed_pose). A minimum-jerk blend between
a start and a goal pose plus a detour, a bump that lifts and twists the arm on the way and
returns, with amplitudes drawn from a seeded generator. Both have zero velocity and
acceleration at the ends, so the arm starts and ends at rest; the detour makes the motion a
valid but clearly not optimal one that optimisation can improve on.

    python examples/panda-reach/make_demonstration.py   # rewrites reach.csv next to this file
"""
from pathlib import Path

import numpy as np

SEED = 23
DURATION = 2.5  # s
RATE = 100.0  # Hz
START = np.array([0.0, -0.6, 0.0, -2.2, 0.0, 1.6, 0.8])  # rad, panda_joint1 .. panda_joint7
GOAL = np.array([1.0, 0.2, 0.3, -1.6, 0.2, 1.9, 1.4])
DETOUR_SCALE = np.array([0.3, 0.4, 0.3, 0.4, 0.5, 0.3, 0.5])  # rad, the largest detour of each joint


def demonstration(seed: int = SEED) -> tuple[np.ndarray, np.ndarray]:
    """(t, Q): q(t) = start + (goal - start) s(u) + detour b(u), u = t / T, with the minimum-jerk
    s(u) = 10 u^3 - 15 u^4 + 6 u^5 and the bump b(u) = 64 u^3 (1 - u)^3 (1 at u = 1/2)."""
    detour = DETOUR_SCALE * np.random.default_rng(seed).uniform(0.5, 1.0, size=7)
    t = np.linspace(0.0, DURATION, int(round(DURATION * RATE)) + 1)
    u = t / DURATION
    s = 10 * u**3 - 15 * u**4 + 6 * u**5
    b = 64 * u**3 * (1 - u) ** 3
    return t, START + np.outer(s, GOAL - START) + np.outer(b, detour)


def main() -> None:
    t, Q = demonstration()
    names = [f"panda_joint{i}" for i in range(1, 8)]
    lines = ["t," + ",".join(names)] + [",".join(f"{v:.9f}" for v in (ti, *qi)) for ti, qi in zip(t, Q)]
    out = Path(__file__).with_name("reach.csv")
    out.write_text("\n".join(lines) + "\n")
    print(f"wrote {out}: {len(t)} samples of {len(names)} joints")


if __name__ == "__main__":
    main()
