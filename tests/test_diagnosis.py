"""Diagnosis (issue 10): forward selection of catalogue effects, on data the project's own
simulator did not make (the independent truth model of uvsim.scenarios), plus the units
it is built from.  The 100-scenario benchmark is the slow test at the end."""
from __future__ import annotations

import json

import numpy as np
import pytest

import uvsim
from uvsim.benchmarks.scenarios import BASE_RETUNE, TRUTH_TO_CATALOGUE
from uvsim.cli import main
from uvsim.diagnosis import diagnose
from uvsim.diagnosis.candidates import EFFECTS, catalogue
from uvsim.diagnosis.regression import stepwise as _stepwise
from uvsim.errors import CalibrationError
from uvsim.fitting.compare import bootstrap_improvement
from uvsim.scenarios import generate, load_truth, sample_scenario

#: Small scenarios keep the fast suite fast: 10 training runs of 8-10 s at 20 Hz.
SMALL = dict(n_runs=10, duration=[8, 10], rate_hz=20.0)


def _scenario(tmp_path, seed, **kw):
    spec = sample_scenario(seed, profile="diagnose", **{**SMALL, **kw})
    out = generate(spec, tmp_path / f"s{seed}")
    return out, load_truth(out)


def _main_rmse(rep, which):
    r = rep[which]
    return r.get("position_m", r.get("attitude_rad"))


# ----------------------------------------------------------------------------- end to end
@pytest.mark.slow
def test_clean_scenario_needs_no_effect(tmp_path):
    """Base coefficients perturbed within +-10 % and no effect: re-tuning them explains
    everything, no effect is named."""
    out, truth = _scenario(tmp_path, 4, n_effects=0)
    assert truth["effects"] == []
    d = diagnose(out, retune=list(BASE_RETUNE))
    assert d.report["effect"] == "none" and d.report["effects"] == []
    assert d.report["confidence"] == "none"
    assert d.report["validation_cost_per_entry"]["final"] < 1.5  # at the noise level


@pytest.mark.slow
def test_a_retune_that_does_not_validate_better_is_not_kept(tmp_path):
    """Issue 45: `--retune` of every base coefficient on clean data whose base model is exact was
    kept whatever it did to the validation runs (the issue's field logs: attitude 62 -> 84 mrad
    with no effect named).  The re-tune is a change of the model like an effect: the verdict
    against the given model must call it better, or the corrected model is the given one."""
    out, truth = _scenario(tmp_path, 4, n_effects=0, perturbation=0.0)
    assert truth["effects"] == []
    rep = diagnose(out, retune=list(BASE_RETUNE)).report
    assert rep["rmse_after"] == rep["rmse_before"]          # the given model, unchanged
    assert rep["effect"] == "none" and rep["retuned"] == {} and rep["model_verdict"] is None
    rv = rep["retune_verdict"]
    assert not rv["kept"] and rv["status"] != "better" and rv["retune"] == list(BASE_RETUNE)
    assert "not kept" in rep["message"]


@pytest.mark.slow
def test_names_a_current_estimates_it_and_halves_the_validation_error(tmp_path):
    out, truth = _scenario(tmp_path, 1, effects=[{"type": "current", "magnitude": 0.05}])
    d = diagnose(out, retune=list(BASE_RETUNE))
    rep = d.report
    assert [e["effect"] for e in rep["effects"]] == ["current"]
    true = truth["effects"][0]["velocity_ned"]
    vals = rep["effects"][0]["parameters"]
    assert vals["current_n"]["value"] == pytest.approx(true[0], abs=0.005)
    assert vals["current_e"]["value"] == pytest.approx(true[1], abs=0.005)
    assert _main_rmse(rep, "rmse_after") <= 0.5 * _main_rmse(rep, "rmse_before")
    # every step's numbers are in the report, and the corrected vehicle carries the effect
    first = next(st for st in rep["steps"] if st["step"] == 1)  # step 0 is the base model's
    assert first["chosen"].startswith("current:")
    assert any(e.kind == "current" for e in d.vehicle_after.effects)


@pytest.mark.slow
def test_a_lead_piece_is_named_with_its_position_and_mass(tmp_path):
    """A 1 N lead piece (0.11 kg in the truth, whose pieces have mass): the ballast wins, and
    its variant with the piece's mass is kept on the open-loop validation cost."""
    out, truth = _scenario(tmp_path, 5, effects=[{"type": "ballast", "variant": "lead", "magnitude": 1.0}])
    eff = truth["effects"][0]
    rep = diagnose(out, retune=list(BASE_RETUNE)).report
    assert [(e["effect"], e["variant"]) for e in rep["effects"]] == [("ballast", "xyz_mass")]
    p = rep["effects"][0]["parameters"]
    assert p["ballast_weight"]["value"] == pytest.approx(eff["weight"], abs=0.03)
    np.testing.assert_allclose([p["ballast_x"]["value"], p["ballast_y"]["value"]], eff["position"][:2], atol=0.01)
    assert abs(p["ballast_mass"]["value"] - eff["mass"]) <= max(3 * p["ballast_mass"]["std"], 0.2 * eff["mass"])
    assert _main_rmse(rep, "rmse_after") <= 0.5 * _main_rmse(rep, "rmse_before")
    step1 = next(st for st in rep["steps"] if st["step"] == 1)  # step 0 is the base model's
    chosen = [c for c in step1["candidates"] if c["chosen"]]
    assert chosen[0]["variant"] == "xyz_mass" and "open-loop validation MSE" in chosen[0]["why"]
    # the pooled scores are mean log MSEs: at least 5 % lower in MSE
    assert np.exp(chosen[0]["open_loop_cost"] - next(c["open_loop_cost"] for c in step1["candidates"]
                                                     if c["variant"] in ("xy", "xyz") and "open_loop_cost" in c)) < 0.95


