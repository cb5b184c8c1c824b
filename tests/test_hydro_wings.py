"""Lifting line, flat plate, Montgomerie blend; Sheldahl data reader and RMS comparison."""
import numpy as np
import pytest

from uvsim.errors import HydroError
from uvsim.hydro import wings as W
from uvsim.hydro.polars import read_sheldahl
from uvsim.hydro.validation import wing_rms_vs_polars


def test_lifting_line_small_alpha():
    wing = W.WingModel(aspect_ratio=4.0, oswald=0.85)
    a = np.radians(np.array([-3.0, 0.5, 2.0]))
    c = W.lifting_line(wing, a, 5e5)
    expect = 2 * np.pi * a / (1 + 2 / (0.85 * 4.0))  # eq. 20 with C_l = 2 pi alpha
    np.testing.assert_allclose(c.CL, expect, rtol=1e-12)
    cd0 = W.profile_drag(wing, 5e5)
    np.testing.assert_allclose(c.CD, cd0 + expect ** 2 / (np.pi * 0.85 * 4.0), rtol=1e-12)  # eqs. 21-22
    # 2-D limit
    c2 = W.lifting_line(W.WingModel(), a, 5e5)
    np.testing.assert_allclose(c2.CL, 2 * np.pi * a)


def test_flat_plate_normal_force_at_90():
    c = W.flat_plate(W.WingModel(), np.radians([90.0, -90.0]), 1e6)
    assert c.CN[0] == pytest.approx(1.98)  # Hoerner 2-D plate
    assert c.CD[0] == pytest.approx(1.98) and c.CD[1] == pytest.approx(1.98)
    assert abs(c.CL[0]) < 1e-12
    w3 = W.WingModel(aspect_ratio=3.0)
    assert W.flat_plate(w3, np.pi / 2, 1e6).CN == pytest.approx(1.11 + 0.018 * 3.0)  # Viterna-Corrigan
    # centre of pressure: mid-chord at 90 deg
    c90 = W.flat_plate(W.WingModel(), np.pi / 2, 1e6)
    assert W.center_of_pressure(c90.CN, c90.CM) == pytest.approx(0.5)


def test_blend_continuity_and_limits():
    wing = W.WingModel(aspect_ratio=5.0)
    a = np.radians(np.linspace(-180, 180, 36001))  # 0.01 deg steps
    c = W.montgomerie_blend(wing, a, 3e5)
    for key in ("CL", "CD", "CM"):
        v = getattr(c, key)
        assert np.max(np.abs(np.diff(v))) < 0.01, key  # no jumps anywhere, incl. 10 and 15 deg
    ll, fp = W.lifting_line(wing, a, 3e5), W.flat_plate(wing, a, 3e5)
    aa = np.abs(np.degrees(a))
    np.testing.assert_allclose(c.CL[aa <= 10], ll.CL[aa <= 10])
    np.testing.assert_allclose(c.CL[aa >= 15], fp.CL[aa >= 15])
    np.testing.assert_allclose(c.CL, -c.CL[::-1], atol=1e-12)  # odd
    np.testing.assert_allclose(c.CD, c.CD[::-1], atol=1e-12)  # even
    assert W.blend_weight(np.radians(12.5)) == pytest.approx(0.5)


def test_wing_validation():
    with pytest.raises(HydroError, match="aspect_ratio"):
        W.WingModel(aspect_ratio=0.0)
    with pytest.raises(HydroError, match="oswald"):
        W.WingModel(oswald=1.5)


def test_sheldahl_reader_spot_values():
    ps = read_sheldahl()
    assert ps.res.tolist() == [1e4, 2e4, 4e4, 8e4, 1.6e5, 3.6e5, 7e5, 1e6, 2e6, 5e6, 1e7]
    # spot values from SOURCE.md (Re = 3.6e5)
    cl, cd, _ = ps.evaluate(3.6e5, np.radians([10.0, 11.0, 45.0, 90.0, 180.0]))
    np.testing.assert_allclose(cl, [0.9440, 0.9572, 1.05, 0.09, 0.0], atol=1e-4)
    np.testing.assert_allclose(cd, [0.0191, 0.0211, 1.075, 1.80, 0.025], atol=1e-4)
    assert ps.covers(5e5, 0.3) and not ps.covers(2e7, 0.3)


def test_rms_against_sheldahl_is_what_docs_report():
    """RMS of the analytic blend (AR = inf) vs Sheldahl over 0..180 deg (a result, see docs)."""
    rows = {r["re"]: r for r in wing_rms_vs_polars(W.WingModel(), read_sheldahl())}
    # documented values, 5 % tolerance
    assert rows[1e4]["rms_CL"] == pytest.approx(0.263, rel=0.05)
    assert rows[3.6e5]["rms_CL"] == pytest.approx(0.144, rel=0.05)
    assert rows[1e7]["rms_CL"] == pytest.approx(0.238, rel=0.05)
    for r in rows.values():
        assert 0.08 < r["rms_CD"] < 0.10
