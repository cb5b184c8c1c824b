"""The vehicle file's schema: every section and field in one place.

Each section of a vehicle file is a :class:`Section` of :class:`Field` s (kind, required or
default, sign, bounds, unit, meaning) with its physical rules beside it (named functions of
:mod:`uvsim.vehicle_rules`).
:func:`validate_vehicle_dict` walks it (unknown keys with a did-you-mean, missing fields,
types, finiteness, signs, bounds, then the rules) into the plain dict :mod:`uvsim.vehicle`
builds the vehicle from; plug-in sections are left to the builders their fields name.
:func:`schema_markdown` renders the tables of docs/model.md (tested equal).
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from uvsim.constants import G
from uvsim.errors import VehicleError
from uvsim.schema import finite_number, require_mapping, unknown_key_message
from uvsim.vehicle_rules import (  # noqa: F401 (the rules and their constants, re-exported)
    ADDED_MASS_NAMES, INERTIA_NAMES, SENSOR_NAMES, MAX_SENSOR_OFFSET, POINT_REACH, MAX_LATENCY, IMU_BIAS_SPECS,
    BUOYANCY_RATIO, Context, buoyancy_near_weight, inertia_positive_definite,
    inertia_triangle_inequality, added_mass_matrix, added_mass_symmetric, added_mass_diagonal_non_negative,
    added_mass_positive_semidefinite, imu_bias_only_on_imu, sensor_position_given, sensor_on_the_vehicle,
    check_current_speed, check_water_density, water_density, gravity_in_m_per_s2, current_a_current,
    noise_signal_names, vehicle_parameter_names, mass_matrix_positive_definite, points_on_the_vehicle, cb_not_below_cg)

FILE_STEM = "<file stem>"  # the default of ``name``: the file's name without ``.yaml``
_ABSENT = object()  # a field neither given nor defaulted: left out of the validated dict


@dataclass(frozen=True)
class Field:
    """One key of a section: what it holds, the checks of its value and its docs."""

    kind: str  # number, vec3, matrix6 (6x6), text (any value, as text), any (free-form), section, list, plugin
    required: bool = False  # absent is an error ("missing")
    default: Any = None  # the value when absent (a number's also when null)
    nullable: bool = False  # null is the same as absent (else a null number is "missing")
    positive: bool = False  # a number's sign and exclusive upper bound
    nonneg: bool = False
    upper: float | None = None
    unit: str = ""  # for the messages and the docs table
    meaning: str = ""
    section: "Section | None" = None  # kind section: what it holds
    builder: str = ""  # kind plugin (list: of each entry): what checks and builds it (uvsim.vehicle calls it)
    expected: str = ""  # message for a wrong type, with {where}, {file}, {key}
    example: str = ""  # a section read by uvsim.schema.require_mapping with this example (null: {})
    parse: Callable | None = None  # parse(value, where) replacing the kind's checks (its own messages)
    rules: tuple = ()  # rule(values so far, ctx) run as soon as this field is read
    after_build: bool = False  # checked by validate_built_vehicle (needs the built vehicle)


@dataclass(frozen=True)
class Section:
    """A mapping of the vehicle file: its fields and the rules that check them together."""

    fields: Mapping[str, Field]  # in the order the messages list them
    key_rules: tuple = ()  # rule(raw, ctx) on the section as read, right after the key check
    rules: tuple = ()  # rule(values, ctx) on the validated values
    built_rules: tuple = ()  # rule(values, ctx) once the vehicle is built (ctx.vehicle)
    hint: str = ""  # appended to the unknown-key message
    noun: str = "key"  # "unknown sensor 'x'"
    each: Field | None = None  # an open section: every key's field ...
    keys: Callable | None = None  # ... and keys(ctx), the accepted keys
    doc_path: str = ""  # its name in the docs when several fields share it
    each_doc: str = "<parameter>"  # an open section's key in the docs

    @property
    def shown(self) -> Mapping[str, Field]:  # the fields as the docs list them
        return {self.each_doc: self.each} if self.each else self.fields


def _join(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key


# ----------------------------------------------------------------------------- field parsers
def check_latency(value, where: str) -> float:
    """A sensor latency in s, validated (0 <= latency <= :data:`MAX_LATENCY`)."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise VehicleError(f"{where}: expected a latency in s (a number), got {value!r}") from None
    if not (np.isfinite(x) and 0.0 <= x <= MAX_LATENCY):
        raise VehicleError(f"{where} = {value!r}: expected 0 <= latency <= {MAX_LATENCY:g} s "
                           "(how late the sensors read relative to the logged inputs)")
    return x