@pytest.mark.slow
def test_names_the_weak_thruster(tmp_path):
    """A PWM-driven vehicle with one thruster at half thrust: the diagnosis names the
    thruster and its gain (issue 14's undeclared per-thruster weakness)."""
    out, truth = _scenario(tmp_path, 3, input_kind="pwm", effects=[{"type": "weak_thruster", "magnitude": 0.5}])
    eff = truth["effects"][0]
    d = diagnose(out, retune=list(BASE_RETUNE))
    rep = d.report
    assert [e["effect"] for e in rep["effects"]] == ["thruster_gain"]
    params = rep["effects"][0]["parameters"]
    name = f"thruster_gain_{eff['thruster']}"  # truth.yaml numbers thrusters from 1, as the log columns
    assert name in params, params
    assert params[name]["value"] == pytest.approx(eff["gain"], abs=0.05)


@pytest.mark.slow
def test_two_effects_are_both_named(tmp_path):
    out, truth = _scenario(tmp_path, 7, n_runs=20, effects=["tether", "current"])
    d = diagnose(out, retune=list(BASE_RETUNE))
    named = {e["effect"] for e in d.report["effects"]}
    assert named == {TRUTH_TO_CATALOGUE.get(e["type"], e["type"]) for e in truth["effects"]}


# ----------------------------------------------------------------------------- shipped datasets
def _shipped(name):
    from pathlib import Path

    return Path(uvsim.__file__).parent / "data" / "datasets" / name


@pytest.mark.slow
def test_shipped_tank_tether_dataset_names_the_tether():
    """Seed 000 style (issue 6): the tether is named, its anchor and stiffness recovered."""
    d = diagnose(_shipped("bluerov2_tank_tether"), "bluerov2_heavy", workers=2)
    rep = d.report
    assert [e["effect"] for e in rep["effects"]] == ["tether"], rep["message"]
    p = rep["effects"][0]["parameters"]
    anchor = [p[f"tether_anchor_{k}"]["value"] for k in "ned"]  # truth (-4, 1, -1) m, 0.3 N/m (manifest)
    np.testing.assert_allclose(anchor, [-4.0, 1.0, -1.0], atol=0.3)
    assert p["tether_stiffness"]["value"] == pytest.approx(0.3, rel=0.2)
    assert rep["rmse_after"]["position_m"] <= 0.1 * rep["rmse_before"]["position_m"]


@pytest.mark.slow
def test_shipped_two_effect_dataset_names_both():
    """The tether + current dataset (examples/make_two_effect_dataset.py): both named,
    the current within 0.01 m/s of its truth.yaml value."""
    root = _shipped("bluerov2_two_effects")
    truth = load_truth(root)
    d = diagnose(root, workers=2)
    rep = d.report
    assert {e["effect"] for e in rep["effects"]} == {"tether", "current"}, rep["message"]
    cur = next(e for e in rep["effects"] if e["effect"] == "current")["parameters"]
    true = next(e for e in truth["effects"] if e["type"] == "current")["velocity_ned"]
    assert cur["current_n"]["value"] == pytest.approx(true[0], abs=0.01)
    assert cur["current_e"]["value"] == pytest.approx(true[1], abs=0.01)
    assert _main_rmse(rep, "rmse_after") <= 0.5 * _main_rmse(rep, "rmse_before")


@pytest.mark.slow
def test_cli_writes_report_corrected_vehicle_and_plots(tmp_path, capsys):
    out, _ = _scenario(tmp_path, 1, effects=[{"type": "current", "magnitude": 0.05}])
    rep, veh, plots = tmp_path / "r.json", tmp_path / "fixed.yaml", tmp_path / "plots"
    rc = main(["diagnose", "--data", str(out), "--retune", ",".join(BASE_RETUNE), "--json", str(rep),
               "--out", str(veh), "--plots", str(plots), "--quiet"])
    text = capsys.readouterr().out
    assert rc == 0, text
    assert "effects: current" in text and "verdict on the validation runs" in text and "VERDICT (exit 0) better" in text
    doc = json.loads(rep.read_text())
    assert doc["status"]["ok"] and doc["effect"] == "current"
    for key in ("steps", "rmse_before", "rmse_after", "validation_cost_per_entry", "criterion", "noise"):
        assert key in doc
    fixed = uvsim.load_vehicle(veh)
    assert [e.kind for e in fixed.effects] == ["current"]
    assert "diagnosed:" in veh.read_text()
    assert sorted(p.name for p in plots.iterdir()) == ["errors_over_time.png", "residual.png", "steps.png",
                                                      "validation_runs.png"]
    assert not list(tmp_path.glob("*.ckpt"))  # finished: the checkpoint (r.json.ckpt) is removed (issue 47)


@pytest.fixture(scope="module")
def small_clean(tmp_path_factory):
    """A small clean dataset, generated once for the tests that only read it."""
    return _scenario(tmp_path_factory.mktemp("clean"), 4, n_effects=0, n_runs=4, duration=[6, 6])[0]


@pytest.mark.parametrize("kw, match", [
    ({"only": ["currents"]}, "unknown candidate effect"),
    ({"max_effects": 0}, "max_effects"),
    ({"top": 0}, "top must be a positive integer"),
    ({"max_iter": 2.5}, "max_iter must be a positive integer"),
    ({"horizon": -1.0}, "horizon"),
    ({"retune": ["X_uuu"]}, "retune: unknown base parameter"),
])
def test_bad_options_are_clear_errors(small_clean, kw, match):
    with pytest.raises(CalibrationError, match=match):
        diagnose(small_clean, **kw)


def test_a_retuned_coefficient_on_the_edge_of_its_range_is_marked():
    """Field logs, clean seed 0 with the quadratic drags re-tuned: four of six ended at +50 % and the
    report printed them like any value. ``retuned`` now says which are on the edge of the re-tune's
    range in the last fit that freed them (kept: a coefficient far off is not unphysical)."""
    from types import SimpleNamespace

    from uvsim.diagnosis.summary import retuned_report

    veh = uvsim.load_vehicle("bluerov2_heavy")
    p = veh.parameters()
    sel = SimpleNamespace(retune=["X_uu", "Y_vv", "N_rr"])
    values = {"X_uu": 1.2 * p["X_uu"], "Y_vv": 1.5 * p["Y_vv"]}          # N_rr was not kept
    rep = retuned_report(sel, values, veh, SimpleNamespace(at_bounds=["Y_vv", "thruster_gain_1"]))
    assert rep == {"X_uu": {"value": values["X_uu"], "before": p["X_uu"], "at_bound": False},
                   "Y_vv": {"value": values["Y_vv"], "before": p["Y_vv"], "at_bound": True}}
    assert not any(d["at_bound"] for d in retuned_report(sel, values, veh, None).values())


