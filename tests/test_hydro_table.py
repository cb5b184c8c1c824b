"""Multifidelity table: provenance, makima smoothing, lookup, save/load, malformed data."""
import numpy as np
import pytest

from uvsim.errors import HydroError
from uvsim.hydro.assembly import build_body_table, build_wing_table, naca0015_table
from uvsim.hydro.body import BodyModel
from uvsim.hydro.datcom import datcom
from uvsim.hydro.geometry import load_hull
from uvsim.hydro.jorgensen import jorgensen
from uvsim.hydro.polars import read_polar_csv
from uvsim.hydro.table import HydroTable

RE_GRID = np.array([1e5, 3e5, 1e6, 3e6, 1e7])


def _write_cfd(path, res=(3e5, 1e6, 3e6), alphas=range(0, 21, 2)):
    rows = ["Re,alpha,CL,CD,CM"]
    for re in res:
        for a in alphas:
            r = np.radians(a)
            rows.append(f"{re},{a},{2.0 * r},{0.1 + r ** 2},{0.5 * r}")
    path.write_text("\n".join(rows) + "\n")
    return path


@pytest.fixture(scope="module")
def body():
    return BodyModel(load_hull("remus100"))


def test_provenance_algorithm1(tmp_path, body):
    cfd = read_polar_csv(_write_cfd(tmp_path / "cfd.csv"), kind="cfd")
    exp_path = tmp_path / "exp.csv"
    exp_path.write_text("Re,alpha,CL,CD,CM\n1e6,0,0,0.2,0\n1e6,5,0.3,0.25,0.1\n")
    exp = read_polar_csv(exp_path, kind="experiment")
    t = build_body_table(body, RE_GRID, cfd=cfd, experiment=exp, smooth=False)
    d = np.radians
    assert t.meta["re_threshold"] == 3e6  # largest Re of the data
    assert t.provenance(d(3), 1e6) == "experiment"  # experiment > CFD
    assert t.provenance(d(-4), 1e6) == "experiment"  # mirrored by symmetry
    assert t.provenance(d(10), 1e6) == "cfd"
    assert t.provenance(d(-18), 3e5) == "cfd"
    assert t.provenance(d(30), 1e6) == "jorgensen"  # beyond the CFD angles, Re <= threshold
    assert t.provenance(d(5), 1e5) == "datcom"  # below the CFD Re range, |alpha| < 15
    assert t.provenance(d(150), 1e5) == "jorgensen"
    assert t.provenance(d(30), 1e7) == "datcom"  # Re > threshold: DATCOM full envelope
    # values in the cells are the source's values
    j, i = 2, int(np.argmin(np.abs(t.alpha - d(10))))
    assert t.CL[j, i] == pytest.approx(2 * d(10))
    i30 = int(np.argmin(np.abs(t.alpha - d(30))))
    assert t.CD[j, i30] == pytest.approx(float(jorgensen(body, t.alpha[i30], 1e6).CD))
    assert t.CD[4, i30] == pytest.approx(float(datcom(body, t.alpha[i30], 1e7).CD))


def test_single_method_tables(body):
    for m in ("jorgensen", "datcom"):
        t = build_body_table(body, RE_GRID, method=m, smooth=False)
        assert set(t.method.ravel()) == {m}


def test_makima_smoothing_reduces_jumps(body):
    raw = build_body_table(body, np.logspace(5, 7, 9), smooth=False)
    sm = build_body_table(body, np.logspace(5, 7, 9), smooth=True)
    assert np.any(sm.smoothed) and not np.any(raw.smoothed)
    assert (sm.method == raw.method).all()  # provenance kept
    for key in ("CL", "CD", "CM"):
        before, after = raw.max_jump(key, at_boundaries=False), sm.max_jump(key, at_boundaries=False)
        assert after < 0.5 * before, (key, before, after)
    # DATCOM -> Jorgensen at 15 deg: the C_D step across the method boundary
    assert sm.max_jump("CD") < 0.1 * raw.max_jump("CD")
    # cells far from boundaries untouched
    far = np.abs(np.degrees(raw.alpha)) > 40
    np.testing.assert_array_equal(sm.CD[:, far], raw.CD[:, far])


