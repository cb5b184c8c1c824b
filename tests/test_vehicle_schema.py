"""The vehicle file's declarative schema (uvsim.vehicle_schema): every field kind's errors name
the file and ``section.field``, every rule fires with its message, unknown keys get a
did-you-mean, the schema covers exactly the keys the loader accepts, and the table in
docs/model.md is the one the schema renders."""
from __future__ import annotations

import ast
import copy
import importlib
import re
from pathlib import Path

import numpy as np
import pytest

from uvsim.files import safe_load
import uvsim.vehicle_schema as vs
import uvsim.vehicle_rules as vehicle_rules
from uvsim.errors import VehicleError
from uvsim.forces import make_term
from uvsim.forces.actuators import build_actuators
from uvsim.vehicle import inertia_tensor, vehicle_from_dict, vehicle_path

ROOT = Path(__file__).resolve().parents[1]
DELETE = object()
FILE = "veh.yaml"


def full_vehicle() -> dict:
    """bluerov2_heavy with every optional field of the schema given (a valid file)."""
    d = safe_load(vehicle_path("bluerov2_heavy").read_text())
    d["meta"] = {"operator": "tank team", "anything": [1, 2]}
    d["rigid_body"]["inertia"].update({"I_xy": 0.01, "I_xz": -0.02, "I_yz": 0.005})
    MA = np.diag([15.6, 17.0, 40.0, 0.3, 0.3, 0.3])
    MA[0, 4] = MA[4, 0] = 0.05
    d["added_mass"].update({"matrix": MA.tolist(), "convention": "positive magnitudes"})
    d["sensors"] = {"imu": {"position": [0.0, 0.0, 0.02], "source": "CAD", "gyro_bias_sd": 0.01, "acc_bias_sd": 0.2},
                    "pressure": {"position": [-0.15, 0.0, 0.0], "source": "measured"},
                    "dvl": {"position": [0.1, 0.0, 0.1]}, "latency": 0.03,
                    "noise": {"yaw": 0.02, "depth": 0.005, "rates": 0.003}}
    d["uncertainty"] = {"X_u": 2.0, "m": 0.1}
    return d


def mutate(d: dict, path: str, value) -> dict:
    """A copy of ``d`` with ``path`` (dotted) set to ``value`` (or deleted)."""
    d = copy.deepcopy(d)
    *parents, key = path.split(".")
    target = d
    for p in parents:
        target = target[p]
    if value is DELETE:
        target.pop(key, None)
    else:
        target[key] = copy.deepcopy(value)
    return d


def error_of(d: dict) -> str:
    with pytest.raises(VehicleError) as exc:
        vehicle_from_dict(d, source=FILE)
    return str(exc.value)


def schema_paths(sec: vs.Section = vs.VEHICLE, path: str = "") -> dict:
    """Every field of the schema by its docs path (``sensors.<sensor>.position``, ...)."""
    out = {}
    for key, fld in sec.shown.items():
        p = f"{path}.{key}" if path else key
        out[p] = fld
        if fld.section is not None:
            out.update(schema_paths(fld.section, fld.section.doc_path or p))
    return out


def docs_path(path: str) -> str:
    """A concrete path as the schema's docs name it."""
    path = re.sub(r"^sensors\.(imu|pressure|dvl)\.", "sensors.<sensor>.", path)
    path = re.sub(r"^sensors\.noise\..+", "sensors.noise.<signal>", path)
    return re.sub(r"^uncertainty\..+", "uncertainty.<parameter>", path)