def _number(fld: Field, raw: Mapping, key: str, ctx: Context):
    value, where = raw.get(key), ctx.at(key)
    if value is None:
        if fld.default is not None:
            return float(fld.default)
        if fld.required or (key in raw and not fld.nullable):
            raise VehicleError(f"{where}: missing (expected a number)")
        return _ABSENT
    v = finite_number(value, where, error=VehicleError, bool_ok=False)
    if (fld.positive and v <= 0) or (fld.nonneg and v < 0):
        raise VehicleError(f"{where}: expected a {'positive' if fld.positive else 'non-negative'} number, got {v}")
    if fld.upper is not None and v >= fld.upper:
        raise VehicleError(f"{where} = {v:g}: expected {fld.unit}, {fld.meaning}")
    return v


def _array(fld: Field, raw: Mapping, key: str, ctx: Context):
    """``vec3`` (absent: the default; null is not) or ``matrix6`` (a copy), finite."""
    if key not in raw and fld.default is None:
        return _ABSENT
    val = raw.get(key, fld.default)
    vec = fld.kind == "vec3"
    got = f", got {val!r}" if vec else ""
    try:
        a = np.asarray(val, dtype=float) if vec else np.array(val, dtype=float)
    except (TypeError, ValueError):
        what = "3 numbers" if vec else "a finite 6x6 matrix of numbers"
        raise VehicleError(f"{ctx.at(key)}: expected {what}{got}") from None
    if a.shape != ((3,) if vec else (6, 6)) or not np.all(np.isfinite(a)):
        raise VehicleError(f"{ctx.at(key)}: expected {'3 finite numbers' if vec else 'a finite 6x6 matrix'}{got}")
    return a


def _text(fld: Field, raw: Mapping, key: str, ctx: Context):
    default = Path(ctx.file).stem if fld.default == FILE_STEM else fld.default
    return str(raw[key]) if key in raw else _ABSENT if default is None else default


def _expected(fld: Field, key: str, ctx: Context) -> VehicleError:
    return VehicleError(fld.expected.format(where=ctx.at(key), file=ctx.file, key=key))


def _any(fld: Field, raw: Mapping, key: str, ctx: Context):
    """As given (free-form; a plug-in for its builder, a required one must be a mapping)."""
    if fld.required and not isinstance(raw.get(key), dict):
        raise _expected(fld, key, ctx)
    return raw[key] if key in raw else _ABSENT


def _list(fld: Field, raw: Mapping, key: str, ctx: Context):
    value = raw.get(key) or []  # an empty value (null, {}, "") is an empty list, as ever
    if not isinstance(value, list):
        raise _expected(fld, key, ctx)
    return value


def _section(fld: Field, raw: Mapping, key: str, ctx: Context):
    value = raw.get(key)
    if value is None and (key not in raw or fld.nullable) and not fld.required:
        if fld.default is None:
            return _ABSENT
        value = fld.default
    if fld.example:
        value = require_mapping(value, ctx.at(key), error=VehicleError, example=fld.example)
    elif not isinstance(value, dict):
        raise _expected(fld, key, ctx)
    return _walk(fld.section, value, replace(ctx, path=_join(ctx.path, key), key=key))


_PARSERS = {"number": _number, "vec3": _array, "matrix6": _array, "text": _text, "any": _any,
            "plugin": _any, "list": _list, "section": _section}


def _parse(fld: Field, raw: Mapping, key: str, ctx: Context):
    if fld.parse is not None:
        return fld.parse(raw[key], ctx.at(key)) if key in raw else _ABSENT if fld.default is None else fld.default
    return _PARSERS[fld.kind](fld, raw, key, ctx)