def test_a_single_run_is_a_clear_error_that_says_how_to_make_runs(tmp_path):
    """An imported log is often one armed interval (the shipped ArduSub tlog): the error says how
    to cut it into runs rather than only that it is one."""
    from contract_data import TINY_RUNS, write_tiny_dataset

    ds = write_tiny_dataset(tmp_path / "one", runs=[(TINY_RUNS[0][0], "train")])
    with pytest.raises(CalibrationError, match=r"need at least 3 runs .* got 1: .*--segments"):
        diagnose(ds)


def test_a_diagnosis_that_fails_a_sanity_check_is_refused_not_called_worse(tmp_path, capsys, monkeypatch):
    """A sanity problem (e.g. every parameter of the accepted effect on its search bound: field tether
    seeds, every channel better or the same) used to make the status *worse*, a word the verdict's
    own table contradicted. It is *refused* (exit 2 as before, nothing written), and the VERDICT line
    says what the verdict alone said of the same model."""
    from uvsim.commands import diagnose as command

    monkeypatch.setattr(command, "diagnosis_problems", lambda rep, val: ["an injected problem"])
    out, _ = _scenario(tmp_path, 1, effects=[{"type": "current", "magnitude": 0.05}])
    rep, veh = tmp_path / "r.json", tmp_path / "fixed.yaml"
    rc = main(["diagnose", "--data", str(out), "--only", "current", "--retune", "X_u,N_r", "--json", str(rep),
               "--out", str(veh), "--quiet"])
    text = capsys.readouterr()
    doc = json.loads(rep.read_text())
    st, mv = doc["status"], doc["model_verdict"]
    assert rc == 2 and st["verdict"] == "refused" and st["exit_code"] == 2 and not st["ok"]
    assert mv["status"] == "better"   # the re-tune validates better: the verdict alone would keep it
    assert f"VERDICT (exit 2) refused: an injected problem; without the check the verdict is {mv['message']}" \
        in text.out
    assert "verdict refused: an injected problem" in text.err and not veh.exists()


def test_interrupted_diagnosis_resumes_without_repeating_finished_fits(tmp_path):
    """Every finished fit is checkpointed; a resumed run takes them from the file and reaches
    the same answer as an uninterrupted one."""
    out, _ = _scenario(tmp_path, 1, effects=[{"type": "current", "magnitude": 0.05}], n_runs=6, duration=[6, 8])
    kw = dict(retune=["X_u", "N_r"], only=["current", "ballast"], max_effects=1)
    ref = diagnose(out, **kw).report
    ck = tmp_path / "d.ckpt"
    seen = []

    def stop_at_second_fit(msg):
        seen.append(msg)
        if sum(m.startswith("fit ") for m in seen) == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        diagnose(out, checkpoint=ck, progress=stop_at_second_fit, **kw)
    assert ck.is_file()
    log = []
    rep = diagnose(out, resume=ck, progress=log.append, **kw).report
    assert any(m.startswith("resuming from") for m in log)
    assert sum("taken from the checkpoint" in m for m in log) >= 2  # the baseline fit and its validation cost
    assert rep["effect"] == ref["effect"]
    for e, e_ref in zip(rep["effects"], ref["effects"]):
        for k, d in e["parameters"].items():
            assert d["value"] == pytest.approx(e_ref["parameters"][k]["value"], rel=1e-9)
    # a checkpoint of other settings is refused, naming what must match
    with pytest.raises(CalibrationError, match="different settings"):
        diagnose(out, resume=ck, retune=["X_u"], only=["current", "ballast"], max_effects=1)


# ----------------------------------------------------------------------------- units
def test_catalogue_variants_follow_the_inputs_and_the_log():
    kw = dict(dt=0.02, p_ref=np.zeros(3), z_max=None)
    force = {c.label for c in catalogue(input_kind="force", n_thrusters=8, has_position=True, **kw)}
    pwm = {c.label for c in catalogue(input_kind="pwm", n_thrusters=8, has_position=True, **kw)}
    assert "thrust_asymmetry:per_dof" in force and "thrust_asymmetry:per_dof" not in pwm
    assert {"thruster_gain:unit_1", "thruster_gain:all", "tether:full", "current:3d",
            "coupled_damping:drag_centre_xz"} <= pwm
    no_pos = {c.effect for c in catalogue(input_kind="pwm", n_thrusters=8, has_position=False, **kw)}
    assert "tether" not in no_pos  # a tether needs the position (or depth) it pulls from
    assert {c.effect for c in catalogue(input_kind="pwm", n_thrusters=8, has_position=True, only=["ballast"],
                                        **kw)} == {"ballast"}
    with pytest.raises(CalibrationError, match="unknown candidate effect"):
        catalogue(input_kind="pwm", n_thrusters=8, has_position=True, only=["tethers"], **kw)
    assert set(EFFECTS) >= {c.effect for c in catalogue(input_kind="pwm", n_thrusters=8, has_position=True,
                                                        z_max=2.0, dt=0.02, p_ref=np.zeros(3))}


def test_every_candidate_has_a_null_and_valid_start():
    for c in catalogue(input_kind="pwm", n_thrusters=8, has_position=True, z_max=2.0, dt=0.02, p_ref=np.zeros(3)):
        assert c.null, c.label  # the Wald test has something to test
        for n in c.free:
            lo, hi = c.bounds[n]
            assert lo <= c.start[n] <= hi, (c.label, n)


def test_bootstrap_improvement_needs_consistent_windows():
    rng = np.random.default_rng(0)
    a = rng.uniform(90, 110, 40)
    better = a * 0.8 + rng.normal(0, 1, 40)
    r = bootstrap_improvement(a, better)
    assert r["significant"] and r["p_better"] == 1.0 and r["relative"] == pytest.approx(0.2, abs=0.02)
    one_window = a.copy()
    one_window[0] -= 500  # a single window carries the whole "improvement"
    r = bootstrap_improvement(a, one_window)
    assert not r["significant"] and 0.4 < r["p_better"] < 1.0
    with pytest.raises(ValueError):
        bootstrap_improvement(a, a[:3])