# ----------------------------------------------------------------------------- field kinds
#: path, value, fragment of the message: each kind's missing / type / finite / sign / bound errors.
FIELD_ERRORS = [
    ("environment", [1, 2], "environment: expected a mapping such as {g: 9.81"),
    ("environment.g", "abc", "environment.g: expected a number, got 'abc'"),
    ("environment.g", True, "environment.g: expected a number, got True"),
    ("environment.g", float("nan"), "environment.g: expected a finite number, got nan"),
    ("environment.g", -9.81, "environment.g: expected a positive number, got -9.81"),
    ("environment.rho", 0, "environment.rho: expected a positive number, got 0.0"),
    ("environment.rho", float("inf"), "environment.rho: expected a finite number"),
    ("environment.current_ned", [0, 0], "environment.current_ned: expected 3 finite numbers, got [0, 0]"),
    ("environment.current_ned", "north", "environment.current_ned: expected 3 numbers, got 'north'"),
    ("environment.current_ned", None, "environment.current_ned: expected 3 finite numbers, got None"),
    ("rigid_body", DELETE, "veh.yaml: 'rigid_body' section missing or not a mapping"),
    ("rigid_body", [1], "veh.yaml: 'rigid_body' section missing or not a mapping"),
    ("rigid_body.mass", DELETE, "rigid_body.mass: missing (expected a number)"),
    ("rigid_body.mass", None, "rigid_body.mass: missing (expected a number)"),
    ("rigid_body.mass", "13 kg", "rigid_body.mass: expected a number, got '13 kg'"),
    ("rigid_body.mass", float("inf"), "rigid_body.mass: expected a finite number, got inf"),
    ("rigid_body.mass", -13.17, "rigid_body.mass: expected a positive number, got -13.17"),
    ("rigid_body.buoyancy", DELETE, "rigid_body.buoyancy: missing (expected a number)"),
    ("rigid_body.buoyancy", -1, "rigid_body.buoyancy: expected a non-negative number, got -1.0"),
    ("rigid_body.r_g", [0, "x", 0], "rigid_body.r_g: expected 3 numbers"),
    ("rigid_body.r_b", [0, 0, float("nan")], "rigid_body.r_b: expected 3 finite numbers"),
    ("rigid_body.inertia", DELETE, "rigid_body.inertia: expected a mapping I_xx, I_yy, I_zz"),
    ("rigid_body.inertia", [0.3, 0.3, 0.4], "rigid_body.inertia: expected a mapping I_xx, I_yy, I_zz"),
    ("rigid_body.inertia.I_xx", DELETE, "rigid_body.inertia.I_xx: missing (expected a number)"),
    ("rigid_body.inertia.I_yy", 0, "rigid_body.inertia.I_yy: expected a positive number, got 0.0"),
    ("rigid_body.inertia.I_zz", "big", "rigid_body.inertia.I_zz: expected a number"),
    ("rigid_body.inertia.I_xy", "x", "rigid_body.inertia.I_xy: expected a number, got 'x'"),
    ("rigid_body.inertia.I_xz", float("nan"), "rigid_body.inertia.I_xz: expected a finite number"),
    ("rigid_body.inertia.I_yz", False, "rigid_body.inertia.I_yz: expected a number, got False"),
    ("added_mass", "none", "veh.yaml: 'added_mass' section missing or not a mapping"),
    ("added_mass.X_udot", -3.0, "added_mass.X_udot: expected a non-negative number, got -3.0"),
    ("added_mass.Y_vdot", None, "added_mass.Y_vdot: missing (expected a number)"),
    ("added_mass.Z_wdot", "heavy", "added_mass.Z_wdot: expected a number"),
    ("added_mass.K_pdot", float("-inf"), "added_mass.K_pdot: expected a finite number"),
    ("added_mass.M_qdot", -0.1, "added_mass.M_qdot: expected a non-negative number"),
    ("added_mass.N_rdot", True, "added_mass.N_rdot: expected a number, got True"),
    ("added_mass.matrix", np.eye(5).tolist(), "added_mass.matrix: expected a finite 6x6 matrix"),
    ("added_mass.matrix", [[1, "x"], [2, 3]], "added_mass.matrix: expected a finite 6x6 matrix of numbers"),
    ("added_mass.matrix", np.full((6, 6), np.nan).tolist(), "added_mass.matrix: expected a finite 6x6 matrix"),
    ("damping", DELETE, "veh.yaml: 'damping' section missing or not a mapping"),
    ("damping", [1, 2], "veh.yaml: 'damping' section missing or not a mapping"),
    ("effects", {"type": "tether"}, "veh.yaml: effects: expected a list"),
    ("thrusters", [1, 2], "thrusters: expected a mapping with 'units'"),  # delegated to build_actuators
    ("sensors", [1], "sensors: expected a mapping such as {pressure: {position: [x, y, z]}}"),
    ("sensors.imu", [0, 0, 0], "sensors.imu: expected a mapping {position: [x, y, z]}"),
    ("sensors.pressure", None, "sensors.pressure: expected a mapping {position: [x, y, z]}"),
    ("sensors.dvl", 3, "sensors.dvl: expected a mapping {position: [x, y, z]}"),
    ("sensors.dvl.position", [0, 0], "sensors.dvl.position: expected 3 finite numbers, got [0, 0]"),
    ("sensors.imu.position", "aft", "sensors.imu.position: expected 3 numbers, got 'aft'"),
    ("sensors.imu.gyro_bias_sd", 0, "sensors.imu.gyro_bias_sd: expected a positive number, got 0.0"),
    ("sensors.imu.gyro_bias_sd", 1.0, "sensors.imu.gyro_bias_sd = 1: expected rad/s, a MEMS gyro's in-run bias"),
    ("sensors.imu.acc_bias_sd", "x", "sensors.imu.acc_bias_sd: expected a number, got 'x'"),
    ("sensors.imu.acc_bias_sd", 2.5, "sensors.imu.acc_bias_sd = 2.5: expected m/s^2, a MEMS accelerometer's"),
    ("sensors.latency", 0.6, "sensors.latency = 0.6: expected 0 <= latency <= 0.5 s"),
    ("sensors.latency", -0.01, "sensors.latency = -0.01: expected 0 <= latency <= 0.5 s"),
    ("sensors.latency", "30 ms", "sensors.latency: expected a latency in s (a number), got '30 ms'"),
    ("sensors.noise", [0.02], "sensors.noise: expected a mapping such as noise: {yaw: 0.02, depth: 0.005}"),
    ("sensors.noise.yaw", 0, "sensors.noise.yaw: expected a positive number, got 0.0"),
    ("sensors.noise.depth", -0.005, "sensors.noise.depth: expected a positive number, got -0.005"),
    ("sensors.noise.yaw", float("nan"), "sensors.noise.yaw: expected a finite number, got nan"),
    ("sensors.noise.u", float("inf"), "sensors.noise.u: expected a finite number, got inf"),
    ("sensors.noise.yaw", "1 deg", "sensors.noise.yaw: expected a number, got '1 deg'"),
    ("sensors.noise.yaw", True, "sensors.noise.yaw: expected a number, got True"),
    ("sensors.noise.attitude", None, "sensors.noise.attitude: missing (expected a number)"),
    ("uncertainty", [1.0], "uncertainty: expected a mapping such as uncertainty: {X_u: 2.0"),
    ("uncertainty.X_u", -2.0, "uncertainty.X_u: expected a positive number, got -2.0"),
    ("uncertainty.m", None, "uncertainty.m: missing (expected a number)"),
]
#: Free-form and text fields: any value is accepted (text is read with str()).
ACCEPTS_ANYTHING = [("name", 123), ("description", None), ("sources", [1, {"a": 2}]), ("meta", "x"),
                    ("added_mass.convention", 5), ("sensors.pressure.source", {"by": "hand"})]


