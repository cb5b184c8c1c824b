"""Sub-commands of the ``uvsim`` CLI (one module each, see :mod:`uvsim.cli`)."""

from uvsim.errors import UvsimError


def parse_pairs(text: str | None, option: str) -> dict[str, float] | None:
    """``"a=1,b=2.5"`` -> ``{"a": 1.0, "b": 2.5}`` for options such as ``--weights`` and
    ``--noise``; None for an empty option.  Errors name the option and the bad item."""
    if not text:
        return None
    out = {}
    for item in text.split(","):
        if "=" not in item:
            raise UvsimError(f"{option}: expected NAME=VALUE pairs separated by commas, got {item!r}")
        k, v = item.split("=", 1)
        try:
            out[k.strip()] = float(v)
        except ValueError:
            raise UvsimError(f"{option}: value of {k.strip()!r} is not a number: {v!r}") from None
    return out


def lag_option(text: str):
    """``--attitude-lag``: "auto" or a time constant in s."""
    if text == "auto":
        return "auto"
    try:
        return float(text)
    except ValueError:
        raise UvsimError(f"--attitude-lag: expected 'auto' or a time constant in s, got {text!r}") from None
