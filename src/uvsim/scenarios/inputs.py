"""Run shapes: what the operator or controller commanded, on the log's sample grid.

A run's shape is a plain dict (stored in the scenario spec and the truth record).  It
defines a generalized force ``tau_d(t)`` (``X, Y, Z`` in N, ``K, M, N`` in N m, body
frame); :func:`actuator_inputs` turns it into the logged input columns of the dataset's
kind:

* ``force``: ``X..N = tau_d + tau_trim``;
* ``thrust``: ``f = A^+ (tau_d + tau_trim)`` (the controller's pseudo-inverse allocation);
* ``pwm``: the ESC command of each ``f`` from the thrust table, whole microseconds.

``tau_trim = [0, 0, B - W, 0, 0, 0]`` holds a positively buoyant vehicle at depth (a
constant ``Z``; with thrusters an offset of the vertical ones).

Shapes (``shape`` key):

=================  ==========================================================================
``step``           ``amplitude`` on ``[t_on, t_off)``, one DOF; ``t_on = 0`` or later
``step_reverse``   ``+amplitude`` on ``[t_on, t_reverse)``, ``-amplitude`` on ``[t_reverse, t_off)``
``sine``           ``amplitude sin(2 pi frequency t + phase)``, one DOF
``decay``          free decay: a short push (``push``: a step of 0.5-1.5 s) or an initial
                   velocity (``velocity``: ``initial_velocity`` in the DOF, no input)
``spiral``         constant surge, heave and yaw together from ``t_on`` (``forces``)
``telegraph``      several DOFs at once, each switching between ``+level`` and ``-level`` at
                   random times (``switches``; dwell times exponential, mean 1-3 s)
``pilot``          a pilot on a gamepad in ArduSub's manual mode: 2-4 DOFs (mostly surge, yaw,
                   heave), each a stick deflection ``s(t)`` in [-1, 1] (``sticks``: knots
                   ``[t, s]``, linear between: ramps of 0.2-1 s to a deflection of 0.3-1, holds
                   of 0.5-3 s, releases to the centre in 0.1-0.3 s, rests) times the force of a
                   full deflection (``gains``), with the thumb's corrections: ``tau_j = gain_j
                   s_j(t) (1 + sum_i a_i sin(2 pi f_i t + phi_i))`` (``tremor``: three sines of
                   0.2-1.5 Hz, ``a_i`` up to 0.05 each)
=================  ==========================================================================

Every shape is allocated to the thrusters the same way (:func:`actuator_inputs`) and scaled
down until no thruster needs more than :data:`THRUST_MARGIN` of its limit.
"""
from __future__ import annotations

import numpy as np

from uvsim.scenarios.effects import ScenarioError

DOF_NAMES = ("surge", "sway", "heave", "roll", "pitch", "yaw")
FORCE_NAMES = ("X", "Y", "Z", "K", "M", "N")
#: Command amplitude ranges per DOF (N for surge/sway/heave, N m for roll/pitch/yaw).  They keep
#: the BlueROV2 below ~0.85 m/s (seed 000 assumption 6: < 1 m/s; terminal surge speed at 25 N
#: with X_uu = -35 kg/m is 0.85 m/s) and roll/pitch below ~22 deg (static angle
#: asin(K / (B |z_b|)) with B |z_b| = 3.2 N m, seed 000 Table 2).
AMPLITUDE_RANGES = {"surge": (8.0, 25.0), "sway": (8.0, 25.0), "heave": (8.0, 25.0),
                    "roll": (0.3, 1.2), "pitch": (0.3, 1.2), "yaw": (0.5, 2.5)}
#: Initial speeds of ``decay`` runs with ``velocity`` (m/s or rad/s).
DECAY_VELOCITY = {"surge": (0.2, 0.5), "sway": (0.2, 0.5), "heave": (0.15, 0.4),
                  "roll": (0.5, 1.5), "pitch": (0.5, 1.5), "yaw": (0.5, 1.5)}
SHAPES = ("step", "step_reverse", "sine", "decay", "spiral", "telegraph", "pilot")
#: Fraction of each thruster's limit (forward 51.5 N / reverse 39.9 N for the T200 at 16 V)
#: that a run may command; larger amplitudes are scaled down when the run is drawn.
THRUST_MARGIN = 0.8