@pytest.mark.parametrize("path, value, fragment", FIELD_ERRORS, ids=[f"{p}={v!r}"[:60] for p, v, _ in FIELD_ERRORS])
def test_each_field_error_names_file_field_and_expectation(path, value, fragment):
    msg = error_of(mutate(full_vehicle(), path, value))
    assert msg.startswith(f"{FILE}: ") and path.split(".")[-1] in msg and fragment in msg, msg


@pytest.mark.parametrize("path, value", ACCEPTS_ANYTHING)
def test_free_form_and_text_fields_accept_anything(path, value):
    v = vehicle_from_dict(mutate(full_vehicle(), path, value), source=FILE)
    if path in ("name", "description"):
        assert getattr(v, path) == str(value)


def test_every_checked_field_has_an_error_case_and_free_fields_a_case():
    """A field added to the schema without a test here fails."""
    tested = {docs_path(p) for p, _, _ in FIELD_ERRORS} | {docs_path(p) for p, _ in ACCEPTS_ANYTHING}
    assert set(schema_paths()) - tested == set()
    kinds = {docs_path(p): schema_paths()[docs_path(p)].kind for p, _ in ACCEPTS_ANYTHING}
    assert set(kinds.values()) <= {"text", "any"}


def test_defaults_fill_an_empty_optional_section_and_nulls():
    d = mutate(mutate(full_vehicle(), "environment", DELETE), "name", DELETE)
    d["rigid_body"]["inertia"]["I_xy"] = None
    d["sensors"]["imu"]["gyro_bias_sd"] = None
    s = vs.validate_vehicle_dict(d, "some/dir/myrov.yaml")
    assert s["name"] == "myrov" and s["environment"]["g"] == 9.81 and s["environment"]["rho"] == 1000.0
    assert s["environment"]["current_ned"].tolist() == [0.0, 0.0, 0.0]
    assert s["rigid_body"]["inertia"]["I_xy"] == 0.0 and "gyro_bias_sd" not in s["sensors"]["imu"]
    assert vs.validate_vehicle_dict(mutate(d, "sensors", None), FILE)["sensors"] == {"latency": 0.0}


