"""UUV Simulator export: the ``fossen`` hydrodynamic model as a xacro macro.

UUV Simulator's ``HMFossen`` (uuv_gazebo_plugins ``HydrodynamicModel.cc``) reads
``<added_mass>`` (36 numbers, row-major, positive: ``M_A``), ``<linear_damping>`` (6 or 36
numbers) and ``<quadratic_damping>`` (6 numbers; only the diagonal is used) and applies
``tau = -D(nu) nu - M_A nu_dot - C_A(nu) nu`` with ``D = -D_lin - diag(D_quad) |nu|``, so
the damping coefficients are in the paper sign (negative) like uvsim's.  It flips
Gazebo's FLU velocities to FRD itself (``ToNEDConvention``: y and z negated), so these
matrices are written exactly as uvsim holds them (FRD); the centre of buoyancy and the
thruster joints, which Gazebo reads in the link frame, are converted to FLU.

Four macros are written: ``<name>_hydro_model`` (the ``<link>`` block the
UnderwaterObjectPlugin reads: volume, centre of buoyancy, Fossen matrices),
``<name>_underwater_plugin`` (the plugin block around it with ``<fluid_density>`` = rho:
the plugin's own default is 1028, ``UnderwaterObjectPlugin.cc:81-84``), ``<name>_thrusters``
(one ``uuv_thruster_ros_plugin`` per thruster with a ``LinearInterp`` conversion whose input
values are the ESC PWM and output values the thrust in N: the vehicle's own thrust curve at
its nominal voltage, :mod:`uvsim.export.thrust_tables`) and ``<name>_inertial`` for the base
link's URDF ``<inertial>`` (with the thruster links' :data:`~uvsim.export.frames.THRUSTER_LINK_MASS`
taken out, :func:`~uvsim.export.frames.base_link_inertial`).

Gazebo classic's ODE link applies ``AddRelativeForce`` at the link's centre of mass and
reads ``AddForceAtRelativePosition``'s position from the centre of mass, not from the link
origin (gazebosim/gazebo-classic ``gazebo/physics/ode/ODELink.cc``, commit 6e3233b5d108:
``dBodyAddRelForce``, ``dBodyAddForceAtRelPos``; the ODE body sits at the CoG,
``UpdateMass``).  UUV Simulator applies its hydrodynamic wrench with the first
(``HydrodynamicModel.cc:428-429``) and buoyancy with the second (``BuoyantObject.cc:186``).
So ``<center_of_buoyancy>`` is written relative to the base link's centre of mass, which
puts buoyancy where uvsim has it; the hydrodynamic wrench acting at the centre of mass
instead of the body origin cannot be undone by the coefficients and is warned when the
centre of gravity is off the origin (the replay check models it).
"""
from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np

from uvsim.errors import VehicleError
from uvsim.export.frames import (S3, THRUSTER_LINK_INERTIA, THRUSTER_LINK_MASS, base_link_inertial,
                                 damping_matrices, frd_to_flu_vector)

XACRO_NS = "http://www.ros.org/wiki/xacro"


def _nums(a) -> str:
    return " ".join(repr(float(x)) for x in np.ravel(a))


def _sub(parent, tag, text=None, **attrib):
    e = ET.SubElement(parent, tag, attrib)
    if text is not None:
        e.text = text
    return e


