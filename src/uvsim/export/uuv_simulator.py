"""UUV Simulator export: the ``fossen`` hydrodynamic model as a xacro macro.

UUV Simulator's ``HMFossen`` (uuv_gazebo_plugins ``HydrodynamicModel.cc``) reads
``<added_mass>`` (36 numbers, row-major, positive: ``M_A``), ``<linear_damping>`` (6 or 36
numbers) and ``<quadratic_damping>`` (6 numbers; only the diagonal is used) and applies
``tau = -D(nu) nu - M_A nu_dot - C_A(nu) nu`` with ``D = -D_lin - diag(D_quad) |nu|``, so
the damping coefficients are in the paper sign (negative) like uvsim's.  It flips
Gazebo's FLU velocities to FRD itself (``ToNEDConvention``: y and z negated), so these
matrices are written exactly as uvsim holds them (FRD); the centre of buoyancy and the
thruster joints, which Gazebo reads in the link frame, are converted to FLU.

Two macros are written: ``<name>_hydro_model`` (the ``<link>`` block the
UnderwaterObjectPlugin reads: volume, centre of buoyancy, Fossen matrices) and
``<name>_thrusters`` (one ``uuv_thruster_ros_plugin`` per thruster with a
``LinearInterp`` conversion whose input values are the ESC PWM and output values the
thrust in N: the vehicle's own thrust curve at its nominal voltage), plus
``<name>_inertial`` for the base link's URDF ``<inertial>``.
"""
from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np

from uvsim.errors import VehicleError
from uvsim.export.frames import S3, damping_matrices, frd_to_flu_vector, inertia_about_cg

XACRO_NS = "http://www.ros.org/wiki/xacro"


def _nums(a) -> str:
    return " ".join(repr(float(x)) for x in np.ravel(a))


def _sub(parent, tag, text=None, **attrib):
    e = ET.SubElement(parent, tag, attrib)
    if text is not None:
        e.text = text
    return e


def uuv_xacro(vehicle) -> tuple[str, list[str]]:
    """Xacro text for UUV Simulator and the warnings to print before writing it."""
    warnings = []
    DL, DQ = damping_matrices(vehicle)
    off = DQ - np.diag(np.diag(DQ))
    if np.any(off):
        raise VehicleError(f"{vehicle.source}: UUV Simulator's fossen model uses only the diagonal of the quadratic "
                           "damping; this vehicle has off-diagonal quadratic terms")
    if vehicle.effects:
        warnings.append(f"effects {[e.kind for e in vehicle.effects]} have no UUV Simulator counterpart; not exported")
    ET.register_namespace("xacro", XACRO_NS)
    robot = ET.Element("robot")
    robot.append(ET.Comment(" exported by uvsim export: Fossen matrices in FRD (UUV Simulator flips Gazebo's FLU "
                            "velocities itself); centre of buoyancy and thruster joints in the FLU link frame "))
    x = f"{{{XACRO_NS}}}"
    hm = _sub(robot, x + "macro", name=f"{vehicle.name}_hydro_model", params="namespace")
    link = _sub(hm, "link", name="${namespace}/base_link")
    _sub(link, "neutrally_buoyant", "0")
    V = vehicle.buoyancy / (vehicle.rho * vehicle.g)
    link.append(ET.Comment(f" volume = B / (rho g) with rho = {vehicle.rho:g} kg/m^3, g = {vehicle.g:g} m/s^2; "
                           "UUV Simulator multiplies it by its world's fluid density "))
    _sub(link, "volume", repr(float(V)))
    _sub(link, "center_of_buoyancy", _nums(frd_to_flu_vector(vehicle.r_b)))
    model = _sub(link, "hydrodynamic_model")
    _sub(model, "type", "fossen")
    _sub(model, "added_mass", _nums(vehicle.added_mass_matrix))
    _sub(model, "linear_damping", _nums(DL))
    _sub(model, "quadratic_damping", _nums(np.diag(DQ)))

    im = _sub(robot, x + "macro", name=f"{vehicle.name}_inertial", params="")
    inertial = _sub(im, "inertial")
    _sub(inertial, "mass", value=repr(float(vehicle.mass)))
    _sub(inertial, "origin", xyz=_nums(frd_to_flu_vector(vehicle.r_g)), rpy="0 0 0")
    J = S3 @ inertia_about_cg(vehicle) @ S3
    _sub(inertial, "inertia", **{k: repr(float(J[i, j])) for k, (i, j) in
                                 zip(("ixx", "ixy", "ixz", "iyy", "iyz", "izz"),
                                     ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)))})
    _thrusters(robot, x, vehicle, warnings)
    ET.indent(robot, "  ")
    text = ET.tostring(robot, encoding="unicode")
    return '<?xml version="1.0"?>\n' + text + "\n", warnings


