#!/usr/bin/env python3
"""Variants of scenario files: each file rerun over object masses, friction coefficients and
(analytic plant) gravity directions, with inhand_scenario --check; a pass count per file and
the failing variants with their first violated expectation.

  variants.py --scenario-bin PATH [--masses 0.02,0.1,...] [--frictions 0.4,0.7,1.0]
              [--gravity +X,-X,+Y,-Y,+Z,-Z] [--jobs N] [--out DIR] [--check] FILE...

A variant changes object.mass [kg], plant.friction (the Coulomb coefficient of the analytic
plant; on MuJoCo the object's and fingertips' sliding friction) and, on the analytic plant
only, plant.gravity (9.81 m/s^2 along the named world axis; a MuJoCo world keeps its model's
gravity). Everything else, the expectations included, is the file's. The controller is told
the plant's gravity as for any scenario file (docs/scenarios.md). Written to DIR (default
out/variants): files/<variant>.json, summaries/<variant>.json and variants.csv (one row per
variant: name, source file, mass, friction, gravity, passed, first violation). Exit status: 0;
with --check, 1 when a variant fails; 2 on a usage error, a file that cannot be read, or a
variant that inhand_scenario refuses or cannot run (its status 2 or 3, printed as ERROR).
"""
import argparse
import concurrent.futures
import csv
import json
import os
import subprocess
import sys

AXES = {"X": 0, "Y": 1, "Z": 2}
G = 9.81


def strip_comments(text):
    """The scenario format's // and /* */ comments removed, string literals kept whole."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            out.append(text[i:j + 1])
            i = j + 1
        elif text.startswith("//", i):
            while i < n and text[i] != "\n":
                i += 1
        elif text.startswith("/*", i):
            end = text.find("*/", i + 2)
            i = n if end < 0 else end + 2
        else:
            out.append(c)
            i += 1
    return "".join(out)


def numbers(text, name):
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{name}: comma-separated numbers, got '{text}'")
    if not values:
        raise argparse.ArgumentTypeError(f"{name}: at least one value")
    return values


def gravity_list(text):
    dirs = [d.strip() for d in text.split(",") if d.strip()]
    for d in dirs:
        if len(d) != 2 or d[0] not in "+-" or d[1] not in AXES:
            raise argparse.ArgumentTypeError(f"--gravity: +X, -X, +Y, -Y, +Z or -Z, got '{d}'")
    return dirs


def variants_of(path, spec, masses, frictions, gravities):
    base = os.path.splitext(os.path.basename(path))[0]
    mujoco = spec.get("plant", {}).get("engine") == "mujoco"
    for m in masses:
        for mu in frictions:
            for g in ([None] if mujoco else gravities):
                v = json.loads(json.dumps(spec))
                v.setdefault("object", {})["mass"] = m
                plant = v.setdefault("plant", {})
                plant["friction"] = mu
                name = f"{base}_m{m:g}_mu{mu:g}"
                if g is not None:
                    vec = [0.0, 0.0, 0.0]
                    vec[AXES[g[1]]] = G if g[0] == "+" else -G
                    plant["gravity"] = vec
                    name += f"_g{g}"
                v["name"] = name
                yield name, m, mu, g or "model", v


def run(binary, files_dir, summaries_dir, item):
    name, source, m, mu, g, spec = item
    file = os.path.join(files_dir, name + ".json")
    with open(file, "w") as f:
        json.dump(spec, f, indent=1)
    r = subprocess.run([binary, file, "--check", "--quiet", "--summary",
                        os.path.join(summaries_dir, name + ".json")],
                       capture_output=True, text=True)
    text = r.stdout + r.stderr
    violations = [l[4:] for l in text.splitlines() if l.startswith("  - ")]
    if r.returncode == 0:
        first = ""
    elif violations:
        first = violations[0]
    else:
        first = (text.strip().splitlines() or [""])[-1]
    return name, source, m, mu, g, r.returncode, first


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("files", nargs="+", help="scenario files (JSON)")
    p.add_argument("--scenario-bin", required=True, help="the inhand_scenario executable")
    p.add_argument("--masses", default="0.02,0.1,0.2,0.3,0.4",
                   type=lambda t: numbers(t, "--masses"), help="kg (default 0.02,0.1,0.2,0.3,0.4)")
    p.add_argument("--frictions", default="0.4,0.7,1.0",
                   type=lambda t: numbers(t, "--frictions"), help="(default 0.4,0.7,1.0)")
    p.add_argument("--gravity", default="+X,-X,+Y,-Y,+Z,-Z", type=gravity_list,
                   help="world axes gravity pulls along, analytic plant (default all six; a list that "
                        "starts with - is given as --gravity=-Z,+Y)")
    p.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    p.add_argument("--out", default="out/variants")
    p.add_argument("--check", action="store_true", help="exit 1 when a variant fails")
    a = p.parse_args()
    files_dir = os.path.join(a.out, "files")
    summaries_dir = os.path.join(a.out, "summaries")
    os.makedirs(files_dir, exist_ok=True)
    os.makedirs(summaries_dir, exist_ok=True)
    items = []
    for path in a.files:
        try:
            with open(path) as f:
                spec = json.loads(strip_comments(f.read()))
        except (OSError, ValueError) as e:
            print(f"{path}: {e}", file=sys.stderr)
            return 2
        for name, m, mu, g, v in variants_of(path, spec, a.masses, a.frictions, a.gravity):
            items.append((name, path, m, mu, g, v))
    with concurrent.futures.ThreadPoolExecutor(max(1, a.jobs)) as pool:
        results = list(pool.map(lambda it: run(a.scenario_bin, files_dir, summaries_dir, it), items))
    with open(os.path.join(a.out, "variants.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["variant", "file", "mass_kg", "friction", "gravity", "passed", "violation"])
        for name, source, m, mu, g, rc, first in results:
            w.writerow([name, source, m, mu, g, int(rc == 0), first])
    print("| file | variants | passed |")
    print("|---|---:|---:|")
    for path in a.files:
        mine = [r for r in results if r[1] == path]
        print(f"| {path} | {len(mine)} | {sum(r[5] == 0 for r in mine)} |")
    failed = [r for r in results if r[5] != 0]
    for name, _, _, _, _, rc, first in failed:
        print(f"FAIL {name}: {first}" if rc == 1 else f"ERROR {name} (status {rc}): {first}")
    print(f"{len(results) - len(failed)} of {len(results)} variants pass ({a.out}/variants.csv)")
    if any(r[5] not in (0, 1) for r in results):
        return 2
    return 1 if a.check and failed else 0


if __name__ == "__main__":
    sys.exit(main())