def test_stepwise_finds_the_regressors_that_made_the_residual():
    rng = np.random.default_rng(3)
    J = rng.normal(size=(8, 400))
    names = ["K_v", "K_vv", "M_u", "M_uu", "N_v", "N_vv", "X_q", "Y_p"]
    r = -(0.7 * J[1] - 1.3 * J[5]) + rng.normal(0, 0.05, 400)
    assert sorted(_stepwise(J, r, names, k=2)) == ["K_vv", "N_vv"]
    # at most one derivative per force row
    r = -(J[0] + J[1])
    assert len({n[0] for n in _stepwise(J, r, names, k=2)}) == 2


def test_drag_centre_moment_is_the_lever_arm_of_the_translational_drag():
    v = uvsim.load_vehicle("bluerov2_heavy").with_effects([{"type": "drag_centre", "x": 0.05, "z": -0.02}])
    m = uvsim.Model(v)
    y = m.initial_state(nu=[0.3, -0.2, 0.1, 0, 0, 0])
    tau = v.effects[0].forces(_ctx(m, y), v.effects[0].prepare(m.params, 1))[0]
    p = v.parameters()
    f = np.array([(p["X_u"] + p["X_uu"] * 0.3) * 0.3, (p["Y_v"] + p["Y_vv"] * 0.2) * -0.2,
                  (p["Z_w"] + p["Z_ww"] * 0.1) * 0.1])
    np.testing.assert_allclose(tau[:3], 0.0)
    np.testing.assert_allclose(tau[3:], np.cross([0.05, 0.0, -0.02], f), rtol=1e-12)


def _ctx(model, y):
    from uvsim.forces.base import Context
    from uvsim.kinematics import quat_to_rotation

    R = quat_to_rotation(y[:, 3:7])
    return Context(0.0, y[:, :3], y[:, 3:7], R, y[:, 7:13], y[:, 7:13], np.zeros((1, 6)), "force", model.weight,
                   model.mass, model.r_g, {}, model.params)


def test_horizontal_tether_pulls_only_horizontally():
    from uvsim.forces import make_term

    t = make_term({"type": "tether", "stiffness": 2.0, "anchor_n": -3.0, "anchor_d": -4.0, "horizontal": True})
    v = uvsim.load_vehicle("bluerov2_heavy").with_effects([t])
    m = uvsim.Model(v)
    y = m.initial_state()
    f = v.effects[0].forces(_ctx(m, y), v.effects[0].prepare(m.params, 1))[0]
    np.testing.assert_allclose(f[:3], [-6.0, 0.0, 0.0], atol=1e-12)  # k * 3 m towards the anchor, no vertical part


def test_slack_starts_move_the_anchor_out_along_the_line_keeping_the_pull():
    """A slack variant's extra starts (uvsim.diagnosis.starts.slack_starts): the anchor of a fit without
    slack moved out along its line from the reference position, the slack chosen so that
    the uvsim tether pulls the vehicle there exactly as the start did."""
    from uvsim.diagnosis.starts import SLACK_START_DISTANCE, slack_starts
    from uvsim.forces import make_term

    p_ref = np.array([0.3, -0.2, 1.2])
    cands = {c.variant: c for c in catalogue(input_kind="force", n_thrusters=8, dt=0.01, p_ref=p_ref,
                                             has_position=True, z_max=2.0)
             if c.effect == "tether"}
    def pull(c, st):
        """The tether's force (body axes) on the vehicle at rest, level, at p_ref."""
        spec = {**c.spec, **{k.removeprefix("tether_"): v for k, v in st.items() if k in c.free}}
        v = uvsim.load_vehicle("bluerov2_heavy").with_effects([make_term(spec)])
        m = uvsim.Model(v)
        y = m.initial_state()
        y[:, :3] = p_ref
        return v.effects[0].forces(_ctx(m, y), v.effects[0].prepare(m.params, 1))[0][:3]

    for variant, horizontal in (("horizontal_slack", True), ("slack_attach", False)):
        c = cands[variant]
        st = {**c.start, "tether_stiffness": 0.4, "tether_anchor_n": 1.1, "tether_anchor_e": 0.4,
              "tether_anchor_d": 1.5}
        out = slack_starts(c, st)
        assert len(out) == 1
        v0 = np.array([1.1, 0.4, 1.5]) - p_ref
        if horizontal:
            v0[2] = 0.0
        for D, o in zip([SLACK_START_DISTANCE], out):
            a = np.array([o["tether_anchor_n"], o["tether_anchor_e"], o["tether_anchor_d"]]) - p_ref
            if horizontal:
                assert o["tether_anchor_d"] == st["tether_anchor_d"]  # not free, not moved
                a[2] = 0.0
            assert np.linalg.norm(a) == pytest.approx(D)
            np.testing.assert_allclose(np.cross(a, v0), 0.0, atol=1e-12)  # on the start's line
            assert a @ v0 > 0  # on the start's side
            assert o["tether_slack_length"] == pytest.approx(D - np.linalg.norm(v0))
            np.testing.assert_allclose(pull(c, o), pull(c, st), atol=1e-12)
    # nothing to add for a variant without slack or a start that already has one
    assert slack_starts(cands["3d_attach"], cands["3d_attach"].start) == []
    assert slack_starts(cands["slack_attach"], {**cands["slack_attach"].start, "tether_slack_length": 1.0}) == []


