#!/usr/bin/env python3
"""Writes scenarios/paper/*.json: the paper's 12 experiments (method.md section 9).

{cylinder, slender box} x {translate, rotate} x {X, Y, Z} on the Shadow-like hand:
  stage 0 "grasp":      1 N per finger with the object frozen, 3 s timeout
  stage 1 "hold":       release, keep the pose for 2 s
  stage 2 "manipulate": 5 mm along the axis and back (translate), or 0 -> -0.2 rad
                        -> 0 about it (rotate), in 4 s; then 1 s of settling
with the bounds the reproduction must meet in "expect". The same 12 experiments on the
other 4-finger hands go to scenarios/allegro/allegro_<name>.json ("allegro_like",
plant::allegro_like_hand()) and scenarios/shadow_coupled/shadow_coupled_<name>.json
("shadow_like_coupled", plant::shadow_like_coupled_hand(): distal joints J1 = J2), with
the same bounds (scenario names are unique across scenarios/). The same experiments are
built in C++ by inhand::plant::paper_scenario(); tests/scenarios checks that the files
parse to exactly that. Re-run after changing this script; the JSON files are committed.

    scripts/gen_paper_scenarios.py [--check]   (--check: exit 1 if a file differs)
"""
import json
import pathlib
import re
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
OUT = ROOT / "scenarios" / "paper"
# (directory, file/scenario name prefix, "hand" value)
HANDS = [(OUT, "", "shadow_like"),
         (ROOT / "scenarios" / "allegro", "allegro_", "allegro_like"),
         (ROOT / "scenarios" / "shadow_coupled", "shadow_coupled_", "shadow_like_coupled")]

OBJECTS = {
    # paper_cylinder(): radius 20 mm, length 100 mm, 50 g; axis along world X.
    "cylinder": {"shape": "cylinder", "radius": 0.02, "length": 0.1, "mass": 0.05},
    # paper_slender_box(): 20 x 20 x 80 mm, 50 g; long axis along world X.
    "box": {"shape": "box", "size": [0.02, 0.02, 0.08], "mass": 0.05},
}
AXES = {"x": [1, 0, 0], "y": [0, 1, 0], "z": [0, 0, 1]}


def scenario(obj, task, axis, prefix="", hand="shadow_like"):
    name = f"{prefix}{obj}_{task}_{axis}"
    if task == "translate":
        segment = {"kind": "reciprocate", "motion": "move", "axis": AXES[axis],
                   "amount": 0.005, "duration": 4.0, "cycles": 1}
        what = f"5 mm along {axis.upper()} and back"
        bounds = {"max_rms_position_error": 5e-4, "max_final_position_error": 2e-4}
    else:
        segment = {"kind": "reciprocate", "motion": "rotate", "axis": AXES[axis],
                   "amount": -0.2, "duration": 4.0, "cycles": 1}
        what = f"0 -> -0.2 rad -> 0 about {axis.upper()}"
        bounds = {"max_rms_orientation_error": 0.01, "max_final_orientation_error": 0.005}
    bounds["max_relative_force_error"] = 0.5
    return name, {
        "name": name,
        "description": f"Paper experiment: {'slender box' if obj == 'box' else 'cylinder'}, "
                       f"{what} (grasp 1 N frozen, release and hold 2 s, manipulate 4 s, settle 1 s)",
        "hand": hand,
        "object": OBJECTS[obj],
        "stages": [
            {"name": "grasp", "kind": "grasp", "duration": 3.0},
            {"name": "hold", "kind": "hold", "release": True, "duration": 2.0},
            {"name": "manipulate", "kind": "manipulate", "segments": [segment], "settle": 1.0},
        ],
        "expect": {
            "all": {"must_not_drop": True, "max_contact_losses": 0},
            "grasp": {"must_complete": True},
            "hold": {"max_settle_time": 1.0},
            "manipulate": bounds,
        },
    }


def to_json(obj):
    """Indented JSON with arrays of numbers kept on one line."""
    text = json.dumps(obj, indent=2)
    flat = re.sub(r"\[\s+([^\[\]{}\"]*?)\s+\]",
                  lambda m: "[" + ", ".join(x.strip() for x in m.group(1).split(",")) + "]", text)
    return flat + "\n"


def main():
    check = "--check" in sys.argv[1:]
    differ = []
    for out, prefix, hand in HANDS:
        out.mkdir(parents=True, exist_ok=True)
        for obj in OBJECTS:
            for task in ("translate", "rotate"):
                for axis in AXES:
                    differ += write(out, scenario(obj, task, axis, prefix, hand), check)
    if differ:
        print("out of date (run scripts/gen_paper_scenarios.py):\n  " + "\n  ".join(differ))
        return 1
    return 0


def write(out, named, check):
    """Writes (or with check compares) one file; returns the paths that differ."""
    name, s = named
    path = out / f"{name}.json"
    text = to_json(s)
    if check:
        return [] if path.exists() and path.read_text() == text else [str(path)]
    path.write_text(text)
    return []


if __name__ == "__main__":
    sys.exit(main())