def uuv_xacro(vehicle, *, force: bool = False) -> tuple[str, list[str]]:
    """Xacro text for UUV Simulator and the warnings to print before writing it.

    What the fossen model cannot hold is refused with :class:`uvsim.errors.VehicleError`:
    off-diagonal quadratic damping always, a centre of gravity off the body origin unless
    ``force`` (then it is a warning; module docstring)."""
    warnings = []
    DL, DQ = damping_matrices(vehicle)
    off = DQ - np.diag(np.diag(DQ))
    if np.any(off):
        raise VehicleError(f"{vehicle.source}: UUV Simulator's fossen model uses only the diagonal of the quadratic "
                           "damping (HydrodynamicModel.cc:479-485); this vehicle has off-diagonal quadratic terms")
    if vehicle.effects:
        warnings.append(f"effects {[e.kind for e in vehicle.effects]} have no UUV Simulator counterpart; not exported")
    if np.any(np.asarray(vehicle.current_ned, float) != 0):
        n, e, d = (float(x) for x in vehicle.current_ned)
        warnings.append(f"UUV Simulator takes the current from its world, not from the vehicle: publish ({e:g}, {n:g}, "
                        f"{-d:g}) m/s (ENU) on the plugin's flow_velocity_topic (UnderwaterObjectPlugin.cc:69-78, "
                        "244-252)")
    units = _units(vehicle, warnings)
    mb, cb, Jb = base_link_inertial(vehicle, [u["position"] for u in units])
    if np.any(np.asarray(vehicle.r_g, float) != 0):
        why = (f"the centre of gravity ({', '.join(f'{x:g}' for x in vehicle.r_g)}) m is off the body origin, and UUV "
               "Simulator applies its hydrodynamic wrench at the centre of mass (HydrodynamicModel.cc:428-429 "
               "AddRelativeForce; Gazebo classic ODELink.cc dBodyAddRelForce, commit 6e3233b5d108) where uvsim's acts "
               "about the origin: no coefficient can undo the lever arm (uvsim export --check measures it)")
        if not force:
            raise VehicleError(f"{vehicle.source}: not exported to uuv-simulator: {why}. Write it anyway with --force")
        warnings.append(why + "; written anyway (--force)")
    ET.register_namespace("xacro", XACRO_NS)
    robot = ET.Element("robot")
    robot.append(ET.Comment(" exported by uvsim export: Fossen matrices in FRD (UUV Simulator flips Gazebo's FLU "
                            "velocities itself); centre of buoyancy and thruster joints in the FLU link frame "))
    x = f"{{{XACRO_NS}}}"
    hm = _sub(robot, x + "macro", name=f"{vehicle.name}_hydro_model", params="namespace")
    link = _sub(hm, "link", name="${namespace}/base_link")
    _sub(link, "neutrally_buoyant", "0")
    V = vehicle.buoyancy / (vehicle.rho * vehicle.g)
    link.append(ET.Comment(f" volume = B / (rho g) with rho = {vehicle.rho:g} kg/m^3 (the plugin's fluid_density, "
                           f"{vehicle.name}_underwater_plugin) and g = {vehicle.g:g} m/s^2 (the world's gravity) "))
    _sub(link, "volume", repr(float(V)))
    link.append(ET.Comment(" centre of buoyancy measured from the base link's centre of mass, where Gazebo classic's "
                           "ODE applies AddForceAtRelativePosition (uvsim.export.uuv_simulator) "))
    _sub(link, "center_of_buoyancy", _nums(frd_to_flu_vector(np.asarray(vehicle.r_b, float) - cb)))
    model = _sub(link, "hydrodynamic_model")
    _sub(model, "type", "fossen")
    _sub(model, "added_mass", _nums(vehicle.added_mass_matrix))
    _sub(model, "linear_damping", _nums(DL))
    _sub(model, "quadratic_damping", _nums(np.diag(DQ)))

    up = _sub(robot, x + "macro", name=f"{vehicle.name}_underwater_plugin", params="namespace")
    pl = _sub(_sub(up, "gazebo"), "plugin", name="uuv_plugin", filename="libuuv_underwater_object_ros_plugin.so")
    _sub(pl, "fluid_density", repr(float(vehicle.rho)))
    _sub(pl, "flow_velocity_topic", "hydrodynamics/current_velocity")
    _sub(pl, "debug", "0")
    _sub(pl, x + f"{vehicle.name}_hydro_model", namespace="${namespace}")

    im = _sub(robot, x + "macro", name=f"{vehicle.name}_inertial", params="")
    inertial = _sub(im, "inertial")
    _sub(inertial, "mass", value=repr(float(mb)))
    _sub(inertial, "origin", xyz=_nums(frd_to_flu_vector(cb)), rpy="0 0 0")
    J = S3 @ Jb @ S3
    _sub(inertial, "inertia", **{k: repr(float(J[i, j])) for k, (i, j) in
                                 zip(("ixx", "ixy", "ixz", "iyy", "iyz", "izz"),
                                     ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)))})
    _thrusters(robot, x, vehicle, units, warnings)
    ET.indent(robot, "  ")
    text = ET.tostring(robot, encoding="unicode")
    return '<?xml version="1.0"?>\n' + text + "\n", warnings