def test_screening_finds_a_cable_taut_from_a_distant_anchor(tmp_path):
    """An elastic cable taut from an anchor 3.6 m away (3.1 m slack) pulls along one
    direction and barely across it.  The screening's slack variant, started from the fit
    without slack (anchor next to the vehicle) and moved out along its line, finds the
    attachment point and the direction to the anchor of the independent truth model; from
    the start without slack alone it stayed near the vehicle (attachment 15 cm off).
    Generator seed 1 is the first whose tether is elastic (its law is drawn)."""
    from uvsim.diagnosis.core import _split
    from uvsim.diagnosis.selector import Selector
    from uvsim.logs import read_dataset

    out, truth = _scenario(tmp_path, 1, rate_hz=100.0,
                           effects=[{"type": "tether", "variant": "horizontal", "magnitude": 0.5}])
    tt = truth["effects"][0]
    assert tt["law"] == "elastic" and tt["slack_length"] > 3.0
    ds = read_dataset(out)
    veh = uvsim.load_vehicle(ds.vehicle_file or ds.vehicle)
    train, val, _ = _split(ds)
    sel = Selector(veh, train, val, retune=list(BASE_RETUNE), noise=None, weights=None, horizon=3.0, max_iter=12,
                   workers=1, say=lambda m: None)
    cur = sel.current([], sel.seed_retune(veh))
    p_ref = np.nanmean([r.position[0] for r in train], axis=0)
    cands = [c for c in catalogue(input_kind=train[0].input_kind, n_thrusters=veh.n_thrusters, dt=0.01, p_ref=p_ref,
                                  has_position=True, z_max=2.0, only=["tether"])
             if c.variant in ("horizontal", "slack_attach")]
    got = {c.variant: s for c, s in sel.screen(cur, cands, coupled=False)[0]}["slack_attach"]["values"]
    attach = [got[f"tether_attach_{k}"] for k in "xyz"]
    np.testing.assert_allclose(attach, tt["attach_body"], atol=0.02)
    d_fit = np.array([got["tether_anchor_n"], got["tether_anchor_e"]]) - p_ref[:2]
    d_true = np.array(tt["anchor_ned"][:2]) - p_ref[:2]
    cos = d_fit @ d_true / np.linalg.norm(d_fit) / np.linalg.norm(d_true)
    assert np.degrees(np.arccos(min(cos, 1.0))) < 10.0


# ----------------------------------------------------------------------------- the benchmark
@pytest.mark.slow
def test_benchmark_100_single_and_30_two_effect_scenarios(tmp_path):
    """Issue 10's acceptance numbers on the independent scenarios (docs/diagnose.md)."""
    from uvsim.benchmarks.scenarios import run_benchmark

    s = run_benchmark(100, 0, two_effects=30, workers=2, results=tmp_path / "r.jsonl")["summary"]
    # issue 10's targets, all met in the recorded run (2026-11-23: 95/100 correct, 0 % of 22 clean,
    # 100/100 correct detections halved, 27/30 two-effect; docs/diagnose.md)
    assert s["false_positive_rate_clean"] <= 0.05
    assert s["two_effects"]["both_named_rate"] >= 0.8
    assert s["single_or_clean"]["correct_rate"] >= 0.95
    assert s["halved_share_of_correct_detections"] == 1.0


# ----------------------------------------------------------------------------- decision rules (stub fits)
def _row(cand, cost, *, p=1e-9, relative=0.5, p_better=1.0, n=40, seed=0):
    """A fitted-candidate row as Selector.fit_candidate makes it, with given numbers."""
    rng = np.random.default_rng(seed)
    w = rng.uniform(0.5, 1.5, n)
    return {"candidate": cand, "problem": None, "val": {"cost": cost, "windows": w * cost / w.sum()},
            "compare": {"wald": {"p": p}, "relative": relative, "p_better": p_better}}


class _StubSelector:
    """fit_candidate returns the prepared row of a candidate and counts the fits;
    open_loop_cost reads the row's stand-in vehicle as an open-loop MSE and returns the pooled
    score, its log (uvsim.fitting.verdict.score)."""

    def __init__(self, rows):
        self.rows, self.fitted = rows, []

    def fit_candidate(self, c, s, cur, val_cur):
        self.fitted.append(c.label)
        return dict(self.rows[c.label])

    def open_loop_cost(self, vehicle, values):
        return float(np.log(vehicle))


def test_lag_start_alternative_is_fitted_and_the_lower_open_loop_cost_wins():
    """Benchmark seed 6: the two lag starts have the same windowed validation cost (each
    window's initial velocities absorb the start), so the free simulation decides."""
    from uvsim.diagnosis.step_choice import alternative_challenger

    steady, rest = catalogue(input_kind="thrust", n_thrusters=8, dt=0.02, p_ref=np.zeros(3), has_position=True,
                             z_max=None, only=["thruster_lag"])
    st = {"all_screened": [(steady, {"reduction": 0.8}), (rest, {"reduction": 0.7})], "cur": {}, "fitted": []}

    def with_ol(row, ol):
        return {**row, "vehicle": ol, "all_values": {}, "why": "significant"}

    best = with_ol(_row(steady, 100.0), 50.0)
    sel = _StubSelector({"thruster_lag:from_rest": with_ol(_row(rest, 100.1), 10.0)})
    new = alternative_challenger(sel, best, st, None)
    assert sel.fitted == ["thruster_lag:from_rest"] and new["candidate"] is rest
    assert "open-loop" in new["why"]
    # a worse (open loop) or a rejected alternative keeps the winner (and is still reported)
    for row in (with_ol(_row(rest, 90.0), 60.0), with_ol(_row(rest, 90.0, p=0.5), 1.0)):
        st["fitted"] = []
        assert alternative_challenger(_StubSelector({"thruster_lag:from_rest": row}), best, st, None) is None
        assert [r["candidate"] for r in st["fitted"]] == [rest]
    # effects without alternatives fit nothing more
    cur = catalogue(input_kind="thrust", n_thrusters=8, dt=0.02, p_ref=np.zeros(3), has_position=True,
                    z_max=None, only=["current"])[0]
    sel = _StubSelector({})
    assert alternative_challenger(sel, _row(cur, 100.0), {"all_screened": [(cur, {})]}, None) is None
    assert sel.fitted == []


