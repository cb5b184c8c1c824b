"""Jorgensen and DATCOM: symmetries, limits, friction lines, cross-flow data."""
import numpy as np
import pytest

from uvsim.errors import HydroError
from uvsim.hydro import crossflow
from uvsim.hydro.body import BodyModel
from uvsim.hydro.datcom import datcom, zero_lift_drag
from uvsim.hydro.friction import skin_friction
from uvsim.hydro.geometry import load_hull
from uvsim.hydro.jorgensen import default_axial_drag, jorgensen

RE = 2.9e6


@pytest.fixture(scope="module")
def body():
    return BodyModel(load_hull("remus100"))


def test_jorgensen_limits(body):
    h = body.hull
    c = jorgensen(body, np.radians([0.0, 90.0, 180.0]), RE, ca0=0.12, ca180=0.2)
    # C_A(0) = form drag input; C_N(0) = 0
    assert c.CA[0] == pytest.approx(0.12) and c.CD[0] == pytest.approx(0.12) and c.CN[0] == pytest.approx(0)
    # C_N(90) = eta c_dn A_p / A (potential term vanishes, sin(2a) = 0)
    expect = body.eta_value * float(body.cdn(np.pi / 2, RE)) * h.planform_area / body.A
    assert c.CN[1] == pytest.approx(expect, rel=1e-12)
    assert c.CD[1] == pytest.approx(expect, rel=1e-12) and c.CA[1] == pytest.approx(0, abs=1e-15)
    # 180 deg: axial force forward (negative CA), drag = ca180
    assert c.CA[2] == pytest.approx(-0.2) and c.CD[2] == pytest.approx(0.2)
    assert abs(c.CN[2]) < 1e-12 and abs(c.CL[2]) < 1e-12


def test_jorgensen_default_ca0_is_friction(body):
    c = jorgensen(body, 0.0, RE)
    cf = float(skin_friction(RE, body.friction_line))
    assert c.CD == pytest.approx(cf * body.hull.wetted_area / body.A)
    assert default_axial_drag(body, RE) == pytest.approx(float(c.CD))


@pytest.mark.parametrize("fn", [jorgensen, datcom])
def test_odd_even_symmetry(body, fn):
    a = np.radians(np.linspace(1.5, 178.5, 178))  # avoid exact method limits (12, 15 deg)
    p, m = fn(body, a, RE), fn(body, -a, RE)
    np.testing.assert_allclose(m.CL, -p.CL, atol=1e-12)
    np.testing.assert_allclose(m.CD, p.CD, atol=1e-12)
    np.testing.assert_allclose(m.CM, -p.CM, atol=1e-12)
    assert np.all(p.CD > 0)
    # periodic input
    w = fn(body, a + 2 * np.pi, RE)
    np.testing.assert_allclose(w.CL, p.CL, atol=1e-12)


def test_array_shapes(body):
    a = np.zeros((2, 3)) + 0.3
    for fn in (jorgensen, datcom):
        c = fn(body, a, RE)
        assert all(np.shape(x) == (2, 3) for x in c)


def test_datcom_low_alpha(body):
    d = datcom(body, np.radians([0.0, 90.0]), RE)
    z = zero_lift_drag(body, RE)
    assert d.CD[0] == pytest.approx(z["cd0"])  # eqs. 13-14 at alpha = 0
    assert d.CL[0] == 0 and d.CM[0] == 0
    # Beyond 15 deg DATCOM uses Jorgensen with C_A0 = C_D0 (eq. 18)
    j = jorgensen(body, np.radians(90.0), RE, ca0=z["cd0"], ca180=z["cd0"])
    assert d.CD[1] == pytest.approx(float(j.CD))
    # eq. 15 form factor > 1, base drag small for the nearly closed REMUS tail
    assert z["cdf"] > z["cf"] * body.hull.wetted_area / body.A
    assert 0 < z["cdb"] < 0.01 * z["cdf"]


def test_friction_lines():
    re = np.array([1e5, 1e6, 1e7])
    cf = skin_friction(re, "schoenherr")
    np.testing.assert_allclose(0.242 / np.sqrt(cf), np.log10(re * cf), rtol=1e-10)
    np.testing.assert_allclose(skin_friction(1e6, "ittc57"), 0.075 / 16.0)
    # Schoenherr's tabulated values (e.g. Lewis, PNA vol. II, 1988): 0.004409 at 1e6, 0.002934 at 1e7
    np.testing.assert_allclose(cf[1:], [0.004409, 0.002934], rtol=2e-4)
    # ITTC-57 lies above Schoenherr below 1e8 (by design, a model-ship correlation line)
    r = np.logspace(5, 7.9, 20)
    assert np.all(skin_friction(r, "ittc57") > skin_friction(r, "schoenherr"))
    with pytest.raises(HydroError):
        skin_friction(10.0)
    with pytest.raises(HydroError, match="unknown friction line"):
        skin_friction(1e6, "blasius")