def test_the_validated_structure_holds_every_field_of_a_full_file():
    """Every field of the schema is accepted: a full file's validated structure has them all."""
    d = full_vehicle()
    s = vs.validate_vehicle_dict(d, FILE)

    def flat(x, path=""):
        for k, v in x.items():
            p = f"{path}.{k}" if path else k
            yield docs_path(p)
            if isinstance(v, dict) and schema_paths().get(docs_path(p), vs.Field("any")).kind == "section":
                yield from flat(v, p)

    built = vs.validate_built_vehicle(d, FILE, vehicle_from_dict(d, source=FILE))  # the after-build fields
    got = set(flat(s)) | set(flat(built))
    assert set(schema_paths()) == {docs_path(p) for p in got}
    assert isinstance(s["rigid_body"]["mass"], float) and s["rigid_body"]["r_g"].shape == (3,)
    assert list(s["sensors"]) == list(d["sensors"])  # file order kept (Vehicle.sensors, to_dict)


# ----------------------------------------------------------------------------- rules
#: rule name -> (a mutation of the full vehicle, fragment of its message)
RULE_CASES = {
    "required_sections_given": (lambda d: mutate(mutate(d, "environment", [1]), "damping", DELETE),
                                "veh.yaml: 'damping' section missing or not a mapping"),
    "buoyancy_near_weight": (lambda d: mutate(d, "rigid_body.buoyancy", 13.5),
                             "rigid_body.buoyancy = 13.5 N is 0.10 times the weight m g = 129.2 N"),
    "inertia_positive_definite": (lambda d: mutate(d, "rigid_body.inertia.I_xy", 1.0),
                                  "rigid_body.inertia: the inertia tensor is not positive definite"),
    "inertia_triangle_inequality": (lambda d: mutate(d, "rigid_body.inertia.I_zz", 4.26),
                                    "rigid_body.inertia: principal moments"),
    "added_mass_symmetric": (lambda d: mutate(d, "added_mass.matrix", (np.eye(6) + np.triu(np.ones((6, 6)), 1)).tolist()),
                             "added_mass.matrix: must be symmetric"),
    "added_mass_diagonal_non_negative": (
        lambda d: mutate(mutate(d, "added_mass.K_pdot", DELETE), "added_mass.matrix", np.diag([1, 1, 1, -1, 1, 1.0]).tolist()),
        "added_mass: diagonal added mass must be given as positive magnitudes"),
    "imu_bias_only_on_imu": (lambda d: mutate(d, "sensors.pressure.gyro_bias_sd", 0.01),
                             "sensors.pressure.gyro_bias_sd: only the imu has a gyro and an accelerometer"),
    "sensor_position_given": (lambda d: mutate(d, "sensors.dvl", {"source": "manual"}),
                              "sensors.dvl.position: missing (expected [x, y, z], m, body frame)"),
    "sensor_on_the_vehicle": (lambda d: mutate(d, "sensors.imu.position", [0, 0, 11]),
                              "sensors.imu.position [0.0, 0.0, 11.0] is more than 10 m from the body origin"),
    "current_a_current": (lambda d: mutate(d, "environment.current_ned", [0, 12, 0]),
                          "environment.current_ned [0.0, 12.0, 0.0]: 12 m/s is faster than any current"),
    "points_on_the_vehicle": (lambda d: mutate(d, "rigid_body.r_b", [0, 0, -20]),
                              "rigid_body.r_b [0.0, 0.0, -20.0] is 20 m from the body origin"),
    "noise_signal_names": (lambda d: mutate(d, "sensors.noise.yawn", 0.02),
                           "sensors.noise: unknown signal 'yawn' (did you mean 'yaw'?); expected x, y, z, depth, "
                           "roll, pitch, yaw, u, v, w, p, q, r, acc_x, acc_y, acc_z, position, attitude, velocity"),
    "vehicle_parameter_names": (lambda d: mutate(d, "uncertainty.X_uq", 1.0),
                                "uncertainty: unknown key 'X_uq' (did you mean"),
    "cb_not_below_cg": (lambda d: mutate(d, "rigid_body.r_b", [0, 0, 0.024]),
                        "rigid_body.r_b: the centre of buoyancy (z_b = 0.024 m) lies 0.024 m below the centre of gravity"),
    # the inertia is about the body origin: a CG 0.5 m below it leaves too little about the CG
    "mass_matrix_positive_definite": (lambda d: mutate(d, "rigid_body.r_g", [0, 0, 0.5]),
                                      "veh.yaml: M = M_RB + M_A is not positive definite"),
    "added_mass_positive_semidefinite": (
        lambda d: mutate(d, "added_mass", {"matrix": (np.eye(6) + 60 * (np.ones((6, 6)) - np.eye(6))).tolist()}),
        "added_mass: M_A is not positive semi-definite"),
    "water_density": (lambda d: mutate(d, "environment.rho", 1.025),
                      "environment.rho: 1.025 kg/m^3 is not a water density; expected 900..1250 kg/m^3"),
    "gravity_in_m_per_s2": (lambda d: mutate(d, "environment.g", 32.17),
                            "environment.g = 32.17: expected m/s^2 within 0.1..25"),
}