def test_an_alternative_of_a_variant_the_guard_refused_can_win_but_never_the_refused_variant():
    """Benchmark pair 118: a lag from rest fitted as ``steady`` removes most of the windowed
    validation cost and makes the free simulation worse (the runs' start is wrong), so the
    guard refuses it; the alternative start is fitted and wins only when it is accepted
    itself, and an alternative fitted before in the step is not fitted again."""
    from uvsim.diagnosis.step_choice import alternative_challenger

    steady, rest = catalogue(input_kind="thrust", n_thrusters=8, dt=0.02, p_ref=np.zeros(3), has_position=True,
                             z_max=None, only=["thruster_lag"])
    screened = [(steady, {"reduction": 0.9}), (rest, {"reduction": 0.9})]

    def with_ol(row, ol, **extra):
        return {**row, "vehicle": ol, "all_values": {}, "why": "significant", **extra}

    # the refused variant has the lower open-loop cost here: it must not come back
    blocked = with_ol(_row(steady, 100.0), 1.0, accepted=False, guard_blocked=True)
    good = with_ol(_row(rest, 100.0), 5.0)
    st = {"all_screened": screened, "cur": {}, "fitted": [blocked]}
    sel = _StubSelector({"thruster_lag:from_rest": good})
    new = alternative_challenger(sel, blocked, st, None, blocked=True)
    assert sel.fitted == ["thruster_lag:from_rest"] and new["candidate"] is rest
    assert "verdict refused" in new["why"] and new["open_loop_cost"] == pytest.approx(np.log(5.0))
    # an alternative that is refused itself (here by its guard) does not win
    refused = with_ol(_row(rest, 100.0), 5.0)
    refused["compare"] = {**refused["compare"], "guard": {"ok": False, "why": "position +50 %"}}
    st = {"all_screened": screened, "cur": {}, "fitted": [blocked]}
    assert alternative_challenger(_StubSelector({"thruster_lag:from_rest": refused}), blocked, st, None,
                                  blocked=True) is None
    # fitted earlier in the step: not fitted again; accepted there, it competes
    st = {"all_screened": screened, "cur": {}, "fitted": [blocked, {**good, "accepted": True}]}
    sel = _StubSelector({})
    new = alternative_challenger(sel, blocked, st, None, blocked=True)
    assert sel.fitted == [] and new["candidate"] is rest and len(st["fitted"]) == 2


@pytest.mark.parametrize("simple_cost, keeps_rich", [(104.0, False), (126.0, True)])
def test_a_simpler_variant_must_be_within_five_percent_of_the_winner(simple_cost, keeps_rich):
    """Benchmark seed 91: the pull-only tether, 26 % worse on validation than the cable-drag
    tether, must not replace it even when the bootstrap over a few windows is inconclusive."""
    from uvsim.diagnosis.step_choice import simplest_sufficient

    tethers = {c.variant: c for c in catalogue(input_kind="pwm", n_thrusters=8, dt=0.02, p_ref=np.zeros(3),
                                               has_position=True, z_max=None, only=["tether"])}
    rich, simple = tethers["drag_attach"], tethers["3d_attach"]
    assert simple.complexity < rich.complexity
    st = {"all_screened": [(rich, {"reduction": 0.5}), (simple, {"reduction": 0.45})], "cur": {}, "fitted": []}
    sel = _StubSelector({simple.label: _row(simple, simple_cost, seed=1)})
    out = simplest_sufficient(sel, _row(rich, 100.0), st, None)
    assert sel.fitted == [simple.label]
    assert (out is None) == keeps_rich
    assert st["fitted"][0]["accepted"] == (not keeps_rich)


def test_a_variant_on_a_search_bound_is_followed_once_by_the_best_screened_variant_without_it():
    """Pair 110: the screening's tether variant ran its slack length to the 50 m search
    bound; the effect's best-screened variant without a slack length, not fitted yet, gets
    its fit (judged like any), once per effect; a refusal for another reason fits nothing
    more."""
    from uvsim.diagnosis.selector import Selector

    t = {c.variant: c for c in catalogue(input_kind="thrust", n_thrusters=8, dt=0.01, p_ref=np.zeros(3),
                                         has_position=True, z_max=None, only=["tether"])}
    cur = catalogue(input_kind="thrust", n_thrusters=8, dt=0.01, p_ref=np.zeros(3), has_position=True,
                    z_max=None, only=["current"])[0]
    screened = [(t["horizontal_full"], {"reduction": 0.41}), (t["full"], {"reduction": 0.39}),
                (t["drag_attach"], {"reduction": 0.36}), (t["lumped_attach"], {"reduction": 0.30}),
                (t["3d"], {"reduction": 0.0}), (cur, {"reduction": 0.5})]

    def on_bound(c, n="tether_slack_length"):
        return {**_row(c, 100.0), "values": {**c.start, n: c.bounds[n][1]}, "at_bounds": [n]}

    def good(c):
        return {**_row(c, 90.0), "values": dict(c.start), "at_bounds": []}

    # slack on its bound: `full` has a slack length too, so `drag_attach` follows; accepted, it says what it replaces
    sel, fitted = _StubSelector({"tether:horizontal_full": on_bound(t["horizontal_full"]),
                                 "tether:drag_attach": good(t["drag_attach"])}), []
    assert Selector.fit_judged(sel, t["horizontal_full"], {}, {}, None, fitted, screened, set())
    assert sel.fitted == ["tether:horizontal_full", "tether:drag_attach"]
    assert fitted[0]["bound_rejected"] and not fitted[0]["accepted"]
    assert fitted[1]["accepted"] and fitted[1]["replaces"] == "tether:horizontal_full"
    # an anchor coordinate on its bound: every tether variant has one, so nothing follows
    sel = _StubSelector({"tether:horizontal_full": on_bound(t["horizontal_full"], "tether_anchor_n")})
    assert not Selector.fit_judged(sel, t["horizontal_full"], {}, {}, None, [], screened, set())
    assert sel.fitted == ["tether:horizontal_full"]
    # once per effect: a second bound-refused variant fits nothing more
    sel, replaced = _StubSelector({"tether:horizontal_full": on_bound(t["horizontal_full"]),
                                   "tether:drag_attach": on_bound(t["drag_attach"], "tether_anchor_d")}), set()
    assert not Selector.fit_judged(sel, t["horizontal_full"], {}, {}, None, [], screened, replaced)
    assert not Selector.fit_judged(sel, t["drag_attach"], {}, {}, None, [], screened, replaced)
    assert sel.fitted == ["tether:horizontal_full", "tether:drag_attach", "tether:drag_attach"]
    # refused for another reason (not significant): nothing more
    sel = _StubSelector({"tether:horizontal_full": {**good(t["horizontal_full"]),
                                                     **_row(t["horizontal_full"], 100.0, p=0.5)}})
    assert not Selector.fit_judged(sel, t["horizontal_full"], {}, {}, None, [], screened, set())
    assert sel.fitted == ["tether:horizontal_full"]


