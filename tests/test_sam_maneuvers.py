"""SAM hydrobatic maneuvers: seed 003 sec. V-C / V-D statements asserted on what we simulate."""
import numpy as np
import pytest

from uvsim.maneuvers import MANEUVERS, dominant_frequency, run_maneuver


@pytest.fixture(scope="module")
def results():
    return {}


def _get(results, name, dataset="multifidelity"):
    key = (name, dataset)
    if key not in results:
        results[key] = run_maneuver(name, dataset=dataset)
    return results[key]


def test_tight_loop_flips_in_a_small_box(results):
    r = _get(results, "tight_loop")
    m = r.metrics
    # seed 003 V-C-1: "remains in a box of dimension of 5 m", "pitch angle goes up to 180 deg"
    assert m["box_xz_m"] < 5.0
    assert m["box_xz_m"] > 1.0
    assert m["flight_path_rotation_deg"] > 360.0      # several full loops in 30 s
    assert m["max_abs_pitch_deg"] > 85.0              # Euler pitch passes through the vertical
    assert m["extent_y_m"] < 0.5                      # stays in the vertical plane
    # "the surge-direction thrust is essentially canceled out": mean surge well below the
    # straight-run speed at full rpm (about 3.5 m/s)
    assert abs(m["mean_surge_m_s"]) < 0.3


def test_turbo_turn_yaw_envelope_and_1hz(results):
    r = _get(results, "turbo_turn")
    m = r.metrics
    assert m["heading_rotation_deg"] > 360.0          # yaw through the full envelope (Fig. 23)
    assert m["box_xy_m"] < 5.0                        # confined area (Fig. 21)
    assert m["yaw_rate_freq_hz"] == pytest.approx(1.0, abs=0.1)   # Fig. 30: close to 1 Hz
    r_rate = r.frame["r"].to_numpy()[r.frame["t"].to_numpy() > 5]
    assert r_rate.min() > 0                           # a turn, modulated by the cycle
    assert m["yaw_rate_amplitude_rad_s"] > 0.02       # ... with a visible oscillation
    assert abs(m["mean_surge_m_s"]) < 0.3             # surge thrust essentially canceled (sec. V-C-1)
    assert abs(m["depth_change_m"]) < 0.5             # level turn without depth control


def test_helix_rolls_through_the_full_envelope(results):
    r = _get(results, "helix")
    m = r.metrics
    # seed 003 V-C-3 / Fig. 26: roll encompasses the full envelope, in a confined box
    assert m["roll_range_deg"] > 360.0                # rolls over completely (unwrapped roll)
    roll = np.degrees(r.frame["roll"].to_numpy())
    assert roll.min() < -170.0 and roll.max() > 170.0
    assert abs(r.frame["z"].iloc[-1]) > 3.0           # it progresses along the vertical
    assert max(m["extent_x_m"], m["extent_y_m"], m["extent_z_m"]) < 10.0


@pytest.mark.xfail(strict=True, reason="with the sourced reverse thrust (0.797) the constant +7 deg yaw vector "
                                       "of our helix commands nearly cancels over a cycle: heading turns 292 deg, "
                                       "not the full yaw envelope of seed 003 Fig. 26 (docs/sam.md)")
def test_helix_yaws_through_the_full_envelope(results):
    assert _get(results, "helix").metrics["heading_rotation_deg"] > 360.0


def test_lcg_sweep_pitches_near_vertical_without_propellers(results):
    r = _get(results, "lcg_sweep")
    df = r.frame
    assert np.all(df["rpm_1_act"] == 0) and np.all(df["rpm_2_act"] == 0)
    assert r.metrics["min_pitch_deg"] < -75.0         # LCG forward: nose down (Fig. 29)
    assert r.metrics["max_pitch_deg"] > 75.0          # LCG back: nose up
    assert r.metrics["max_speed_m_s"] < 0.2           # stationary maneuver
    assert max(r.metrics["extent_x_m"], r.metrics["extent_y_m"]) < 1.0


def test_accelerating_turn_datasets_differ_but_bounded(results):
    runs = {ds: _get(results, "accelerating_turn", ds) for ds in ("jorgensen", "datcom", "multifidelity")}
    P = {ds: r.frame[["x", "y", "z"]].to_numpy() for ds, r in runs.items()}
    speed = {ds: r.metrics["max_speed_m_s"] for ds, r in runs.items()}
    ref = P["multifidelity"]
    scale = np.ptp(ref, axis=0).max()
    d = np.abs(P["jorgensen"] - ref).max()
    assert d > 1e-3                                      # the hull data set matters ...
    assert d < 0.5 * scale                               # ... but the trajectories stay alike
    for ds in ("jorgensen", "datcom"):
        assert speed[ds] == pytest.approx(speed["multifidelity"], rel=0.1)
    # multifidelity is DATCOM below 12 deg (Algorithm 1 without CFD): a turn that never takes the
    # hull past 12 deg of incidence runs on the same table cells
    f = runs["multifidelity"].frame
    incidence = np.degrees(np.arctan2(np.hypot(f["v"], f["w"]), f["u"])[f["t"] > 0.5])
    assert incidence.max() < 12.0
    np.testing.assert_allclose(P["datcom"], ref, atol=1e-9)
    u = f["u"].to_numpy()
    assert u[-1] > 2.0 and speed["multifidelity"] > 2.5  # it accelerates
    assert runs["multifidelity"].metrics["heading_rotation_deg"] > 90.0


def test_dominant_frequency_helper():
    t = np.arange(0, 20, 0.02)
    assert dominant_frequency(t, np.sin(2 * np.pi * 0.7 * t) + 0.3) == pytest.approx(0.7, abs=0.06)


def test_cli_writes_replayable_log(tmp_path):
    import uvsim
    from uvsim.cli import main
    from uvsim.logs import read_run
    from uvsim.sam.vehicle import load_sam

    out = tmp_path / "loop.csv"
    rc = main(["maneuver", "tight_loop", "--out", str(out), "--duration", "3", "--plots", str(tmp_path / "p")])
    assert rc == 0
    run = read_run(out)
    assert run.inputs.shape[1] == 7 and run.input_kind == "thrust"
    for col in ("rpm_1_act", "tv_pitch_act", "vbs_act", "lcg_act", "tcg_act"):
        assert col in run.data
    assert len(list((tmp_path / "p").glob("tight_loop_*.png"))) == 3
    res = uvsim.simulate_run(load_sam(), run)
    np.testing.assert_allclose(res.position, run.position, atol=1e-9)


def test_unknown_maneuver_is_an_error():
    from uvsim.errors import SimulationError

    with pytest.raises(SimulationError, match="unknown maneuver"):
        run_maneuver("barrel_roll")
    assert set(MANEUVERS) == {"tight_loop", "turbo_turn", "helix", "lcg_sweep", "accelerating_turn"}


@pytest.mark.slow
def test_benchmark_step_converges_and_reports():
    from uvsim.benchmarks.sam import DESCRIPTIONS, run

    out = run(quick=False)
    assert set(out) == set(DESCRIPTIONS)
    assert out["sam_dt50ms_position_error_m"] < 0.5     # dt = 0.05 s within 1 % of the ~50 m path (dt = 0.005 s ref)
    assert out["sam_realtime_factor"] > 0 and out["sam_realtime_factor_dt10ms"] > 0
