"""Start values of the diagnosis's candidate fits (screening and simulator fits).

The catalogue gives each candidate one start (:mod:`uvsim.diagnosis.candidates`); a
tether's pull direction and, for the variants with a slack length, the anchor's distance
are what the data decide, so those get more (:func:`candidate_starts`, :func:`slack_starts`).
"""
from __future__ import annotations

from typing import Mapping

import numpy as np

from uvsim.diagnosis.candidates import ANCHOR_START_SOUTH, Candidate

#: Distance (m) from the reference position to which a slack variant's extra start moves
#: the anchor of the best simpler tether (:func:`slack_starts`): a few times a tank run's
#: excursions (+-0.5 m in the benchmark's start region), so the pull's direction hardly
#: turns over a run; anchors farther out along the same line differ mainly in slack length
#: and stiffness, which the Gauss-Newton steps then adjust.
SLACK_START_DISTANCE = 5.0
#: Gauss-Newton steps of a slack variant's screening (2 for the others): the slack length
#: and the anchor's distance are nearly interchangeable along the line, so a start moved
#: out needs more steps (the taut-cable test of tests/test_diagnosis.py: reduction 0.20
#: after 2 steps, 0.32 after 3 and 4).
SLACK_GN_ITERATIONS = 4


def slack_starts(c: Candidate, start: Mapping[str, float]) -> list[dict]:
    """The extra start of a tether variant with a free slack length: the anchor of ``start``
    (the best simpler tether, fitted without slack) moved out along its line from the
    reference position to :data:`SLACK_START_DISTANCE`, with the slack length that keeps
    the pull at the reference position (``k (D - L_s) = k L_0``).  Why: a cable taut from a
    spool metres away pulls along one direction and barely across it, which an elastic line
    without slack cannot describe, so the simpler fit puts its anchor next to the vehicle and
    a slack length started at 0 stays there (benchmark pair 101: a horizontal cable with
    2.7 m of slack; from that start the slack variants removed 0-15 % of the equation error,
    from this one `horizontal_full` removes 43 %).  Empty when the variant has no slack,
    ``start`` has one already, or its anchor is at the reference position or beyond the
    distance."""
    if "tether_slack_length" not in c.free or float(start.get("tether_slack_length", 0.0)) > 0.0:
        return []
    names = ("tether_anchor_n", "tether_anchor_e", "tether_anchor_d")
    ref = reference_position(c)
    free = np.array([n in c.free for n in names])
    v = np.where(free, np.array([float(start.get(n, r)) for n, r in zip(names, ref)]) - ref, 0.0)
    L0 = float(np.linalg.norm(v))
    if not 1e-3 < L0 < SLACK_START_DISTANCE:
        return []
    anchor = ref + v / L0 * SLACK_START_DISTANCE
    return [{**start, "tether_slack_length": SLACK_START_DISTANCE - L0,
             **{n: float(a) for n, a, f in zip(names, anchor, free) if f}}]


def candidate_starts(c: Candidate) -> list[dict]:
    """Start values of a candidate's multi-start: the catalogue start, plus for a tether
    anchors in four directions (the pull direction is what the data decide)."""
    if c.effect != "tether":
        return [dict(c.start)]
    out = []
    n0, e0, _ = reference_position(c)
    for dn, de in ((-5.0, 0.0), (5.0, 0.0), (0.0, -5.0), (0.0, 5.0)):
        out.append({**c.start, "tether_anchor_n": n0 + dn, "tether_anchor_e": e0 + de})
    return out


def reference_position(c: Candidate) -> np.ndarray:
    """The reference position (m, NED) of a tether candidate (the training runs' mean start):
    its catalogue start has the anchor ANCHOR_START_SOUTH south of it (uvsim.diagnosis.candidates)."""
    return np.array([c.start["tether_anchor_n"] + ANCHOR_START_SOUTH, c.start["tether_anchor_e"],
                     c.start["tether_anchor_d"]])