def test_lookup_matches_nodes_and_shapes(body):
    t = build_body_table(body, RE_GRID)
    j, i = 2, 200
    got = t.lookup(t.alpha[i], t.re[j])
    assert got == pytest.approx((t.CL[j, i], t.CD[j, i], t.CM[j, i]))
    a = np.array([[0.1, -2.0, 3.0], [-3.1, 0.0, 1.0]])
    cl, cd, cm = t.lookup(a, 2e6)
    assert cl.shape == cd.shape == cm.shape == (2, 3)
    # scalar fast path == vector path; periodic alpha
    for x in a.ravel():
        s = t.lookup(float(x), 2e6)
        v = t.lookup(np.array([x, x + 2 * np.pi]), np.array([2e6, 2e6]))
        assert s == pytest.approx((v[0][0], v[1][0], v[2][0]), abs=1e-12)
        assert v[0][1] == pytest.approx(v[0][0], abs=1e-9)
    # midway in alpha and log Re = bilinear average
    am = 0.5 * (t.alpha[i] + t.alpha[i + 1])
    rm = np.sqrt(t.re[j] * t.re[j + 1])
    expect = 0.25 * (t.CD[j, i] + t.CD[j, i + 1] + t.CD[j + 1, i] + t.CD[j + 1, i + 1])
    assert t.lookup(am, rm)[1] == pytest.approx(expect)
    # Re policy
    assert t.lookup(0.3, 1.0)[1] == pytest.approx(t.lookup(0.3, t.re[0])[1])  # clamp (documented)
    with pytest.raises(HydroError, match="outside the table range"):
        t.lookup(0.3, 1e9, extrapolate="raise")
    with pytest.raises(HydroError, match="outside the table range"):
        t.lookup(np.array([0.3]), np.array([1e9]), extrapolate="raise")


def test_save_load_roundtrip(tmp_path, body):
    t = build_body_table(body, RE_GRID)
    p = t.save(tmp_path / "remus.csv")
    u = HydroTable.load(p)
    for key in ("CL", "CD", "CM"):
        np.testing.assert_array_equal(getattr(u, key), getattr(t, key))
    np.testing.assert_array_equal(u.re, t.re)
    np.testing.assert_allclose(u.alpha, t.alpha, atol=1e-15)
    assert (u.method == t.method).all() and (u.smoothed == t.smoothed).all()
    assert u.meta["ref_area_m2"] == pytest.approx(body.A) and u.name == t.name
    assert u.lookup(0.7, 2e6) == pytest.approx(t.lookup(0.7, 2e6), abs=1e-14)


def test_load_malformed_table(tmp_path):
    p = tmp_path / "bad.csv"
    p.write_text("re,alpha_deg,CL\n1,2,3\n")
    with pytest.raises(HydroError, match="bad.csv"):
        HydroTable.load(p)


@pytest.mark.parametrize("content,match", [
    ("Re,alpha,CL,CD\n1e6,0,0,0.1\n1e6,5,0.1,0.1\n", "missing column"),
    ("Re,alpha,CL,CD,CM\n1e6,0,0,0.1,0\n1e6,abc,0.1,0.1,0\n", "'alpha' row 3"),
    ("Re,alpha,CL,CD,CM\n1e6,0,0,0.1,0\n1e6,0,0.1,0.1,0\n", "duplicate angle"),
    ("Re,alpha,CL,CD,CM\n1e6,0,0,0.1,0\n1e6,200,0.1,0.1,0\n", r"\[-180, 180\]"),
    ("Re,alpha,CL,CD,CM\n1e6,0,0,0.1,0\n", "fewer than 2 angles"),
    ("Re,alpha,CL,CD,CM\n-1e6,0,0,0.1,0\n-1e6,5,0,0.1,0\n", "'Re' must be > 0"),
    ("Re,alpha,CL,CD,CM\n", "no data rows"),
])
def test_malformed_cfd_tables(tmp_path, content, match):
    p = tmp_path / "cfd_bad.csv"
    p.write_text(content)
    with pytest.raises(HydroError, match=match) as ei:
        read_polar_csv(p)
    assert "cfd_bad.csv" in str(ei.value)


def test_wing_tables():
    t = naca0015_table(np.array([1e4, 1e5, 1e6]))
    assert set(t.method.ravel()) == {"experiment"}
    cl, cd, _ = t.lookup(np.radians(90.0), 3.6e5)
    assert cd == pytest.approx(1.80, abs=1e-9)  # Sheldahl is Re-independent post stall
    assert t.meta["cm_source"].startswith("analytic")
    t3 = naca0015_table(np.array([1e4, 1e5, 1e6]), aspect_ratio=3.0)
    d = np.radians
    assert t3.provenance(d(5), 1e5) == "lifting_line"
    assert t3.provenance(d(-12), 1e5) == "montgomerie_blend"
    assert t3.provenance(d(100), 1e5) == "flat_plate"
    # partial experiment: makima only where data meet analytic cells
    t4 = build_wing_table(re_grid=np.array([1e5]), smooth=True)
    assert not t4.smoothed.any()
