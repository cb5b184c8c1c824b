"""Regenerate the shipped dataset src/uvsim/data/datasets/bluerov2_two_effects/.

A BlueROV2 Heavy tank dataset with two effects the shipped vehicle files do not declare:
an umbilical (an elastic tether attached on the frame, pulling towards an anchor) and a
slow horizontal current, written by the independent truth model of ``uvsim.scenarios``
(not by the simulator that diagnoses it).  The base coefficients are those of seed 000
Table 5 (``perturbation=0``), so the vehicle file beside the manifest is right apart from
the two effects and the example needs no ``--retune``.  It is the two-effect example of
``uvsim diagnose`` (docs/diagnose.md); ``truth.yaml`` beside the manifest records the
truth.  Deterministic (seed 2027).

    python examples/make_two_effect_dataset.py [OUT_DIR]   # default ./bluerov2_two_effects; the shipped copy: src/uvsim/data/datasets/bluerov2_two_effects
"""
import sys
from pathlib import Path

from uvsim.scenarios import generate, sample_scenario

out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("bluerov2_two_effects")  # never into the installed package
spec = sample_scenario(2027, profile="diagnose", n_runs=18, duration=[10, 12], rate_hz=25.0, input_kind="force",
                       perturbation=0.0,
                       effects=[{"type": "tether", "variant": "3d", "magnitude": 0.5},
                                {"type": "current", "variant": "horizontal", "magnitude": 0.04}])
path = generate(spec, out)
print(f"wrote {path}")
