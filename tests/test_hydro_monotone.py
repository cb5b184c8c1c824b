"""No default table has a force that falls as the speed rises (issue 12, item 3).

A force ``1/2 rho U^2 A C(alpha, Re(U))`` that falls while U rises at fixed alpha is negative
damping in a simulator.  The smooth-cylinder drag crisis (``cdn_model="reynolds"``) does this
to the cross-flow force; the default (Jorgensen's subcritical ``c_dn``) must not.  Checked for
every angle of the table grid and 300 speeds from 0.1 to 5 m/s, on the tables the SAM vehicle
builds (hull: three data sets; nozzle: NACA 0015 ring wing) and on the default REMUS 100 tables.

Required monotone: normal force, axial force (bodies), drag, moment and total force magnitude.
Not required: lift of a body and the chordwise force of a wing, projections that cross zero as
Re changes at fixed alpha (a body near 180 deg; a wing's leading-edge suction near 6 deg), where
their magnitude dips through zero without the force vector shrinking (docs/hydro.md).
"""
import numpy as np
import pytest

from uvsim.hydro.assembly import build_body_table
from uvsim.hydro.body import BodyModel
from uvsim.hydro.geometry import load_hull
from uvsim.sam.vehicle import load_sam

SPEEDS = np.geomspace(0.1, 5.0, 300)


def _falling(table, length, nu, kind):
    """Names of the force components whose magnitude falls somewhere as U rises."""
    A, R = np.meshgrid(table.alpha, SPEEDS * length / nu)
    CL, CD, CM = table.lookup(A, R)
    CN = CL * np.cos(A) + CD * np.sin(A)
    CA = -CL * np.sin(A) + CD * np.cos(A)
    parts = {"normal": CN, "drag": CD, "moment": CM, "total": np.hypot(CL, CD)}
    parts["axial" if kind == "body" else "lift"] = CA if kind == "body" else CL
    out = []
    for name, C in parts.items():
        F = np.abs(SPEEDS[:, None] ** 2 * C)
        if np.any(np.diff(F, axis=0) < -1e-12 * F.max()):
            out.append(name)
    return out


@pytest.mark.parametrize("dataset", ["multifidelity", "jorgensen", "datcom"])
def test_sam_tables_never_fall_with_speed(dataset):
    damping = load_sam(dataset).damping
    assert damping.cdn_model == "subcritical"
    for comp in damping.components:
        assert _falling(comp.table, comp.length, damping.nu, comp.kind) == [], comp.name


@pytest.mark.parametrize("method", ["multifidelity", "jorgensen", "datcom"])
def test_default_body_tables_never_fall_with_speed(method):
    body = BodyModel(load_hull("remus100"))
    assert body.cdn_model == "subcritical"
    assert _falling(build_body_table(body, method=method), body.L, body.nu, "body") == []


def test_drag_crisis_model_does_fall_with_speed():
    """The check can fail: the Reynolds-dependent c_dn gives a cross-flow force that falls (the
    SAM hull side force at 90 deg drops from 2.0 to 2.5 m/s)."""
    body = BodyModel(load_hull("remus100"), cdn_model="reynolds")
    assert {"normal", "drag", "total"} <= set(_falling(build_body_table(body), body.L, body.nu, "body"))
    spec = load_sam().damping.to_dict()
    spec.pop("type")
    from uvsim.sam.buildup import ComponentBuildup

    side = [ComponentBuildup(**dict(spec, cdn_model="reynolds")).component_forces([[0, U, 0, 0, 0, 0]])["hull"][0, 1]
            for U in (2.0, 2.5)]
    assert abs(side[1]) < 0.8 * abs(side[0])
