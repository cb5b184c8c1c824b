"""Component build-up damping (seed 003 eqs. 23-26): robustness, reduction to eq. 25, paths agree."""
import numpy as np
import pytest

from uvsim.errors import VehicleError
from uvsim.forces import make_term
from uvsim.sam.buildup import ComponentBuildup
from uvsim.sam.vehicle import load_sam

HULL = {"stations": {"x": [0.0, 0.05, 0.1, 1.25, 1.5], "r": [0.0, 0.08, 0.095, 0.095, 0.05]}}


@pytest.fixture(scope="module")
def sam_damping():
    return load_sam().damping


class _Ctx:
    def __init__(self, nu_r):
        self.nu_r = np.atleast_2d(np.asarray(nu_r, float))


def _forces(term, nu_r, params=None):
    nu_r = np.atleast_2d(np.asarray(nu_r, float))
    prep = term.prepare(params or term.parameters(), nu_r.shape[0])
    return term.forces(_Ctx(nu_r), prep)


def test_zero_speed_gives_zero_force_without_nan(sam_damping):
    for nu in (np.zeros((1, 6)), np.zeros((3, 6))):
        f = _forces(sam_damping, nu)
        assert np.all(np.isfinite(f)) and np.all(f == 0.0)


@pytest.mark.parametrize("vel", [[-1.5, 0, 0], [0, 1.2, 0], [0, 0, -0.8], [-1, 1, 1], [1e-12, 0, 0], [0, 1e-9, 0]])
def test_any_flow_direction_is_finite_and_dissipative(sam_damping, vel):
    nu = np.array([vel + [0.0, 0.0, 0.0]])
    f = _forces(sam_damping, nu)
    assert np.all(np.isfinite(f))
    # pure translation: the damping force takes energy out (F . v < 0 unless v ~ 0)
    power = float(f[0, :3] @ np.asarray(vel))
    assert power <= 0.0
    if np.linalg.norm(vel) > 1e-3:
        assert power < 0.0


def test_flow_from_behind_pushes_forward(sam_damping):
    f = _forces(sam_damping, [[-1.0, 0, 0, 0, 0, 0]])
    assert f[0, 0] > 0 and abs(f[0, 1]) < 1e-9 and abs(f[0, 2]) < 1e-9


def test_side_flow_is_the_rotated_heave_flow(sam_damping):
    """Axisymmetric hull + symmetric nozzle halves: sway flow = heave flow rotated 90 deg about x."""
    fv = _forces(sam_damping, [[0.5, 0.7, 0, 0, 0, 0]])[0]
    fw = _forces(sam_damping, [[0.5, 0, 0.7, 0, 0, 0]])[0]
    np.testing.assert_allclose(fv[[0, 1, 5]], [fw[0], fw[2], -fw[4]], rtol=1e-9, atol=1e-12)


def test_scalar_and_batch_paths_agree(sam_damping):
    rng = np.random.default_rng(1)
    nu = rng.normal(size=(20, 6)) * [2, 1, 1, 1, 1, 1]
    nu[0] = 0.0
    nu[1] = [-2.0, 0, 0, 0, 0, 0]
    fb = _forces(sam_damping, nu)
    fs = np.vstack([_forces(sam_damping, nu[i:i + 1]) for i in range(nu.shape[0])])
    np.testing.assert_allclose(fs, fb, rtol=1e-10, atol=1e-10)


def test_single_hull_reduces_to_eq25():
    """One hull at the body origin: X = X_uu(alpha)|u|u, Z = Z_ww(alpha)|w|w, M = -x_cp Z (eq. 23-25)."""
    term = ComponentBuildup([{"name": "hull", "kind": "body", "hull": HULL, "nose": [0.0, 0, 0]}], rho=1026.0)
    # put the moment reference at the origin
    term.components[0].r = np.zeros(3)
    U = 1.7
    for a_deg in (5.0, 30.0, 60.0, 120.0, 170.0):
        a = np.radians(a_deg)
        u, w = U * np.cos(a), U * np.sin(a)
        f = _forces(term, [[u, 0.0, w, 0, 0, 0]])[0]
        eq = term.equivalent_coefficients(a, U)
        assert f[0] == pytest.approx(eq["X_uu"][0] * abs(u) * u, rel=1e-9, abs=1e-12)
        assert f[2] == pytest.approx(eq["Z_ww"][0] * abs(w) * w, rel=1e-9)
        assert f[4] == pytest.approx(-eq["x_cp"][0] * f[2], rel=1e-9, abs=1e-12)
        assert f[1] == 0.0 and f[3] == 0.0 and f[5] == 0.0