# Pilot runs (``pilot`` shape).  ArduSub's manual mode passes the sticks straight to the
# motor mix (no stabilization, ardusub.com "Flight Modes"), so a stick deflection is a
# generalized-force command; the numbers below describe a thumb on a gamepad stick.
#: How often a pilot uses each DOF: forward, yaw and vertical are the main sticks; lateral is
#: used less, roll and pitch (a button-shifted function on a BlueROV2 Heavy) rarely.
PILOT_DOF_WEIGHTS = {"surge": 0.25, "sway": 0.14, "heave": 0.2, "roll": 0.08, "pitch": 0.08, "yaw": 0.25}
#: Seconds a pilot takes to push a stick to a new deflection (a deliberate thumb movement,
#: a few tenths of a second; slow ones up to 1 s).
PILOT_RAMP = (0.2, 1.0)
#: Seconds a deflection is held (a manoeuvre of a few body lengths at < 1 m/s).
PILOT_HOLD = (0.5, 3.0)
#: Seconds a released stick takes back to the centre (a spring-centred stick snaps back in
#: ~0.05 s; a pilot usually eases off, and 0.1 s keeps the command smooth on a 100-200 Hz log).
PILOT_RELEASE = (0.1, 0.3)
#: Seconds at the centre between manoeuvres, and before the first.
PILOT_REST = (0.3, 2.0)
#: Magnitude of a held deflection (fraction of full stick).
PILOT_DEFLECTION = (0.3, 1.0)
#: Probability that a hold ends with the stick released (else it moves to another deflection).
PILOT_RELEASE_P = 0.6
#: The thumb's corrections while a stick is deflected: three sines per DOF of 0.2-1.5 Hz
#: (slow corrections by eye; physiological tremor, 8-12 Hz, is far smaller on a stick) with
#: relative amplitudes up to 0.05 each (at most +-15 % of the deflection).
PILOT_TREMOR_HZ = (0.2, 1.5)
PILOT_TREMOR_AMPLITUDE = 0.05


def _dof_index(dof: str) -> int:
    if dof not in DOF_NAMES:
        raise ScenarioError(f"run shape: dof {dof!r}; expected one of {list(DOF_NAMES)}")
    return DOF_NAMES.index(dof)


def force_profile(shape: dict, t: np.ndarray) -> np.ndarray:
    """Generalized force ``tau_d`` (n_t, 6) of a run shape at the sample times ``t`` (s)."""
    t = np.asarray(t, dtype=float)
    out = np.zeros((t.size, 6))
    kind = shape.get("shape")
    if kind in ("step", "step_reverse", "sine", "decay"):
        j = _dof_index(shape["dof"])
        a = float(shape.get("amplitude", 0.0))
        if kind == "step" or (kind == "decay" and shape.get("variant") == "push"):
            out[:, j] = a * ((t >= shape["t_on"]) & (t < shape["t_off"]))
        elif kind == "step_reverse":
            out[:, j] = a * (((t >= shape["t_on"]) & (t < shape["t_reverse"])).astype(float)
                             - ((t >= shape["t_reverse"]) & (t < shape["t_off"])))
        elif kind == "sine":
            out[:, j] = a * np.sin(2 * np.pi * shape["frequency"] * t + shape["phase"])
    elif kind == "spiral":
        on = t >= shape["t_on"]
        for name, val in shape["forces"].items():
            out[:, FORCE_NAMES.index(name)] = val * on
    elif kind == "telegraph":
        for name, level in shape["levels"].items():
            n_sw = np.searchsorted(np.asarray(shape["switches"][name], dtype=float), t, side="right")
            out[:, FORCE_NAMES.index(name)] = shape["signs"][name] * level * (1.0 - 2.0 * (n_sw % 2))
    elif kind == "pilot":
        for name, gain in shape["gains"].items():
            knots = np.asarray(shape["sticks"][name], dtype=float)
            stick = np.interp(t, knots[:, 0], knots[:, 1])
            tr = shape["tremor"][name]
            wobble = sum(a * np.sin(2 * np.pi * f * t + ph)
                         for a, f, ph in zip(tr["amplitude"], tr["frequency"], tr["phase"]))
            out[:, FORCE_NAMES.index(name)] = gain * stick * (1.0 + wobble)
    else:
        raise ScenarioError(f"run shape {kind!r}: expected one of {list(SHAPES)}")
    return out