def all_rules(sec: vs.Section = vs.VEHICLE, seen=None) -> set:
    seen = set() if seen is None else seen
    out = {r.__name__ for r in (*sec.key_rules, *sec.rules, *sec.built_rules)} | ({sec.keys.__name__} if sec.keys else set())
    for fld in sec.shown.values():
        out |= {r.__name__ for r in fld.rules}
        if fld.section is not None and id(fld.section) not in seen:
            seen.add(id(fld.section))
            out |= all_rules(fld.section, seen)
    return out


def test_every_rule_of_the_schema_has_a_case():
    assert all_rules() == set(RULE_CASES)


@pytest.mark.parametrize("rule", sorted(RULE_CASES))
def test_each_rule_fires_with_its_message(rule):
    make, fragment = RULE_CASES[rule]
    msg = error_of(make(full_vehicle()))
    assert msg.startswith(f"{FILE}: ") and fragment in msg, msg


def test_the_imu_may_state_only_its_bias_specs():
    d = mutate(full_vehicle(), "sensors.imu", {"gyro_bias_sd": 0.02})
    v = vehicle_from_dict(d, source=FILE)
    assert "imu" not in v.sensors and v.gyro_bias_sd == 0.02 and v.acc_bias_sd is None
    assert "sensors.imu.position: missing" in error_of(mutate(d, "sensors.imu", {"source": "x"}))


def test_declared_noise_is_read_saved_and_loaded_again(tmp_path):
    """``sensors.noise`` reaches the vehicle (Vehicle.sensor_noise), a save writes it and a load
    reads it back unchanged; without it the vehicle declares nothing."""
    from uvsim.vehicle import load_vehicle, save_vehicle

    v = vehicle_from_dict(full_vehicle(), source=FILE)
    assert v.sensor_noise == {"yaw": 0.02, "depth": 0.005, "rates": 0.003}
    back = load_vehicle(save_vehicle(v, tmp_path / "v.yaml"))
    assert back.sensor_noise == v.sensor_noise and back.to_dict()["sensors"]["noise"] == v.sensor_noise
    assert back.with_parameters({"X_u": -5.0}).sensor_noise == v.sensor_noise  # a fit's vehicle keeps it
    assert vehicle_from_dict(mutate(full_vehicle(), "sensors.noise", None), source=FILE).sensor_noise == {}
    assert "noise" not in vehicle_from_dict(mutate(full_vehicle(), "sensors.noise", DELETE),
                                            source=FILE).to_dict()["sensors"]


def test_noise_signals_are_the_measurement_groups():
    from uvsim.signals import GROUPS

    assert vehicle_rules.NOISE_SIGNALS == {g: tuple(c) for g, c in GROUPS.items()}


def test_principal_moments_use_the_vehicles_inertia_tensor():
    i = {"I_xx": 0.3, "I_yy": 0.4, "I_zz": 0.5, "I_xy": 0.05, "I_xz": -0.02, "I_yz": 0.01}
    np.testing.assert_allclose(vehicle_rules._principal_moments(i), np.linalg.eigvalsh(inertia_tensor(*i.values())), rtol=1e-15)