# ----------------------------------------------------------------------------- the walker
def _walk(sec: Section, raw: Mapping, ctx: Context, *, only=None, rules=None) -> dict:
    """One section: keys, key rules, fields (declared order), rules -> {given keys in file order, defaults}."""
    allowed = list(sec.keys(ctx) if sec.keys else sec.fields)
    known = set(allowed)
    for key in raw:
        if key not in known:
            raise VehicleError(unknown_key_message(ctx.where, key, allowed, sec.hint, sec.noun))
    for rule in sec.key_rules:
        rule(raw, ctx)
    fields = {k: sec.each for k in raw} if sec.each else sec.fields
    parsed = ctx.root if not ctx.path and only is not None else {}
    for key, fld in fields.items():
        if only is None or only(fld):
            value = _parse(fld, raw, key, ctx)
            if value is not _ABSENT:
                parsed[key] = value
            for rule in fld.rules:
                rule(parsed, ctx)
    out = {**{k: parsed[k] for k in raw if k in parsed}, **parsed}
    for rule in sec.rules if rules is None else rules:
        rule(out, ctx)
    return out


def validate_vehicle_dict(d: Mapping, source: str) -> dict:
    """Validate a vehicle-file dictionary against :data:`VEHICLE` (all but the after-build part).

    Parameters
    ----------
    d : the file as read from YAML.
    source : its name, in every message.

    Returns
    -------
    dict
        The sections: numbers as floats, vectors and matrices as arrays, defaults filled in,
        plug-in sections as given.

    Raises
    ------
    VehicleError
        Naming the source, ``section.field`` and what was expected.
    """
    return _walk(VEHICLE, d, Context(source, "", "", {}), only=lambda f: not f.after_build)


def validate_built_vehicle(d: Mapping, source: str, vehicle) -> dict:
    """The checks that need the built vehicle: its ``uncertainty`` section and the built rules.

    Parameters
    ----------
    d, source : as for :func:`validate_vehicle_dict`.
    vehicle : the vehicle built from them (its ``parameters()`` and ``M``).

    Returns
    -------
    dict
        ``{"uncertainty": {parameter: sigma}}``.
    """
    ctx = Context(source, "", "", {}, vehicle)
    return _walk(VEHICLE, d, ctx, only=lambda f: f.after_build, rules=VEHICLE.built_rules)


# ----------------------------------------------------------------------------- a rule of the walk
def required_sections_given(raw: Mapping, ctx: Context) -> None:
    """The required sections (``rigid_body``, ``added_mass``, ``damping``) are mappings."""
    for key, fld in VEHICLE.fields.items():
        if fld.required and not isinstance(raw.get(key), dict):
            raise _expected(fld, key, ctx)



# ----------------------------------------------------------------------------- the schema
_SECTION = "{file}: '{key}' section missing or not a mapping"

ENVIRONMENT = Section({
    # uvsim.constants.G: standard gravity (CGPM 1901), the value every shipped file states
    "g": Field("number", default=G, positive=True, unit="m/s^2", meaning="gravitational acceleration",
               rules=(gravity_in_m_per_s2,)),
    # nominal fresh water: the loader's default since the first release (RHO_FRESH is 998 at 20 degC)
    "rho": Field("number", default=1000.0, positive=True, unit="kg/m^3", meaning="water density",
                 rules=(water_density,)),
    "current_ned": Field("vec3", default=(0.0, 0.0, 0.0), unit="m/s",
                         meaning="constant ocean current, NED (parameters current_n, current_e, current_d)"),
}, rules=(current_a_current,))

INERTIA = Section({
    **{k: Field("number", required=True, positive=True, unit="kg m^2", meaning=f"moment of inertia {k}")
       for k in INERTIA_NAMES[:3]},
    **{k: Field("number", default=0.0, unit="kg m^2", meaning=f"product of inertia {k} (I_b has -{k})")
       for k in INERTIA_NAMES[3:]},
}, rules=(inertia_positive_definite, inertia_triangle_inequality))