def test_eq25_ratios_are_singular_where_direct_forces_are_not():
    term = ComponentBuildup([{"name": "hull", "kind": "body", "hull": HULL, "nose": [0.0, 0, 0]}])
    eq = term.equivalent_coefficients(np.array([0.0, np.pi / 2]), 1.0)
    assert np.isnan(eq["Z_ww"][0]) and np.isnan(eq["X_uu"][1])
    f = _forces(term, [[1.0, 0, 0, 0, 0, 0], [0, 0, 1.0, 0, 0, 0]])
    assert np.all(np.isfinite(f))


def test_rotational_damping_and_rotation_term(sam_damping):
    p = sam_damping.parameters()
    f = _forces(sam_damping, [[0, 0, 0, 0.5, 0, 0]])[0]
    assert f[3] == pytest.approx(p["K_pp"] * 0.25)  # nozzle on the axis: no rotation-induced flow
    f = _forces(sam_damping, [[0, 0, 0, 0, 0, 0.8]])[0]
    # yaw rotation: N_rr |r| r plus the nozzle sections aft of the origin seeing side flow
    assert f[5] < p["N_rr"] * 0.64 < 0
    assert f[1] != 0.0


def test_cross_coupled_eq26_terms():
    base = dict(components=[{"name": "hull", "kind": "body", "hull": HULL, "nose": [0.7, 0, 0]}],
                rotational={"K_pp": -0.1, "M_qq": -5.0, "N_rr": -5.0})
    plain = ComponentBuildup(**base)
    zero = ComponentBuildup(**base, cross_coupled={})
    cc = {"X_qq": -1.0, "X_rr": -2.0, "Y_pp": -3.0, "Y_rr": -4.0, "Z_pp": -5.0, "Z_qq": -6.0}
    coupled = ComponentBuildup(**base, cross_coupled=cc)
    nu = np.array([[1.0, 0.2, -0.1, 0.3, -0.4, 0.5]])
    f0, fz, fc = _forces(plain, nu), _forces(zero, nu), _forces(coupled, nu)
    np.testing.assert_allclose(fz, f0)
    p, q, r = 0.3, -0.4, 0.5
    extra = [-1 * abs(q) * q - 2 * abs(r) * r, -3 * abs(p) * p - 4 * abs(r) * r, -5 * abs(p) * p - 6 * abs(q) * q]
    np.testing.assert_allclose(fc[0, :3] - f0[0, :3], extra, rtol=1e-12)
    np.testing.assert_allclose(fc[0, 3:], f0[0, 3:])
    assert set(cc) <= set(coupled.parameters())


def test_round_trip_and_parameters(sam_damping):
    d = sam_damping.to_dict()
    again = make_term(d)
    nu = np.array([[1.0, 0.3, -0.2, 0.1, 0.2, -0.3]])
    np.testing.assert_allclose(_forces(again, nu), _forces(sam_damping, nu))
    changed = sam_damping.with_parameters({"M_qq": -30.0})
    assert changed.parameters()["M_qq"] == -30.0
    veh = load_sam().with_parameters({"N_rr": -20.0})
    assert veh.parameters()["N_rr"] == -20.0


def test_data_sets_differ_but_agree_in_size():
    fs = {}
    for ds in ("jorgensen", "datcom", "multifidelity"):
        fs[ds] = _forces(load_sam(ds).damping, [[1.5, 0, np.tan(np.radians(8)) * 1.5, 0, 0, 0]])[0]
    assert not np.allclose(fs["jorgensen"], fs["datcom"])
    for ds in fs:
        assert np.all(np.sign(fs[ds][[0, 2]]) == np.sign(fs["multifidelity"][[0, 2]]))
        assert abs(fs[ds][0]) == pytest.approx(abs(fs["multifidelity"][0]), rel=0.5)


@pytest.mark.parametrize("bad, msg", [
    ({"dataset": "cfd"}, "dataset"),
    ({"components": []}, "components"),
    ({"components": [{"kind": "fin"}]}, "kind"),
    ({"components": [{"kind": "wing", "position": [0, 0, 0], "area": -1, "chord": 0.1, "aspect_ratio": 3}]}, "area"),
    ({"rotational": {"M_qq": 5.0}}, "M_qq"),
    ({"rotational": {"Mqq": -5.0}}, "Mqq"),
])
def test_bad_specs_name_the_field(bad, msg):
    spec = {"components": [{"name": "hull", "kind": "body", "hull": HULL, "nose": [0.7, 0, 0]}]}
    spec.update(bad)
    with pytest.raises(VehicleError, match=msg):
        ComponentBuildup(**spec)