def test_a_ballast_piece_mass_is_fitted_from_the_winner_and_kept_on_a_lower_open_loop_cost():
    """Benchmark seed 38: a 10 g foam block's mass is invisible to the windowed cost
    (within 0.04 %) but decides the open-loop validation run; the mass variant is not
    screened, it is fitted from the winner's values and wins only on an open-loop cost at
    least 5 % lower."""
    from types import SimpleNamespace

    from uvsim.diagnosis.step_choice import inertia_challenger

    cands = {c.variant: c for c in catalogue(input_kind="force", n_thrusters=8, dt=0.04, p_ref=np.zeros(3),
                                             has_position=True, z_max=None, only=["ballast"])}
    xy, mass = cands["xy"], cands["xyz_mass"]
    assert mass.tags.get("open_loop") and not xy.tags.get("open_loop")
    st = {"held": [mass], "cur": {"vehicle": SimpleNamespace(g=9.81)}, "fitted": []}
    vals = {"ballast_weight": -0.206, "ballast_x": -0.019, "ballast_y": 0.1}
    best = {**_row(xy, 100.0), "vehicle": 600.0, "all_values": {"X_udot": 14.0, **vals}, "values": vals,
            "why": "significant"}
    seeds = []

    class Sel(_StubSelector):
        def fit_candidate(self, c, s, cur, val_cur):
            seeds.append(s["values"])
            return super().fit_candidate(c, s, cur, val_cur)

    def row(ol, **kw):
        return {**_row(mass, 100.05, **kw), "vehicle": ol, "all_values": {}, "why": "significant"}

    new = inertia_challenger(Sel({mass.label: row(54.0)}), best, st, None)
    assert new["candidate"] is mass and "open-loop" in new["why"]
    # started from the winner's values (base coefficients included) and a mass of |w| / g
    assert seeds[0]["X_udot"] == 14.0 and seeds[0]["ballast_weight"] == -0.206
    assert seeds[0]["ballast_mass"] == pytest.approx(0.206 / 9.81)
    # not 5 % lower, rejected by the tests, or diverging: the winner stays (the fit is reported)
    for r in (row(580.0), row(1.0, p=0.5), row(float("inf"))):
        st["fitted"] = []
        assert inertia_challenger(Sel({mass.label: r}), best, st, None) is None
        assert [x["candidate"] for x in st["fitted"]] == [mass]
    # other effects have no inertial variant: nothing is fitted
    cur = catalogue(input_kind="force", n_thrusters=8, dt=0.04, p_ref=np.zeros(3), has_position=True,
                    z_max=None, only=["current"])[0]
    sel = Sel({})
    assert inertia_challenger(sel, {**_row(cur, 100.0), "values": {}}, st, None) is None and sel.fitted == []


def test_a_variant_the_verdict_refused_gets_a_simpler_one_tried():
    """The foreign suite's kind of case b, in stubs: a 3-D tether with its attachment free is
    refused by the open-loop verdict (a trade-off: position bought with depth), nothing else is
    accepted, and the horizontal variant (simpler, half the screening reduction or more) is fitted
    and accepted: the fallback tries simpler variants as it tries richer ones and alternatives."""
    from uvsim.diagnosis.step_choice import blocked_fallback

    cands = {c.variant: c for c in catalogue(input_kind="force", n_thrusters=8, dt=0.02, p_ref=np.zeros(3),
                                             has_position=True, z_max=None, only=["tether"])}
    rich, simple = cands["lumped_attach"], cands["horizontal_lumped"]
    assert simple.complexity < rich.complexity
    blocked = {**_row(rich, 72.7), "accepted": False, "guard_blocked": True, "why": "trade-off: z +202 %",
               "vehicle": 1.0, "all_values": {}}
    st = {"all_screened": [(rich, {"reduction": 0.70}), (simple, {"reduction": 0.49})], "cur": {}, "fitted": [blocked],
          "held": []}
    good = {**_row(simple, 1.0), "vehicle": 1.0, "all_values": {}}
    sel = _StubSelector({simple.label: good})
    win = blocked_fallback(sel, st, None)
    assert win is not None and win["candidate"] is simple and sel.fitted == [simple.label]
    assert "simplest variant" in win["why"]
    # refused by the verdict itself, the simpler variant does not win either
    bad = {**good, "compare": {**good["compare"], "guard": {"ok": False, "why": "trade-off: x +30 %"}}}
    st["fitted"] = [blocked]
    assert blocked_fallback(_StubSelector({simple.label: bad}), st, None) is None


def test_a_richer_variant_accepted_after_a_refusal_is_chosen_though_not_significantly_better():
    """Slow test seed 7 (tether + current), in stubs: the screened tether variant (slack_attach)
    is a trade-off, its richer variant (full) is fitted by the fallback and accepted, but is not
    significantly better on validation than the refused row; it is still the step's choice (it
    was chosen nowhere before this fix, and the diagnosis named nothing)."""
    from uvsim.diagnosis.step_choice import blocked_fallback

    cands = {c.variant: c for c in catalogue(input_kind="force", n_thrusters=8, dt=0.02, p_ref=np.zeros(3),
                                             has_position=True, z_max=None, only=["tether"])}
    refused, rich = cands["slack_attach"], cands["full"]
    blocked = {**_row(refused, 10.0), "accepted": False, "guard_blocked": True, "why": "trade-off: x +141 %",
               "vehicle": 1.0, "all_values": {}}
    st = {"all_screened": [(refused, {"reduction": 0.45}), (rich, {"reduction": 0.46})], "cur": {},
          "fitted": [blocked], "held": []}
    accepted = {**_row(rich, 9.9, seed=1), "vehicle": 1.0, "all_values": {}}  # as good, not significantly better
    sel = _StubSelector({rich.label: accepted})
    win = blocked_fallback(sel, st, None)
    assert sel.fitted[0] == rich.label
    assert win is not None and win["candidate"] is rich and win["accepted"]
    assert "in place of tether:slack_attach" in win["why"]