RIGID_BODY = Section({
    "mass": Field("number", required=True, positive=True, unit="kg", meaning="mass m"),
    "buoyancy": Field("number", required=True, nonneg=True, unit="N", meaning="buoyancy force B (a force, not a mass)",
                      rules=(buoyancy_near_weight,)),
    "r_g": Field("vec3", default=(0.0, 0.0, 0.0), unit="m", meaning="centre of gravity, body frame"),
    "r_b": Field("vec3", default=(0.0, 0.0, 0.0), unit="m", meaning="centre of buoyancy, body frame"),
    "inertia": Field("section", section=INERTIA, required=True, meaning="inertia tensor about the body origin",
                     expected="{where}: expected a mapping I_xx, I_yy, I_zz (and optional I_xy, I_xz, I_yz)"),
})

ADDED_MASS = Section({
    **{k: Field("number", nonneg=True, unit="kg" if i < 3 else "kg m^2",
                meaning=f"{dof} added mass, a positive magnitude (replaces matrix[{i}][{i}])")
       for i, (k, dof) in enumerate(zip(ADDED_MASS_NAMES, ("surge", "sway", "heave", "roll", "pitch", "yaw")))},
    "matrix": Field("matrix6", meaning="full symmetric M_A, positive convention (default zeros)"),
    "convention": Field("any", meaning="free text on the sign convention (not read)"),
}, rules=(added_mass_symmetric, added_mass_diagonal_non_negative, added_mass_positive_semidefinite))

SENSOR = Section({
    "position": Field("vec3", unit="m", meaning="where the sensor is, body frame"),
    "source": Field("any", meaning="where the position comes from (free text, not read)"),
    **{k: Field("number", nullable=True, positive=True, upper=top, unit=unit, meaning=what)
       for k, (unit, top, what) in IMU_BIAS_SPECS.items()},
}, key_rules=(imu_bias_only_on_imu, sensor_position_given), rules=(sensor_on_the_vehicle,),
    doc_path="sensors.<sensor>")

NOISE = Section({}, each=Field("number", positive=True, unit="the channel's",
                               meaning="1-sigma noise of a log channel or group (m, rad, m/s, rad/s, m/s^2), used "
                                       "instead of the level estimated from the logs"),
                keys=noise_signal_names, noun="signal", each_doc="<signal>",
                hint=" (a log channel such as 'yaw', 'depth', 'u', or a group such as 'attitude')")

SENSORS = Section({
    **{n: Field("section", section=SENSOR, meaning=what,
                expected="{where}: expected a mapping {{position: [x, y, z]}} (m, body frame; optional source)")
       for n, what in zip(SENSOR_NAMES, ("the IMU: accelerometer position, bias specs", "the pressure sensor "
                                          "(depth of its position)", "the DVL (velocity of its position)"))},
    "latency": Field("number", default=0.0, parse=check_latency, unit="s",
                     meaning=f"how late every sensor reads relative to the inputs, 0 to {MAX_LATENCY:g} s"),
    "noise": Field("section", section=NOISE, nullable=True, example="noise: {yaw: 0.02, depth: 0.005}",
                   meaning="declared noise levels by channel or group (docs/model.md, 'Sensor noise')"),
}, noun="sensor")

UNCERTAINTY = Section({}, each=Field("number", positive=True, unit="the parameter's",
                                     meaning="1-sigma of the file's value (a calibration's prior width)"),
                      keys=vehicle_parameter_names,
                      hint=" (a parameter name of this vehicle: uvsim.load_vehicle(...).parameters())")

