"""Regression against seed 003 Table II: REMUS 100 hull at Re = 2.9e6 (u = 1.5 m/s).

Assumptions (all cited, none tuned):
- Geometry: Prestero (2001) Table 2.1 Myring parameters (data/hulls/remus100.yaml), bare hull.
- rho = 1030 kg/m^3: the sea-water density of Prestero's REMUS model (his Table 4.1 / the REMUS
  coefficient scripts derived from it); seed 003 does not state its rho.
- Reference area for dimensionalising: frontal area pi d^2/4 (Prestero's A_f = 0.0285 m^2).
  |Y_vv| at 90 deg = 1/2 rho eta c_dn A_p does not depend on it.
- Re = 2.9e6 is the length Reynolds number (sets C_f); the cross-flow Reynolds number is
  Re_n = Re d/L sin(alpha) = 4.2e5 at 90 deg.
- C_f: Karman-Schoenherr line (DATCOM's turbulent flat-plate line).  eta(l/d = 6.98) = 0.651 from
  Jorgensen Fig. 4 (digitized); k2 - k1 from Lamb's prolate spheroid.
- Jorgensen's C_A(0): flat-plate friction on the wetted area (our choice; seed 003 does not say).

Result: Table II is NOT reproduced within 10 %.  The values we get are asserted below with a 2 %
tolerance (regression guard) and the 10 % reproduction checks are strict xfails, so that a change
which reproduces the paper shows up.  docs/hydro.md discusses the differences.
"""
import pytest

from uvsim.hydro.body import BodyModel
from uvsim.hydro.coefficients import quadratic_damping
from uvsim.hydro.geometry import load_hull

RE = 2.9e6
RHO = 1030.0
PAPER = {"jorgensen": {"Xuu": 2.006, "Yvv": 64.3}, "datcom": {"Xuu": 2.117, "Yvv": 55.4}}
PRESTERO = {"Xuu": 1.62, "Yvv": 131.0}
# What this implementation gives (see docs/hydro.md, "Table II")
OURS_REYNOLDS = {"jorgensen": {"Xuu": 1.342, "Yvv": 27.84}, "datcom": {"Xuu": 1.609, "Yvv": 27.84}}
OURS_SUBCRITICAL_YVV = 92.25


@pytest.fixture(scope="module")
def results():
    hull = load_hull("remus100")
    return {m: quadratic_damping(BodyModel(hull, cdn_model=m), RE, RHO) for m in ("reynolds", "subcritical")}


def test_values_we_get(results):
    r = results["reynolds"]
    for meth in ("jorgensen", "datcom"):
        for k in ("Xuu", "Yvv"):
            assert r[meth][k] == pytest.approx(OURS_REYNOLDS[meth][k], rel=0.02)
        assert r[meth]["Zww"] == r[meth]["Yvv"]  # axial symmetry
    assert results["subcritical"]["jorgensen"]["Yvv"] == pytest.approx(OURS_SUBCRITICAL_YVV, rel=0.02)
    # X_uu does not depend on the cross-flow model
    assert results["subcritical"]["datcom"]["Xuu"] == r["datcom"]["Xuu"]


def test_paper_cross_flow_value_lies_between_our_two_cdn_models(results):
    lo = results["reynolds"]["jorgensen"]["Yvv"]
    hi = results["subcritical"]["jorgensen"]["Yvv"]
    assert lo < PAPER["jorgensen"]["Yvv"] < hi
    assert lo < PAPER["datcom"]["Yvv"] < hi


def test_datcom_axial_drag_close_to_prestero(results):
    # Prestero's X_uu (also a form-factor x skin-friction estimate) agrees with our DATCOM C_D0
    assert results["reynolds"]["datcom"]["Xuu"] == pytest.approx(PRESTERO["Xuu"], rel=0.03)


@pytest.mark.xfail(strict=True, reason="Table II not reproduced: we get Xuu 1.34 (J) / 1.61 (D) vs "
                                       "2.006 / 2.117; see docs/hydro.md")
@pytest.mark.parametrize("meth", ["jorgensen", "datcom"])
def test_table2_axial_within_10_percent(results, meth):
    assert results["reynolds"][meth]["Xuu"] == pytest.approx(PAPER[meth]["Xuu"], rel=0.10)


@pytest.mark.xfail(strict=True, reason="Table II not reproduced: Yvv 27.8 (Re-dependent c_dn) or 92.3 "
                                       "(subcritical c_dn) vs 64.3 / 55.4; see docs/hydro.md")
@pytest.mark.parametrize("model", ["reynolds", "subcritical"])
@pytest.mark.parametrize("meth", ["jorgensen", "datcom"])
def test_table2_crossflow_within_10_percent(results, model, meth):
    assert results[model][meth]["Yvv"] == pytest.approx(PAPER[meth]["Yvv"], rel=0.10)