def test_an_effect_clearly_better_than_the_base_models_thrust_scale_takes_its_place():
    """Field-log benchmark, dead case seed 1 (issue 48), in stubs: step 0 accepted the thrust
    scale on its 0.5 bound (validation cost 6786 squared noise sigmas per residual) and pre-empted
    the dead unit, which on the given model gives 489; the effect now wins.  A curve mismatch, where
    the units' gains explain no more than the one scale, keeps the base model, and so does a step
    without an accepted effect."""
    from uvsim.diagnosis.step_choice import base_effect_challenge, base_effect_kept

    (scale,) = [c for c in catalogue(input_kind="pwm", n_thrusters=8, dt=0.2, p_ref=np.zeros(3), has_position=False,
                                     z_max=None, only=["base_model"], base={}) if c.variant == "thrust_scale"]
    units = {c.variant: c for c in catalogue(input_kind="pwm", n_thrusters=8, dt=0.2, p_ref=np.zeros(3),
                                             has_position=False, z_max=None, only=["thruster_gain"])}

    def row(c, cost, seed):
        r = _row(c, cost, seed=seed)
        r["val"]["per_entry"] = cost / 100.0
        return r

    base = row(scale, 678_600.0, 0)
    why = base_effect_challenge(base, row(units["reversed_6"], 48_900.0, 1))
    assert why is not None and "thruster_gain:reversed_6" in why and "clearly better" in why
    # as good as the scale (a curve mismatch that every unit's gain says again): the scale stays
    same = row(units["all"], 678_000.0, 2)
    assert base_effect_challenge(base, same) is None
    assert "not clearly better" in base_effect_kept(base, same)
    assert base_effect_challenge(base, None) is None and "no effect" in base_effect_kept(base, None)


def test_a_dead_vertical_thruster_is_not_pre_empted_by_the_base_models_thrust_scale(tmp_path):
    """A vertical thruster dead (gain 0), nothing else wrong, 4 short PWM runs at 10 Hz: the thrust
    scale of step 0 is accepted (it absorbs part of the missing thrust) but the dead unit explains the
    validation runs clearly better (before the base model's challenge, the scale stayed and the unit
    was named reversed, "at 0.10 of its curve").  Every gain on the given model wins the challenge
    (thruster 8 at 0, the others 0.85-0.95 for the perturbed hydrodynamics), and the scale with thruster
    8 alone is as good (step_choice.unit_beside_base; before, ``thruster_gain:all`` was named); the
    hydrodynamics are re-tuned in step 2, after which the scale is 1 again.  Since the unit's forms are
    fitted beside every gain in the challenge step (unit_choice.unit_forms), thruster 8 alone on the
    given model wins that step (validation cost 5.0 against every gain's 7.7), the scale is set aside
    and only the hydrodynamics are re-tuned: the same unit, at the noise level, without the scale."""
    out, truth = _scenario(tmp_path, 0, input_kind="pwm", n_runs=4, duration=[6, 8], rate_hz=10.0,
                           effects=[{"type": "weak_thruster", "magnitude": 1.0}])
    eff = truth["effects"][0]
    assert eff["gain"] == 0.0 and eff["thruster"] == 8
    rep = diagnose(out).report
    step0 = rep["steps"][0]
    assert step0["base_challenge"]["best_effect"] == "thruster_gain:unit_8" and not step0["base_challenge"]["kept"]
    assert [(e["effect"], e["variant"]) for e in rep["effects"]] == [("thruster_gain", "unit_8")]
    assert "thruster 8 gives no thrust" in rep["effects"][0]["answer"]
    assert rep["base_model"]["variant"] == "hydrodynamics"
    assert rep["validation_cost_per_entry"]["final"] < 1.5  # at the noise level


def test_a_dead_unit_beside_a_thrust_curve_off_is_named_as_the_unit_not_as_every_gain(tmp_path):
    """The dead vertical thruster 8 of the test above, on a given model whose thrust curve is 1.5
    times the truth's (every unit): every gain on the given model (thruster 8 at 0, the others at
    0.67) wins the base model's challenge, but the curve scaled plus thruster 8 alone, two
    parameters, is as good on validation, so the scale stays and the unit is named (field-log
    benchmark, dead case seed 21: ``thruster_gain:all`` with thruster 7 at 0 and the others
    0.55-0.67; step_choice.unit_beside_base).  Before, ``thruster_gain:all`` was named."""
    import pandas as pd

    from uvsim.thrust_curves import DATA_DIR

    out, truth = _scenario(tmp_path, 0, input_kind="pwm", n_runs=4, duration=[6, 8], rate_hz=10.0,
                           effects=[{"type": "weak_thruster", "magnitude": 1.0}])
    assert truth["effects"][0]["gain"] == 0.0 and truth["effects"][0]["thruster"] == 8
    tab = pd.read_csv(DATA_DIR / "t200_16v.csv")
    tab["thrust_N"] *= 1.5
    tab.to_csv(out / "strong.csv", index=False)
    veh = (out / "myrov.yaml").read_text()
    (out / "myrov.yaml").write_text(veh.replace("curve: t200_16v", f"curve: {{csv: {out / 'strong.csv'}}}"))
    rep = diagnose(out).report
    step0 = rep["steps"][0]
    assert step0["chosen"] == "base_model:thrust_scale" and step0["base_challenge"]["kept"]
    nested = step0["base_challenge"]["nested"]
    assert step0["base_challenge"]["best_effect"] == "thruster_gain:all" and nested["accepted"]
    assert rep["base_model"]["variant"].startswith("thrust_scale")
    assert 0.55 < rep["base_model"]["parameters"]["thrust_scale_scale"]["value"] < 0.8  # 1 / 1.5, base coefficients perturbed
    assert [(e["effect"], e["variant"]) for e in rep["effects"]] == [("thruster_gain", "unit_8")]
    assert "thruster 8 gives no thrust" in rep["effects"][0]["answer"]
    # no sanity problem (exit 2): the dead unit's gain 0 is a physical floor, and the scale the final
    # fit leaves inside its range is not "on a bound" because step 0's fit put it there
    from uvsim.commands.checks import diagnosis_problems
    from uvsim.logs import read_dataset

    assert not rep["effects"][0]["parameters"]["thruster_gain_8"]["at_bound"]
    assert not rep["base_model"]["parameters"]["thrust_scale_scale"]["at_bound"]
    val = [r for r in read_dataset(out).runs if r.split == "validation"]
    assert not [p for p in diagnosis_problems(rep, val) if "bound" in p]