VEHICLE = Section({
    "name": Field("text", default=FILE_STEM, meaning="the vehicle's name"),
    "description": Field("text", default="", meaning="one line on the vehicle"),
    "sources": Field("any", meaning="free-form citations (kept when the vehicle is saved)"),
    "meta": Field("any", meaning="free-form metadata, never read"),
    "environment": Field("section", section=ENVIRONMENT, default={}, nullable=True, meaning="the water",
                         example="{g: 9.81, rho: 1000.0, current_ned: [0, 0, 0]}"),
    "rigid_body": Field("section", section=RIGID_BODY, required=True, expected=_SECTION, meaning="mass properties"),
    "added_mass": Field("section", section=ADDED_MASS, required=True, expected=_SECTION, meaning="M_A"),
    "damping": Field("plugin", required=True, builder="uvsim.forces.make_term", expected=_SECTION,
                     meaning="damping model {type: diagonal, ...}, coefficients in the paper sign"),
    "thrusters": Field("plugin", builder="uvsim.forces.actuators.build_actuators",
                       meaning="thruster curve(s) and geometry or configuration matrix"),
    "effects": Field("list", builder="uvsim.forces.make_term", expected="{where}: expected a list",
                     meaning="extra force terms [{type: tether, ...}, ...]"),
    "sensors": Field("section", section=SENSORS, default={}, nullable=True,
                     meaning="sensor positions, latency and noise",
                     expected="{where}: expected a mapping such as {{pressure: {{position: [x, y, z]}}}}"),
    "uncertainty": Field("section", section=UNCERTAINTY, default={}, nullable=True, after_build=True,
                         example="uncertainty: {X_u: 2.0, N_rdot: 0.05}", meaning="1-sigma of named parameters"),
}, key_rules=(required_sections_given,), built_rules=(mass_matrix_positive_definite, points_on_the_vehicle, cb_not_below_cg),
    hint=" (free-form metadata goes under 'meta:')")


# ----------------------------------------------------------------------------- docs
_KINDS = {"number": "number", "vec3": "[x, y, z]", "matrix6": "6x6 numbers", "text": "text", "any": "free-form",
          "section": "mapping", "list": "list of plug-ins", "plugin": "plug-in"}


def _limits(fld: Field) -> str:
    if fld.parse or fld.kind in ("plugin", "list"):
        return f"checked by `{fld.parse.__name__ if fld.parse else fld.builder}`"
    return ", ".join(["> 0"] * fld.positive + [">= 0"] * fld.nonneg + ([f"< {fld.upper:g}"] if fld.upper else []))


def _presence(fld: Field) -> str:
    if fld.required or fld.default is None or fld.kind == "section":
        return "required" if fld.required else "optional"
    return f"default `{list(fld.default) if isinstance(fld.default, tuple) else fld.default!r}`"


def _blocks(sec: Section, path: str, seen: set) -> list[tuple[str, Section]]:
    """``(path, section)`` of ``sec`` and every section below it, each once, parents first."""
    kids = {}
    for key, fld in sec.shown.items():
        if fld.section is not None and id(fld.section) not in seen:
            seen.add(id(fld.section))
            kids[fld.section.doc_path or _join(path, key)] = fld.section
    return [(path, sec)] + [b for p, child in kids.items() for b in _blocks(child, p, seen)]


def _rule_rows(path: str, sec: Section) -> list[tuple]:
    rules = [(path, r) for r in (*sec.key_rules, *[sec.keys] * bool(sec.keys))]
    rules += [(_join(path, k), r) for k, f in sec.shown.items() for r in f.rules]
    return [(f"`{p or 'top level'}`", f"`{r.__name__}`", r.__doc__.strip().splitlines()[0].replace("``", "`"))
            for p, r in rules + [(path, r) for r in (*sec.rules, *sec.built_rules)]]


def _table(header: tuple, rows: list[tuple]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    return "\n".join(lines + ["| " + " | ".join(r) + " |" for r in rows])


def schema_markdown() -> str:
    """The schema as Markdown: the "Vehicle file fields" table, then the rules table.

    Returns
    -------
    str
        Two tables (fields: path, kind, presence, accepted values, unit, meaning; rules:
        section, rule function, what it checks), as docs/model.md holds them.
    """
    blocks = _blocks(VEHICLE, "", set())
    fields = _table(("field", "kind", "presence", "accepted values", "unit", "meaning"), [
        (f"`{_join(path, k)}`", _KINDS[f.kind], _presence(f), _limits(f), f.unit, f.meaning)
        for path, sec in blocks for k, f in sec.shown.items()])
    rules = _table(("section or field", "rule", "checks"), [r for path, sec in blocks for r in _rule_rows(path, sec)])
    return (f"{fields}\n\nRules (functions of `uvsim.vehicle_rules`; a field's run right after it, a "
            f"section's after all its fields, `M` once the vehicle is built):\n\n{rules}\n")