def _thrusters(robot, x, vehicle, warnings) -> None:
    act = vehicle.actuators
    units = (vehicle.raw.get("thrusters") or {}).get("units")
    if act.matrix is None or not units or not act.curves:
        if act.matrix is not None:
            warnings.append("thrusters without positions or thrust curves: thruster macro omitted")
        return
    tm = _sub(robot, x + "macro", name=f"{vehicle.name}_thrusters", params="namespace")
    for i, unit in enumerate(units):
        curve = act.curves[i]
        pwm = np.asarray(getattr(curve, "table_pwm", [curve.pwm_min, curve.pwm_max]), float)
        thrust = curve.thrust(pwm)
        d = frd_to_flu_vector(np.asarray(unit["direction"], float) / np.linalg.norm(unit["direction"]))
        lk = _sub(tm, "link", name=f"${{namespace}}/thruster_{i}")
        li = _sub(lk, "inertial")
        _sub(li, "mass", value="0.001")  # nominal: the thruster's mass is part of base_link
        _sub(li, "inertia", ixx="1e-06", ixy="0", ixz="0", iyy="1e-06", iyz="0", izz="1e-06")
        j = _sub(tm, "joint", name=f"${{namespace}}/thruster_{i}_joint", type="continuous")
        _sub(j, "origin", xyz=_nums(frd_to_flu_vector(unit["position"])), rpy="0 0 0")
        _sub(j, "axis", xyz=_nums(d))
        _sub(j, "parent", link="${namespace}/base_link")
        _sub(j, "child", link=f"${{namespace}}/thruster_{i}")
        gz = _sub(tm, "gazebo")
        pl = _sub(gz, "plugin", name=f"${{namespace}}_{i}_thruster_model", filename="libuuv_thruster_ros_plugin.so")
        pl.append(ET.Comment(f" {act.names[i]}: input = ESC PWM (us), output = thrust (N), curve {curve.name!r} "))
        _sub(pl, "linkName", f"${{namespace}}/thruster_{i}")
        _sub(pl, "jointName", f"${{namespace}}/thruster_{i}_joint")
        _sub(pl, "thrusterID", str(i))
        _sub(pl, "gain", "1")
        _sub(pl, "clampMin", repr(float(pwm.min())))
        _sub(pl, "clampMax", repr(float(pwm.max())))
        _sub(pl, "thrustMin", repr(float(thrust.min())))
        _sub(pl, "thrustMax", repr(float(thrust.max())))
        _sub(_sub(pl, "dynamics"), "type", "ZeroOrder")
        conv = _sub(pl, "conversion")
        _sub(conv, "type", "LinearInterp")
        _sub(conv, "inputValues", _nums(pwm))
        _sub(conv, "outputValues", _nums(thrust))


def parse_uuv_xacro(text: str) -> dict:
    """Numbers of a xacro written by :func:`uuv_xacro`, in the file's frames and signs."""
    root = ET.fromstring(text)
    ns = {"xacro": XACRO_NS}
    hm = next(m for m in root.findall("xacro:macro", ns) if m.get("name").endswith("_hydro_model"))
    link = hm.find("link")
    model = link.find("hydrodynamic_model")

    def arr(tag, node=model):
        return np.array([float(v) for v in node.find(tag).text.split()])

    lin = arr("linear_damping")
    out = {"type": model.find("type").text, "added_mass": arr("added_mass").reshape(6, 6),
           "linear": lin.reshape(6, 6) if lin.size == 36 else np.diag(lin),
           "quadratic": np.diag(arr("quadratic_damping")), "volume": float(link.find("volume").text),
           "cb": arr("center_of_buoyancy", link)}
    im = next(m for m in root.findall("xacro:macro", ns) if m.get("name").endswith("_inertial"))
    ine = im.find("inertial")
    g = ine.find("inertia").attrib
    J = np.array([[g["ixx"], g["ixy"], g["ixz"]], [g["ixy"], g["iyy"], g["iyz"]], [g["ixz"], g["iyz"], g["izz"]]], float)
    out.update(mass=float(ine.find("mass").get("value")), inertia_cg=J,
               cg=np.array([float(v) for v in ine.find("origin").get("xyz").split()]))
    tm = [m for m in root.findall("xacro:macro", ns) if m.get("name").endswith("_thrusters")]
    out["thrusters"] = []
    if tm:
        for j, gz in zip(tm[0].findall("joint"), tm[0].findall("gazebo")):
            conv = gz.find("plugin/conversion")
            out["thrusters"].append({
                "position": np.array([float(v) for v in j.find("origin").get("xyz").split()]),
                "axis": np.array([float(v) for v in j.find("axis").get("xyz").split()]),
                "pwm": arr("inputValues", conv), "thrust": arr("outputValues", conv)})
    return out