def test_crossflow_data():
    assert crossflow.subcritical_cdn() == pytest.approx(1.2, abs=0.03)  # Jorgensen Fig. 1, M_n -> 0
    # AeroSandbox fit values quoted in SOURCE.md: 0.608 at l/d = 4, 0.683 at 10, 0.753 at 20
    assert crossflow.eta(4.0) == pytest.approx(0.608, abs=0.01)
    assert crossflow.eta(10.0) == pytest.approx(0.683, abs=0.01)
    assert crossflow.eta(20.0) == pytest.approx(0.753, abs=0.01)
    with pytest.raises(HydroError, match="outside the digitized eta range"):
        crossflow.eta(1.0)
    cd = crossflow.cylinder_cd_reynolds([1e4, 1e5, 2e5, 5e5, 1e6])
    assert 0.9 < cd[1] < 1.3 and 0.9 < cd[2] < 1.3  # subcritical plateau
    assert cd[3] < 0.5 and cd[4] < 0.5  # after the drag crisis
    # Lamb's k-factors for prolate spheroids: l/d = 6 -> k2-k1 = 0.918-0.045, l/d = 10 -> 0.960-0.021
    assert crossflow.munk_factor(6.0) == pytest.approx(0.873, abs=0.01)
    assert crossflow.munk_factor(10.0) == pytest.approx(0.939, abs=0.01)
    assert crossflow.munk_factor(1000.0) == pytest.approx(1.0, abs=1e-3)


def test_body_model_validation(body):
    with pytest.raises(HydroError, match="cdn_model"):
        BodyModel(body.hull, cdn_model="magic")
    with pytest.raises(HydroError, match="ref_area"):
        BodyModel(body.hull, ref_area=-1.0)


def test_total_incidence():
    from uvsim.hydro.body import total_incidence
    a, phi = total_incidence([1.0, 1.0, -1.0, 0.0], [0.0, 1.0, 0.0, 0.0], [1.0, 0.0, 0.0, 2.0])
    np.testing.assert_allclose(a, [np.pi / 4, np.pi / 4, np.pi, np.pi / 2])
    np.testing.assert_allclose(phi[:2], [0.0, np.pi / 2])


def test_munk_couple_can_be_left_out(body):
    """BodyModel(munk_moment=False) removes exactly the Munk couple: k V sin(2a') cos(a'/2) / (A L)
    from Jorgensen eqs. 9/11 and 2 a V / (A L) from DATCOM eq. 19; forces are unchanged."""
    from dataclasses import replace

    no = replace(body, munk_moment=False)
    h = body.hull
    a = np.radians(np.array([3.0, 10.0, 40.0, 120.0, 170.0, -30.0]))
    full, part = jorgensen(body, a, RE), jorgensen(no, a, RE)
    ap = np.where(np.abs(a) > np.pi / 2, np.pi - np.abs(a), np.abs(a))
    couple = np.sign(a) * np.where(np.abs(a) > np.pi / 2, -1, 1) * body.k * h.volume / (body.A * body.L) \
        * np.sin(2 * ap) * np.cos(ap / 2)
    np.testing.assert_allclose(full.CM - part.CM, couple, rtol=1e-12, atol=1e-15)
    np.testing.assert_array_equal(full.CN, part.CN)
    np.testing.assert_array_equal(full.CA, part.CA)
    d_full, d_part = datcom(body, np.radians(5.0), RE), datcom(no, np.radians(5.0), RE)
    assert float(d_full.CM - d_part.CM) == pytest.approx(2 * np.radians(5.0) * h.volume / (body.A * body.L), rel=1e-12)
    with pytest.raises(HydroError, match="munk_moment"):
        BodyModel(body.hull, munk_moment="yes")


def test_default_cdn_is_jorgensens_subcritical(body):
    assert body.cdn_model == "subcritical"
    np.testing.assert_allclose(body.cdn(np.radians([10.0, 90.0]), [1e5, 1e7]), crossflow.subcritical_cdn())