def initial_velocity(shape: dict) -> np.ndarray:
    """Body velocity (6,) at t = 0: zero except for ``decay`` runs with ``velocity``."""
    nu = np.zeros(6)
    if shape.get("shape") == "decay" and shape.get("variant") == "velocity":
        nu[_dof_index(shape["dof"])] = shape["initial_velocity"]
    return nu


def actuator_inputs(tau: np.ndarray, kind: str, allocation: np.ndarray, table, trim: float
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Logged inputs and the commanded actuator outputs for a generalized force.

    Parameters
    ----------
    tau : (n_t, 6) commanded generalized force without trim.
    kind : "force", "thrust" or "pwm".
    allocation : (6, k) thruster allocation ``A``.
    table : thrust table (``thrust``, ``command_for``).
    trim : N, constant downward force ``B - W`` that holds the vehicle at depth.

    Returns
    -------
    inputs : (n_t, 6 or k) the log's input columns (N / N m, N, or us).
    commanded : (n_t, 6 or k) what the actuators are told to deliver (N / N m or N): the
        inputs themselves, or the table's thrust at each PWM command.
    """
    total = np.array(tau, dtype=float)
    total[:, 2] += trim
    if kind == "force":
        return total, total.copy()
    thrust = total @ np.linalg.pinv(allocation).T
    if kind == "thrust":
        return thrust, thrust.copy()
    if kind == "pwm":
        pwm = table.command_for(thrust)
        return pwm, table.thrust(pwm)
    raise ScenarioError(f"input kind {kind!r}: expected force, thrust or pwm")


def thrust_utilization(tau: np.ndarray, allocation: np.ndarray, table, trim: float) -> float:
    """Largest ``|f_i| / limit_i`` over the run (limit: forward or reverse maximum)."""
    total = np.array(tau, dtype=float)
    total[:, 2] += trim
    f = total @ np.linalg.pinv(allocation).T
    return float(np.max(np.where(f >= 0, f / table.max_forward, f / table.max_reverse)))


def _amplitude(rng, dof: str) -> float:
    lo, hi = AMPLITUDE_RANGES[dof]
    return float(rng.uniform(lo, hi) * rng.choice([-1.0, 1.0]))


def sample_shape(rng: np.random.Generator, shape: str, duration: float, dof: str | None = None,
                 n_dofs: int | None = None) -> dict:
    """Draw the parameters of one run shape (see the module table)."""
    r2 = lambda x: round(float(x), 2)  # noqa: E731  - times on a 10 ms grid
    if shape in ("step", "step_reverse", "sine", "decay"):
        dof = dof or str(rng.choice(DOF_NAMES))
        d = {"shape": shape, "dof": dof}
        if shape == "step":
            t_on = 0.0 if rng.random() < 0.5 else r2(rng.uniform(0.5, 2.0))
            d.update(amplitude=_amplitude(rng, dof), t_on=t_on, t_off=r2(rng.uniform(0.55, 0.8) * duration))
        elif shape == "step_reverse":
            t_on = 0.0 if rng.random() < 0.5 else r2(rng.uniform(0.5, 1.5))
            t_off = rng.uniform(0.6, 0.8) * duration
            d.update(amplitude=_amplitude(rng, dof), t_on=t_on, t_reverse=r2(0.5 * (t_on + t_off)), t_off=r2(t_off))
        elif shape == "sine":
            d.update(amplitude=_amplitude(rng, dof), frequency=r2(rng.uniform(0.1, 0.5)),
                     phase=float(rng.uniform(0, 2 * np.pi)))
        else:
            if rng.random() < 0.5:
                lo, hi = DECAY_VELOCITY[dof]
                d.update(variant="velocity", initial_velocity=float(rng.uniform(lo, hi) * rng.choice([-1, 1])))
            else:
                t_on = r2(rng.uniform(0.3, 1.0))
                d.update(variant="push", amplitude=_amplitude(rng, dof), t_on=t_on,
                         t_off=r2(t_on + rng.uniform(0.5, 1.5)))
        return d
    if shape == "spiral":
        return {"shape": "spiral", "dof": "mixed", "t_on": r2(rng.uniform(0.0, 1.0)),
                "forces": {"X": float(rng.uniform(8, 18)), "Z": float(rng.uniform(4, 10) * rng.choice([-1, 1])),
                           "N": float(rng.uniform(0.6, 1.5) * rng.choice([-1, 1]))}}
    if shape == "telegraph":
        k = n_dofs or int(rng.integers(2, 5))
        dofs = sorted(rng.choice(6, size=k, replace=False).tolist())
        mean_dwell = rng.uniform(1.0, 3.0)
        levels, switches, signs = {}, {}, {}
        for j in dofs:
            name = FORCE_NAMES[j]
            lo, hi = AMPLITUDE_RANGES[DOF_NAMES[j]]
            levels[name] = float(rng.uniform(lo, hi) * 0.7)   # several DOFs share the thrusters
            times, tt = [], 0.0
            while True:
                tt += max(0.3, rng.exponential(mean_dwell))
                if tt >= duration:
                    break
                times.append(r2(tt))
            switches[name] = times
            signs[name] = float(rng.choice([-1.0, 1.0]))
        return {"shape": "telegraph", "dof": "mixed", "levels": levels, "switches": switches, "signs": signs}
    if shape == "pilot":
        return _pilot(rng, duration, r2)
    raise ScenarioError(f"run shape {shape!r}: expected one of {list(SHAPES)}")


def _pilot(rng: np.random.Generator, duration: float, r2) -> dict:
    """A pilot's run (module table; constants ``PILOT_*``)."""
    k = int(rng.integers(2, 5))
    w = np.array([PILOT_DOF_WEIGHTS[d] for d in DOF_NAMES])
    dofs = sorted(rng.choice(6, size=k, replace=False, p=w / w.sum()).tolist())
    gains, sticks, tremor = {}, {}, {}
    for j in dofs:
        name = FORCE_NAMES[j]
        lo, hi = AMPLITUDE_RANGES[DOF_NAMES[j]]
        gains[name] = float(rng.uniform(lo, hi))          # force of a full deflection (the pilot gain)
        tt = r2(rng.uniform(0.0, PILOT_REST[1]))
        knots = [[0.0, 0.0]] + ([[tt, 0.0]] if tt > 0 else [])
        while tt < duration:
            level = float(rng.uniform(*PILOT_DEFLECTION) * rng.choice([-1.0, 1.0]))
            tt = r2(tt + rng.uniform(*PILOT_RAMP))
            knots.append([tt, level])
            tt = r2(tt + rng.uniform(*PILOT_HOLD))
            knots.append([tt, level])
            if rng.random() < PILOT_RELEASE_P:
                tt = r2(tt + rng.uniform(*PILOT_RELEASE))
                knots.append([tt, 0.0])
                tt = r2(tt + rng.uniform(*PILOT_REST))
                knots.append([tt, 0.0])
        sticks[name] = knots
        tremor[name] = {"amplitude": [float(x) for x in rng.uniform(0.0, PILOT_TREMOR_AMPLITUDE, 3)],
                        "frequency": [float(x) for x in rng.uniform(*PILOT_TREMOR_HZ, 3)],
                        "phase": [float(x) for x in rng.uniform(0.0, 2 * np.pi, 3)]}
    return {"shape": "pilot", "dof": "mixed", "gains": gains, "sticks": sticks, "tremor": tremor}


def scale_shape(shape: dict, factor: float) -> dict:
    """The same shape with every force amplitude multiplied by ``factor``."""
    d = dict(shape)
    if "amplitude" in d:
        d["amplitude"] = d["amplitude"] * factor
    if "forces" in d:
        d["forces"] = {k: v * factor for k, v in d["forces"].items()}
    if "levels" in d:
        d["levels"] = {k: v * factor for k, v in d["levels"].items()}
    if "gains" in d:
        d["gains"] = {k: v * factor for k, v in d["gains"].items()}
    return d
