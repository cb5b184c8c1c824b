"""Importers: real vehicle logs -> uvsim datasets (docs/import_export.md).

* :mod:`uvsim.importers.ardusub`: ArduSub DataFlash (.BIN) and MAVLink telemetry
  (.tlog) logs, read with pymavlink (optional extra ``uvsim[ardusub]``);
* :mod:`uvsim.importers.rosbag`: ROS 1 / ROS 2 bags, read with rosbags (optional
  extra ``uvsim[ros]``), driven by a topic map;
* :mod:`uvsim.importers.timeline`: message streams -> rows on one time base, with a
  report of every alignment, hold and gap;
* :mod:`uvsim.importers.segments`: cutting a log into runs (armed intervals or a
  segments YAML) and writing the dataset with its import record.

Malformed input raises :class:`uvsim.errors.LogFormatError` naming the file, the
message type or topic and the field.
"""
from __future__ import annotations

import importlib

from uvsim.errors import LogFormatError


def require(module: str, extra: str, purpose: str):
    """Import an optional dependency or raise a LogFormatError naming the extra."""
    try:
        return importlib.import_module(module)
    except ImportError:
        raise LogFormatError(
            f"{purpose} needs the optional package {module.split('.')[0]} "
            f"(pip install 'uvsim[{extra}]')"
        ) from None