def test_sam_vehicle_file_round_trip(tmp_path):
    import uvsim

    veh = load_sam("datcom")
    path = uvsim.save_vehicle(veh, tmp_path / "sam_copy.yaml", header="copy")
    again = uvsim.load_vehicle(path)
    assert again.damping.dataset == "datcom"
    assert [e.kind for e in again.effects] == [e.kind for e in veh.effects]
    assert again.parameters() == veh.parameters()
    nu = np.array([[1.0, 0.3, -0.2, 0.1, 0.2, -0.3]])
    np.testing.assert_allclose(_forces(again.damping, nu), _forces(veh.damping, nu))
    for a, b in zip(again.effects, veh.effects):
        assert a.to_dict() == b.to_dict()


def test_gimbal_nozzle_turns_with_the_thrust_vector():
    """Nozzle sections with gimbal: true see the thrust-vector angle; at forward speed a positive
    yaw vector gives a side force to port on the nozzle (like a rudder with its trailing edge to
    starboard), adding to the thrust's yaw moment."""
    import uvsim
    from uvsim.sam.components import gimbal_matrix
    from uvsim.sam.model import make_model
    from uvsim.sam.vehicle import commands

    veh = load_sam()
    d = veh.damping
    nu = np.array([[1.5, 0, 0, 0, 0, 0]])
    f0 = d.component_forces(nu, tv=[0.0, 0.0])["nozzle_vertical"][0]
    f1 = d.component_forces(nu, tv=[0.0, 0.1])["nozzle_vertical"][0]
    assert abs(f0[1]) < 1e-9 and f1[1] < 0 and f1[5] > 0
    G = gimbal_matrix(0.05, 0.1)
    np.testing.assert_allclose(G @ [1, 0, 0], [np.cos(0.05) * np.cos(0.1), -np.sin(0.1), np.sin(0.05) * np.cos(0.1)])
    np.testing.assert_allclose(G @ G.T, np.eye(3), atol=1e-12)
    # inside a model the term reads the propulsion states; scalar and batch paths agree
    u = commands(2, rpm_1=[800, 800], rpm_2=[800, 800], tv_pitch=[0.05, -0.1], tv_yaw=[0.1, 0.02])
    m2 = make_model(veh, n=2)
    y = m2.initial_state(nu=np.array([[1.2, 0.1, -0.1, 0.1, 0.2, 0.3]] * 2), u0=u)
    rb = m2.rhs(0.0, y, u)
    m1 = make_model(veh, n=1)
    rs = np.vstack([m1.rhs(0.0, y[i:i + 1], u[i:i + 1]) for i in range(2)])
    np.testing.assert_allclose(rs, rb, rtol=1e-9, atol=1e-12)
    assert uvsim.load_vehicle("sam").damping.components[1].gimbal


def test_gimbal_without_propulsion_is_an_error():
    import copy

    from uvsim.model import Model

    veh = copy.copy(load_sam())
    veh.effects = [e for e in veh.effects if e.kind != "sam_propulsion"]
    with pytest.raises(VehicleError, match="sam_propulsion"):
        Model(veh, input_kind="thrust")


# ----------------------------------------------------------------------------- one Munk moment
def _lamb_k(fineness):
    """Lamb's k1, k2 of a prolate spheroid of fineness ratio l/d (Lamb 1932 sec. 373), written here
    independently of uvsim.hydro."""
    e = np.sqrt(1.0 - fineness ** -2)
    L = np.log((1 + e) / (1 - e))
    a0 = 2 * (1 - e * e) / e ** 3 * (0.5 * L - e)
    b0 = 1 / e ** 2 - (1 - e * e) / (2 * e ** 3) * L
    return a0 / (2 - a0), b0 / (2 - b0)


def _hull_only(dataset, munk_moment):
    import copy

    from uvsim.vehicle import load_vehicle, vehicle_from_dict

    d = copy.deepcopy(load_vehicle("sam").raw)
    d["damping"]["components"] = [c for c in d["damping"]["components"] if c["kind"] == "body"]
    d["damping"].update(dataset=dataset, munk_moment=munk_moment)
    return vehicle_from_dict(d, source="sam hull only")