# ----------------------------------------------------------------------------- keys
UNKNOWN_KEYS = [("", "descripton", "'description'"), ("environment", "curent_ned", "'current_ned'"),
                ("rigid_body", "rb", "'r_b'"), ("rigid_body.inertia", "I_xzz", "'I_zz' or 'I_xz'"),
                ("added_mass", "X_udt", "'X_udot'"), ("sensors", "presure", "'pressure'"),
                ("sensors.imu", "positon", "'position'"), ("uncertainty", "X_uuu", "'X_uu'")]


@pytest.mark.parametrize("section, key, suggestion", UNKNOWN_KEYS)
def test_unknown_keys_get_a_did_you_mean(section, key, suggestion):
    msg = error_of(mutate(full_vehicle(), f"{section}.{key}" if section else key, 1.0))
    where = f"{FILE}: {section}" if section else FILE
    noun = "sensor" if section == "sensors" else "key"
    assert msg.startswith(f"{where}: unknown {noun} '{key}' (did you mean {suggestion}?); expected "), msg


def test_every_section_rejects_a_key_absent_from_the_schema_and_lists_its_keys():
    sections = {p for p, f in schema_paths().items() if f.kind == "section"} - {"uncertainty", "sensors.noise"}
    for path in sorted(sections | {""}):
        concrete = path.replace("<sensor>", "dvl")
        msg = error_of(mutate(full_vehicle(), f"{concrete}.zz_unheard_of" if concrete else "zz_unheard_of", 1))
        sec = schema_paths()[path].section if path else vs.VEHICLE
        assert "'zz_unheard_of'" in msg and msg.endswith(", ".join(sec.fields) + (sec.hint or "")), msg


def test_key_tuples_are_the_schemas_and_unchanged():
    import uvsim.vehicle as v

    assert v.VEHICLE_KEYS == ("name", "description", "sources", "meta", "environment", "rigid_body", "added_mass",
                              "damping", "thrusters", "effects", "sensors", "uncertainty")
    assert v.ENVIRONMENT_KEYS == ("g", "rho", "current_ned")
    assert v.RIGID_BODY_KEYS == ("mass", "buoyancy", "r_g", "r_b", "inertia")
    assert v.SENSOR_KEYS == ("position", "source", "gyro_bias_sd", "acc_bias_sd")
    assert v.SENSOR_NAMES == ("imu", "pressure", "dvl") and v.MAX_LATENCY == 0.5 and v.MAX_SENSOR_OFFSET == 10.0
    assert v.check_latency is vs.check_latency and v.IMU_BIAS_SPECS is vs.IMU_BIAS_SPECS


# ----------------------------------------------------------------------------- structure and docs
def test_plugin_fields_name_the_builders_the_loader_calls():
    builders = {f.builder for f in schema_paths().values() if f.kind in ("plugin", "list")}
    assert builders == {"uvsim.forces.make_term", "uvsim.forces.actuators.build_actuators"}
    for name, fn in (("uvsim.forces.make_term", make_term), ("uvsim.forces.actuators.build_actuators", build_actuators)):
        module, attr = name.rsplit(".", 1)
        assert getattr(importlib.import_module(module), attr) is fn


def _uvsim_imports(name: str) -> set:
    tree = ast.parse((ROOT / "src" / "uvsim" / name).read_text())
    modules = {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
    modules |= {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
    return {m for m in modules if m.startswith("uvsim")}


def test_the_schema_module_imports_downhill():
    # (uvsim.rigid_body: the inertia tensor's formula, Fossen eq. 3.34; it imports no uvsim module)
    low = {"uvsim.errors", "uvsim.schema", "uvsim.constants", "uvsim.rigid_body"}
    assert _uvsim_imports("vehicle_rules.py") <= low
    assert _uvsim_imports("vehicle_schema.py") <= low | {"uvsim.vehicle_rules"}
    rb = ast.parse((ROOT / "src" / "uvsim" / "rigid_body.py").read_text())
    assert not any(isinstance(n, (ast.Import, ast.ImportFrom)) and "uvsim" in ast.dump(n) for n in ast.walk(rb))


def test_docs_table_is_the_one_the_schema_renders():
    text = (ROOT / "docs" / "model.md").read_text()
    m = re.search(r"<!-- vehicle-schema:begin[^>]*-->\n(.*?)<!-- vehicle-schema:end -->", text, re.S)
    assert m, "docs/model.md lost its vehicle-schema markers"
    assert m.group(1) == vs.schema_markdown(), "regenerate the table with uvsim.vehicle_schema.schema_markdown()"
    assert "## Vehicle file fields" in text
    for path in schema_paths():
        assert f"| `{path}` |" in m.group(1)
