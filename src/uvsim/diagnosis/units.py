"""The catalogue's thruster-unit variants (effect ``thruster_gain``, built by
:func:`uvsim.diagnosis.candidates._gain`) and the answers a report gives for them.

Per thruster ``i`` of a vehicle with thruster inputs (generalized-force inputs: through the
pseudo-inverse allocation):

* ``unit_i``: the unit's gain (``thruster_gain_i``, 0-1.5; 0 is a dead unit, named as such);
* ``reversed_i``: the unit pushes the wrong way (mounted or wired reversed: gain -1.5-0);
* ``fouled_i``: the unit's gain *and* its reverse ratio (``thruster_reverse_i``, the factor on its
  reverse thrust beyond the curve's own reverse branch, :mod:`uvsim.forces.actuators`): a line or
  weed round the propeller, or a damaged blade, costs a unit thrust both ways and more of it in
  reverse (issue 48's fouled unit; the T200's reverse branch itself is already ~80 % of forward
  thrust in the curve, Blue Robotics' 16 V data, so the ratio is relative to the curve's reverse
  thrust).  The ratio is searched within :data:`FOULED_REVERSE_RANGE`, at most 1: that is what the
  variant says (reverse thrust hit at least as hard as forward); a unit that pushes *more* in
  reverse than its curve is no fouling but a curve or an asymmetry (``thrust_asymmetry``, up to
  1.5), and a fit that runs to 1 is on the edge of the search range, so not named (the unit's gain
  alone, ``unit_i``, is then the form that describes it).  Why: with the ratio free up to 1.5 the
  variant named "thruster 5 delivers 0.96 forward and 1.05 in reverse" on a field log with a
  current and no thruster fault (seed 15; validation cost 5.5 % lower, just past the 5 %);

and ``all``: every unit's gain.  A report names the faulty *unit* (``unit_i``) for both of its
forms, the gain alone and the gain with a reverse ratio: what the catalogue can say about a unit
that delivers less than its curve is which unit and by how much each way
(:func:`reported_variant`; ``fitted_as`` in the report keeps the form, :func:`plain_answer` says it in words).
"""
from __future__ import annotations

from typing import Mapping

import numpy as np

from uvsim.fitting.parameters import REVERSE_RANGE

#: Search range of a fouled unit's reverse ratio (module docstring): REVERSE_RANGE's floor, at most 1.
FOULED_REVERSE_RANGE = (REVERSE_RANGE[0], 1.0)
#: A fitted gain below this is "no thrust": the dead-unit answer (2 % of a T200's 51.5 N at full
#: command, Blue Robotics' 16 V data, is about 1 N: no more than a tether's or a current's pull).
DEAD_GAIN = 0.02


def reported_variant(c, values: Mapping[str, float]) -> str:
    """The variant a report names: ``c.variant``, except a reversed unit whose fitted gain is within
    :data:`DEAD_GAIN` of 0, which is the unit's own variant at 0 (``unit_i``: the same model, a dead
    unit; field-log benchmark, dead case seed 0, fitted from the reversed side at -0.00), and a fouled
    unit, which is the unit (``unit_i``) with its reverse ratio (module docstring)."""
    if c.effect == "thruster_gain" and "unit" in c.tags:
        i = c.tags["unit"]
        if c.tags.get("fouled"):
            return f"unit_{i}"
        if c.tags.get("reversed") and abs(float(values.get(f"thruster_gain_{i}", -1.0))) < DEAD_GAIN:
            return f"unit_{i}"
    return c.variant


def farthest_from_median(gains: Mapping):
    """The key of ``gains`` ({key: gain}) farthest from the median of all of them (the first in
    order on a tie): the one unit that stands out of every unit's gain."""
    med = float(np.median(list(gains.values())))
    return max(gains, key=lambda k: abs(gains[k] - med))


def plain_answer(c, values: Mapping[str, float]) -> str | None:
    """The answer in words when it is at a physical limit or names a fault: a dead, a reversed or a
    fouled thruster (issue 48: "thruster 1 gives no thrust"), and for every unit's gain the unit
    farthest from the others with the others' range; None otherwise."""
    if c.effect != "thruster_gain":
        return None
    if "unit" not in c.tags:  # every gain: name the dead units among them, else the one farthest out
        gains = {int(n.rsplit("_", 1)[1]): float(values.get(n, 1.0)) for n in c.free}
        dead = [i for i, g in gains.items() if g < DEAD_GAIN]
        if not dead:
            # which unit stands out is what a reader looks for (field logs at 50 Hz, weak seeds 3 and
            # 23: thruster 7 at 0.49, the other seven 0.78-0.82, every gain 9 % better on validation
            # than one unit beside a common scale, so "all" is named)
            k = farthest_from_median(gains)
            rest = [g for i, g in gains.items() if i != k]
            return (f"every unit's gain: thruster {k} at {gains[k]:.2f} of its curve, the other {len(rest)} at "
                    f"{min(rest):.2f}-{max(rest):.2f}") if rest else None
        rest = [g for i, g in gains.items() if i not in dead]
        return (f"thruster{'s' if len(dead) > 1 else ''} {', '.join(map(str, dead))} give{'' if len(dead) > 1 else 's'} "
                "no thrust (a dead unit)" + (f"; the other gains {min(rest):.2f}-{max(rest):.2f}" if rest else ""))
    i = c.tags["unit"]
    g = float(values.get(f"thruster_gain_{i}", 1.0))
    if abs(g) < DEAD_GAIN:  # gain 0 is in both ranges: a reversed unit fitted at 0 is a dead one
        return f"thruster {i} gives no thrust (gain {g:.3f}: a dead unit)"
    if c.tags.get("reversed"):
        return f"thruster {i} pushes the wrong way (mounted or wired reversed), at {abs(g):.2f} of its curve"
    if c.tags.get("fouled"):
        r = float(values.get(f"thruster_reverse_{i}", 1.0))
        return (f"thruster {i} delivers {g:.2f} of its curve forward and {g * r:.2f} in reverse (gain {g:.2f}, "
                f"reverse ratio {r:.2f}: fouled or damaged)")
    return None