def _units(vehicle, warnings) -> list[dict]:
    act = vehicle.actuators
    units = (vehicle.raw.get("thrusters") or {}).get("units")
    if act.matrix is None or not units or not act.curves:
        if act.matrix is not None:
            warnings.append("thrusters without positions or thrust curves: thruster macro omitted (drive the model "
                            "with generalized forces)")
        return []
    return list(units)


def _thrusters(robot, x, vehicle, units, warnings) -> None:
    from uvsim.export.thrust_tables import curve_knots, table_warnings

    if not units:
        return
    act = vehicle.actuators
    warnings.extend(table_warnings(vehicle, "UUV Simulator"))
    tm = _sub(robot, x + "macro", name=f"{vehicle.name}_thrusters", params="namespace")
    for i, unit in enumerate(units):
        curve = act.curves[i]
        pwm, thrust = curve_knots(curve)
        d = frd_to_flu_vector(np.asarray(unit["direction"], float) / np.linalg.norm(unit["direction"]))
        lk = _sub(tm, "link", name=f"${{namespace}}/thruster_{i}")
        li = _sub(lk, "inertial")
        _sub(li, "mass", value=repr(THRUSTER_LINK_MASS))  # taken out of base_link (frames.base_link_inertial)
        _sub(li, "inertia", ixx=repr(THRUSTER_LINK_INERTIA), ixy="0", ixz="0", iyy=repr(THRUSTER_LINK_INERTIA),
             iyz="0", izz=repr(THRUSTER_LINK_INERTIA))
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
    """Numbers of a xacro written by :func:`uuv_xacro`, in the file's frames and signs.

    ``cb`` is the file's ``<center_of_buoyancy>``: measured from the base link's centre of
    mass ``cg`` (module docstring); ``fluid_density`` from ``<name>_underwater_plugin``
    (1028, the plugin's default, when that macro is absent); ``thrusters``: position, axis,
    link ``mass`` and ``inertia``, the PWM clamp and thrust limits and the ``LinearInterp``
    table (``pwm``, ``thrust``)."""
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
           "cb": arr("center_of_buoyancy", link), "fluid_density": 1028.0}
    for m in root.findall("xacro:macro", ns):
        fd = m.find("gazebo/plugin/fluid_density")
        if m.get("name").endswith("_underwater_plugin") and fd is not None:
            out["fluid_density"] = float(fd.text)
    im = next(m for m in root.findall("xacro:macro", ns) if m.get("name").endswith("_inertial"))
    ine = im.find("inertial")
    out.update(mass=float(ine.find("mass").get("value")), inertia_cg=_inertia(ine.find("inertia").attrib),
               cg=np.array([float(v) for v in ine.find("origin").get("xyz").split()]))
    tm = [m for m in root.findall("xacro:macro", ns) if m.get("name").endswith("_thrusters")]
    out["thrusters"] = []
    if tm:
        links = tm[0].findall("link")
        for lk, j, gz in zip(links, tm[0].findall("joint"), tm[0].findall("gazebo")):
            pl = gz.find("plugin")
            conv = pl.find("conversion")
            li = lk.find("inertial")
            out["thrusters"].append({
                "position": np.array([float(v) for v in j.find("origin").get("xyz").split()]),
                "axis": np.array([float(v) for v in j.find("axis").get("xyz").split()]),
                "mass": float(li.find("mass").get("value")), "inertia": _inertia(li.find("inertia").attrib),
                "clamp": (float(pl.find("clampMin").text), float(pl.find("clampMax").text)),
                "limits": (float(pl.find("thrustMin").text), float(pl.find("thrustMax").text)),
                "pwm": arr("inputValues", conv), "thrust": arr("outputValues", conv)})
    return out


def _inertia(g: dict) -> np.ndarray:
    """3x3 tensor of a URDF ``<inertia>`` element's attributes."""
    return np.array([[g["ixx"], g["ixy"], g["ixz"]], [g["ixy"], g["iyy"], g["iyz"]], [g["ixz"], g["iyz"], g["izz"]]],
                    float)
