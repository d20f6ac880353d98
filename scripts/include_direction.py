#!/usr/bin/env python3
"""The solver's physics stands apart from its input format: no physics file reaches the scenario
reader, directly or through the headers it includes.

Physics: the headers that hold the model, materials, contact, the stress pass and the integrator
(PHYSICS_HEADERS) and every source under solver/src/{kernels,contact,time,materials}. Input
layer: scenario.hpp, scenario_keys.hpp, model_build.hpp (the reader and what turns a scenario into
a model) and the TOML library. scenario.hpp includes the physics headers for their parameter
structs, never the reverse. Prints each physics file that reaches the input layer with the chain
of includes, and exits 1 if there is one.
  scripts/include_direction.py [ROOT]
"""
import re
import sys
from pathlib import Path

PHYSICS_HEADERS = [
    "contact.hpp",
    "contact_settings.hpp",
    "curve.hpp",
    "energy.hpp",
    "explicit.hpp",
    "internal_force.hpp",
    "loading.hpp",
    "mass_scaling.hpp",
    "material.hpp",
    "model.hpp",
    "rigid.hpp",
    "run_settings.hpp",
    "schedule.hpp",
]
PHYSICS_FOLDERS = ["kernels", "contact", "time", "materials"]
INPUT_LAYER = {"scenario.hpp", "scenario_keys.hpp", "model_build.hpp"}
INCLUDE = re.compile(r'^\s*#\s*include\s*[<"]([^">]+)[">]', re.M)


def main():
    root = Path(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).resolve().parent.parent)
    solver = root / "solver"
    public = solver / "include" / "tactus" / "solver"
    files = sorted(public.glob("*.hpp")) + sorted((solver / "src").rglob("*.[hc]pp"))

    def resolve(including, name):
        """The solver file an include names, or None (another library's or the system's)."""
        if name.startswith("tactus/solver/"):
            return public / name[len("tactus/solver/") :]
        local = (including.parent / name).resolve()
        return local if local.exists() and solver in local.parents else None

    includes = {}
    for f in files:
        includes[f] = [(name, resolve(f, name)) for name in INCLUDE.findall(f.read_text())]

    def chain_to_input(start):
        """The include chain from start to the input layer, or None."""
        seen, stack = {start}, [(start, [start.name])]
        while stack:
            f, path = stack.pop()
            for name, target in includes.get(f, []):
                if "toml" in name or (target is not None and target.name in INPUT_LAYER):
                    return path + [name]
                if target is not None and target not in seen and target in includes:
                    seen.add(target)
                    stack.append((target, path + [target.name]))
        return None

    physics = [public / h for h in PHYSICS_HEADERS]
    missing = [p.name for p in physics if not p.exists()]
    physics += [f for f in files if f.parent.name in PHYSICS_FOLDERS]
    bad = 0
    for f in physics:
        if not f.exists():
            continue
        chain = chain_to_input(f)
        if chain:
            bad += 1
            print(f"{f.relative_to(root)} reaches the input layer: {' -> '.join(chain)}")
    if missing:
        print("physics headers listed here but not in the tree (rename them here too): " + ", ".join(missing))
        bad += 1
    print(f"{len(physics)} physics files checked, {bad} reaching the input layer")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