@pytest.mark.parametrize("munk_moment", ["added_mass", "table"])
@pytest.mark.parametrize("dataset", ["jorgensen", "datcom", "multifidelity"])
def test_pitch_moment_has_one_munk_term(dataset, munk_moment):
    """Total pitch moment on the SAM hull at alpha = 5 deg, U = 2 m/s (everything the model applies:
    hull table, added-mass Coriolis C_A(nu) nu, restoring; propellers off, level) = the table's
    viscous and base-lift parts + exactly one Munk moment.  Truth from seed 003 eqs. 9 / 19 and
    Lamb's k-factors, computed here; the double count of the old model is off by ~12.7 N m."""
    from uvsim.hydro import crossflow
    from uvsim.hydro.geometry import hull_from_stations
    from uvsim.sam.model import make_model
    from uvsim.sam.vehicle import NEUTRAL

    veh = _hull_only(dataset, munk_moment)
    spec = veh.raw["damping"]["components"][0]["hull"]["stations"]
    h = hull_from_stations(spec["x"], spec["r"])
    rho, U, a = 1026.0, 2.0, np.radians(5.0)
    u, w = U * np.cos(a), U * np.sin(a)
    A, L, xm = np.pi * 0.095 ** 2, 1.5, h.volume_centroid
    k1, k2 = _lamb_k(L / 0.19)
    q = 0.5 * rho * U * U
    base = -q * (k2 - k1 if dataset == "jorgensen" else 1.0) * h.base_area * (L - xm) * (
        np.sin(2 * a) * np.cos(a / 2) if dataset == "jorgensen" else 2 * a)
    viscous = 0.0
    if dataset == "jorgensen":  # eq. 9, second term (DATCOM eq. 19 below 12 deg has none)
        viscous = q * crossflow.eta(L / 0.19) * crossflow.subcritical_cdn() * h.planform_area \
            * (xm - h.planform_centroid) * np.sin(a) ** 2
    if munk_moment == "added_mass":  # C_A(nu) nu with M_A = k rho V: (Z_wdot - X_udot) u w
        munk = (k2 - k1) * rho * h.volume * u * w
    else:  # the table's own: eq. 9 (k V sin 2a cos(a/2)) or eq. 19 (2 a V, k = 1)
        munk = q * h.volume * ((k2 - k1) * np.sin(2 * a) * np.cos(a / 2) if dataset == "jorgensen" else 2 * a)
    m = make_model(veh)
    y = m.initial_state(nu=[u, 0, w, 0, 0, 0], u0=NEUTRAL[None])
    tau = m.M @ m.rhs(0.0, y, NEUTRAL[None])[0, 7:13]
    assert abs(munk) > 10.0
    assert tau[4] == pytest.approx(viscous + base + munk, rel=1e-4, abs=1e-3)


def test_added_mass_munk_needs_added_mass():
    import copy

    from uvsim.model import Model
    from uvsim.vehicle import load_vehicle, vehicle_from_dict

    d = copy.deepcopy(load_vehicle("sam").raw)
    d["added_mass"] = {k: 0.0 for k in ("X_udot", "Y_vdot", "Z_wdot", "K_pdot", "M_qdot", "N_rdot")}
    veh = vehicle_from_dict(d, source="no added mass")
    with pytest.raises(VehicleError, match="munk_moment: 'added_mass'.*X_udot"):
        Model(veh, input_kind="thrust")
    d["damping"]["munk_moment"] = "table"
    Model(vehicle_from_dict(d, source="no added mass"), input_kind="thrust")  # the tables keep it: fine


@pytest.mark.parametrize("key, value", [("munk_moment", "both"), ("cdn_model", "drag_crisis")])
def test_unknown_munk_and_cdn_choices_are_named(key, value):
    spec = load_sam().damping.to_dict()
    spec[key] = value
    with pytest.raises(VehicleError, match=f"{key}: '{value}' not one of"):
        make_term(spec)


def test_table_munk_mode_cancels_the_added_mass_couple_per_row():
    """munk_moment: table adds v x (M_A11 v) with the model's added mass, per row of a batch
    (calibration overrides), so that -C_A(nu) nu leaves no Munk moment."""
    from uvsim.model import coriolis_term
    from uvsim.sam.model import make_model

    veh = _hull_only("jorgensen", "table")
    m = make_model(veh, n=2, overrides={"Z_wdot": np.array([37.75, 20.0]), "Y_vdot": np.array([37.75, 30.0])})
    term = m.terms[[t.kind for t in m.terms].index("component_buildup")]
    prep = m.preps[[t.kind for t in m.terms].index("component_buildup")]
    nu = np.array([[1.2, 0.3, -0.4, 0.0, 0.0, 0.0], [0.8, -0.2, 0.5, 0.0, 0.0, 0.0]])
    with_couple = term.forces(_Ctx(nu), prep)
    plain = ComponentBuildup(**{k: v for k, v in veh.damping.to_dict().items() if k != "type"})
    without = _forces(plain, nu)
    ab = np.einsum("nij,nj->ni", m.M_A, nu)
    ca = coriolis_term(nu, ab)  # C_A(nu) nu; its moment is the Munk couple for pure translation
    np.testing.assert_allclose(with_couple[:, 3:] - without[:, 3:], ca[:, 3:], rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(with_couple[:, :3], without[:, :3])
    single = np.vstack([ComponentBuildup._forces_single(term, nu[i].tolist(), term.prepare(
        dict(m.params, Z_wdot=[37.75, 20.0][i], Y_vdot=[37.75, 30.0][i]), 1)) for i in range(2)])
    np.testing.assert_allclose(single, with_couple, rtol=1e-10, atol=1e-10)
