"""The model a user starts from as a prior on the fitted parameters (maximum a posteriori).

A free parameter ``theta_j`` with prior mean ``mu_j`` (the vehicle file's value) and prior
standard deviation ``sigma_j`` adds the residual ``(theta_j - mu_j) / sigma_j`` to the
fit (a Gaussian prior as a least-squares residual: Tarantola 2005, *Inverse Problem
Theory*, sec. 3.2, eq. 3.46; the MAP estimate of a linearized problem). A coefficient the
data do not excite then stays near the start instead of running to a search bound, and a
coefficient they do determine moves as far as they say. Bounds are physical limits only.

**How much the data count.** The fit's residuals are normalized by the sensors' noise, as
if every sample were independent. Trajectory residuals are not (100 Hz samples of one
slow motion, and a model that differs from the vehicle in structure leaves a correlated
misfit), so ``J^T J`` overstates what the data know by a factor ``k`` and a prior of
any sensible width would be swamped. The data's residuals are therefore weighted by
``w = min(1, 1 / k)`` with ``k = tr(S^-1 M) / p``: ``S`` the data's information on the
parameters (nuisance profiled out) and ``M`` the sum of the windows' score outer
products (the cluster-robust "meat" of :func:`uvsim.fitting.solver.covariance`), so that
``w S`` matches the information the windows' scatter supports (``k = 1`` for white,
correctly scaled residuals). Raising the likelihood to a power below one for a
misspecified model is the "coarsened" / power posterior of Miller & Dunson 2019
("Robust Bayesian inference via coarsening", JASA 114(527), 1113-1125); the power is
re-estimated at every fresh linearization, like the weights of iteratively reweighted
least squares.

Default prior width (:func:`default_prior_sd`): :data:`DEFAULT_RELATIVE_SD` of the value
(a start model 20-40 % off lies within one sigma); thruster gains :data:`THRUSTER_GAIN_SD`,
reverse ratios :data:`THRUSTER_REVERSE_SD` and the supply voltage :data:`SUPPLY_VOLTAGE_SD`
(from the T200's measured voltage family); for the other parameters whose natural range is not
relative (positions, current) the half-width of their default search range
(:func:`uvsim.fitting.parameters.default_bounds` at margin :data:`DEFAULT_RELATIVE_SD`).
A parameter that is 0 in the file gets a quarter of its search range. A vehicle file may
state its own per-coefficient uncertainty (``uncertainty:`` section, docs/calibration.md),
which takes precedence.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

import numpy as np

from uvsim.errors import CalibrationError
from uvsim.fitting.parameters import ParameterSpace, default_bounds

#: Relative prior standard deviation of a coefficient whose uncertainty the vehicle file
#: does not state (start models in practice are 20-40 % off: issue 21).
DEFAULT_RELATIVE_SD = 0.5


#: Prior standard deviation of a fitted ``supply_voltage`` (V): half the span of a 4S
#: lithium-ion pack (the BlueROV2's battery) from full, 4 x 4.2 V = 16.8 V, to a 3.2 V per
#: cell cut-off, 12.8 V (cell limits of the lithium-ion chemistry; Blue Robotics' 14.8 V
#: nominal 4S pack).
SUPPLY_VOLTAGE_SD = 2.0

#: Prior standard deviation of a fitted ``thruster_gain_i`` (-), about the file's value: the
#: 16 V T200 sheet's full-command thrust changes by about 7 % per volt of supply (4.53 kgf at
#: 14 V, 5.25 at 16 V, 6.02 at 18 V: Blue Robotics' T200 measurements,
#: ``uvsim/data/thrusters/t200_voltage``), so one sd covers a battery within about 1.4 V of
#: the voltage the vehicle's curve was measured at, or a unit, propeller or ESC delivering
#: 10 % less or more than the sheet.  (The parameter's search range, 0.05-1.5, is a
#: physical limit, not a belief: half of it, 0.725, let a common factor on every gain trade
#: freely against the masses and damping.)
THRUSTER_GAIN_SD = 0.1

#: Prior standard deviation of a fitted ``thruster_reverse_i`` (-), the factor on a unit's
#: reverse thrust beyond its curve's, about the file's value: the T200 sheets' reverse to
#: forward thrust ratio moves with the supply (full command 0.789, 0.785, 0.777, 0.776, 0.763,
#: 0.749 at 10, 12, 14, 16, 18, 20 V; at 1300 / 1700 us 0.822, 0.798, 0.798, 0.789, 0.816, 0.825:
#: Blue Robotics' T200 measurements, ``uvsim/data/thrusters/t200_voltage``), a few per cent about
#: the 16 V curve, and a propeller mounted or pitched otherwise, or fouled, changes it more; one
#: sd of 0.1 covers both.  (Half the parameter's 0.1-1.5 search range, 0.7, let a reverse ratio
#: trade freely against the damping.)
THRUSTER_REVERSE_SD = 0.1


def default_prior_sd(name: str, value: float) -> float:
    """Prior standard deviation of parameter ``name`` at ``value`` (module docstring)."""
    if name == "supply_voltage":
        return SUPPLY_VOLTAGE_SD
    if name.startswith("thruster_gain_"):
        return THRUSTER_GAIN_SD
    if name.startswith("thruster_reverse_"):
        return THRUSTER_REVERSE_SD
    try:
        lo, hi = default_bounds(name, float(value), DEFAULT_RELATIVE_SD)
    except CalibrationError:  # a coefficient that is 0 in the file has no relative width
        raise CalibrationError(f"parameter {name} is 0 in the vehicle, so it has no default prior width; state "
                               f"its uncertainty in the vehicle file (uncertainty: {{{name}: SD}}) or fit "
                               "without priors (--no-prior)") from None
    return 0.5 * (hi - lo)  # DEFAULT_RELATIVE_SD |value| for the relative families


@dataclass
class Prior:
    """Gaussian prior on a space's free parameters, in its scaled variables ``z``:
    ``mean_z`` (p,), ``sd_z`` (p,) > 0; ``temper``: weight the data by
    :func:`data_weight` (module docstring)."""

    mean_z: np.ndarray
    sd_z: np.ndarray
    temper: bool = True

    def residual(self, z: np.ndarray) -> np.ndarray:
        return (np.asarray(z, float) - self.mean_z) / self.sd_z


def make_prior(space: ParameterSpace, means: Mapping[str, float], sds: Mapping[str, float] | None = None, *,
               temper: bool = True) -> Prior:
    """The prior of ``space``'s free parameters: mean ``means[name]`` (the vehicle file's
    value), standard deviation ``sds[name]`` or :func:`default_prior_sd` (physical units;
    for a mean of 0, which has no relative width, a quarter of the parameter's search range)."""
    sds = dict(sds or {})
    mu, sd = [], []
    for fp in space.free:
        if fp.name not in means:
            raise CalibrationError(f"no prior mean for parameter {fp.name}")
        m = float(means[fp.name])
        if fp.name in sds:
            s = float(sds[fp.name])
        else:
            try:
                s = default_prior_sd(fp.name, m)
            except CalibrationError:  # 0 with no default width: a quarter of the search range the caller gave
                s = 0.25 * (fp.upper - fp.lower)
        if not (np.isfinite(s) and s > 0):
            raise CalibrationError(f"prior standard deviation of {fp.name}: {s!r}; expected a positive number")
        mu.append(m / fp.scale)
        sd.append(s / fp.scale)
    return Prior(np.array(mu, float), np.array(sd, float), temper)


def data_weight(S: np.ndarray, meat: np.ndarray) -> float:
    """``min(1, p / tr(S^-1 M))`` (module docstring): ``S`` the data's reduced information
    (p, p), ``meat`` the sum of window score outer products (p, p)."""
    p = S.shape[0]
    if p == 0:
        return 1.0
    k = float(np.trace(np.linalg.pinv(S) @ meat)) / p
    return 1.0 if not np.isfinite(k) or k <= 1.0 else 1.0 / k
