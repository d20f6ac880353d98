#!/usr/bin/env python3
# The report of a mesh study (bench/hand_block_mesh_study.sh, bench/ball_block_study.sh): for
# meshes solved into WORK/NAME/out (and WORK/NAME/out_K, K = 1 .. N-1, for an ensemble), contact
# force, area and 25 mm^2 peak pressure at each output side by side with their differences, where
# each mesh's peak sits, the 25 mm^2 average at the last mesh's highest sites on every mesh, force
# and area averaged over +-0.25 ms, the contact impulse between outputs, and the ensemble statistics.
#   mesh_study_report.py BENCH_DIR WORK N NAME...
import json
import sys

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, sys.argv[1])
from history_kit import centred_mean, read_columns, time_integral  # noqa: E402 (after the path it lives on)

w, ensemble, names = sys.argv[2], int(sys.argv[3]), sys.argv[4:]
runs = {n: json.load(open(f"{w}/{n}/out/run.json")) for n in names}
# Each history read once (the 0.49x run's is ~150 MB): time, normal force, area.
histories = {n: read_columns(f"{w}/{n}/out/history.csv", "contact_normal_force", "contact_area") for n in names}


def impulse(n):
    t, force, _ = histories[n]
    return time_integral(t, force)


for n, j in runs.items():
    print(
        f"{n}: {j['tets']} tets, {j['contact']['pairs'][0]['slave_nodes']} skin nodes, {j['steps']} steps, {j['wall_time_s']:.0f} s, "
        f"contact impulse {impulse(n):.3f} N s"
    )


def rel(x, y):
    return f"{100 * (y / x - 1):+.1f} %" if x else "-"


for a_name, b_name in zip(names, names[1:]):
    d, f = runs[a_name], runs[b_name]
    print(f"\n{a_name} / {b_name}:")
    print("| t (ms) | force (N) | diff | windowed force (N) | diff | area (mm^2) | diff | windowed area (mm^2) | diff | 25 mm^2 peak (MPa) | diff |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for a, b in zip(d["contact"]["at_outputs"], f["contact"]["at_outputs"]):
        cells = [f"{a['time'] * 1e3:.0f}"]
        for key, scale, digits in (
            ("normal_force", 1, 0),
            ("windowed_normal_force", 1, 0),
            ("area", 1e6, 0),
            ("windowed_area", 1e6, 0),
            ("averaged_peak_pressure", 1e-6, 2),
        ):
            cells += [f"{scale * a[key]:.{digits}f} / {scale * b[key]:.{digits}f}", rel(a[key], b[key])]
        print("| " + " | ".join(cells) + " |")
# Where each mesh's 25 mm^2 peak sits (current coordinates, run.json's averaged_at) and how far apart
# the meshes' sites are: a peak that moves between meshes is a different contact, not a converging one.
print("\nwhere the 25 mm^2 peak is (current position, mm), " + " / ".join(names) + ", and the distance between sites:")
print("| t (ms) | " + " | ".join(names) + " | distances (mm) |")
print("|---|" + "---|" * len(names) + "---|")
for i, o in enumerate(runs[names[0]]["contact"]["at_outputs"]):
    sites = [runs[n]["contact"]["at_outputs"][i]["averaged_at"] for n in names]
    gaps = [sum((1e3 * (p - q)) ** 2 for p, q in zip(a, b)) ** 0.5 for a, b in zip(sites, sites[1:])]
    print(
        f"| {o['time'] * 1e3:.0f} | "
        + " | ".join("(" + ", ".join(f"{1e3 * c:.1f}" for c in s) + ")" for s in sites)
        + " | "
        + ", ".join(f"{g:.1f}" for g in gaps)
        + " |"
    )
# The 25 mm^2 average at the same material points on every mesh: the finest mesh's three highest
# sites (at least 10 mm apart), each taken on the other meshes about the skin node nearest to it
# in the reference configuration (bench/pressure_sites.py, the solver's average recomputed from the
# state files). The largest average above is a maximum over sites; this compares the field.
from pressure_sites import Field, state_files  # noqa: E402

files = {n: state_files(f"{w}/{n}/out") for n in names}
print("\n25 mm^2 averages (MPa) at the " + names[-1] + " mesh's three highest sites, on each mesh (" + " / ".join(names) + "):")
print("| t (ms) | site (x, y, z at " + names[-1] + ", mm) | " + " / ".join(names) + " | diffs |")
print("|---|---|---|---|")
for o in runs[names[0]]["contact"]["at_outputs"]:
    t = round(o["time"], 9)
    if any(t not in files[n] for n in names):
        continue
    fields = {n: Field(files[n][t]) for n in names}
    finest = fields[names[-1]]
    for node, _ in finest.sites():
        X = finest.state["X"][node]
        values = [fields[n].at_material_point(X)[0] * 1e-6 for n in names]
        site = ", ".join(f"{1e3 * c:.0f}" for c in finest.state["x"][node])
        print(
            f"| {t * 1e3:.0f} | ({site}) | "
            + " / ".join(f"{v:.2f}" for v in values)
            + " | "
            + ", ".join(rel(a, b) for a, b in zip(values, values[1:]))
            + " |"
        )
# The same at a lower bandwidth: force and area averaged over +-0.25 ms about each output. The
# windowed values above average over the pressure window (10 us by default), which passes the
# block's and the bones' ringing (tens of kHz) that differs from mesh to mesh.
times = [o["time"] for o in runs[names[0]]["contact"]["at_outputs"]]
low = {
    n: (centred_mean(histories[n][0], histories[n][1], times, 2.5e-4), centred_mean(histories[n][0], histories[n][2], times, 2.5e-4)) for n in names
}
print("\nforce and area averaged over +-0.25 ms about each output, " + " / ".join(names) + ":")
print("| t (ms) | force (N) | diffs | area (mm^2) | diffs |")
print("|---|---|---|---|---|")
for i, t in enumerate(times):
    force = [low[n][0][i] for n in names]
    area = [low[n][1][i] * 1e6 for n in names]
    print(
        f"| {t * 1e3:.0f} | "
        + " / ".join(f"{x:.0f}" for x in force)
        + " | "
        + ", ".join(rel(x, y) for x, y in zip(force, force[1:]))
        + " | "
        + " / ".join(f"{x:.0f}" for x in area)
        + " | "
        + ", ".join(rel(x, y) for x, y in zip(area, area[1:]))
        + " |"
    )
# The contact impulse between consecutive outputs (the normal force's time integral, mN s): a
# quantity of the whole interval, where the figures above are of an instant. On the hand-block
# case the instantaneous figures of the light first touches scatter by ~10 % from mesh to mesh
# without a trend, while the impulse per millisecond of two meshes with the same cells and finer
# or coarser skin facets agrees within ~8 % but in the first millisecond (README, "Is this case
# mesh-converged?").
bounds = [0.0] + times
print("\ncontact impulse between outputs (mN s), " + " / ".join(names) + ":")
print("| interval (ms) | impulse | diffs |")
print("|---|---|---|")
for lo, hi in zip(bounds, bounds[1:]):
    values = [1e3 * time_integral(histories[n][0], histories[n][1], lo, hi) for n in names]
    print(
        f"| {1e3 * lo:.0f}-{1e3 * hi:.0f} | "
        + " / ".join(f"{v:.2f}" for v in values)
        + " | "
        + ", ".join(rel(a, b) for a, b in zip(values, values[1:]))
        + " |"
    )
if ensemble > 1:
    # Each figure per member of each mesh's ensemble: +-0.25 ms force and area, windowed force and
    # area, 25 mm^2 peak; its mean and spread (max - min) per mesh, then the difference of the
    # meshes' means beside the larger of their spreads (both relative to the first mesh's mean).
    # The first member is the run above (its history and run.json already read); each file once.
    def members(n):
        yield runs[n], histories[n]
        for k in range(1, ensemble):
            d = f"{w}/{n}/out_{k}"
            yield json.load(open(f"{d}/run.json")), read_columns(f"{d}/history.csv", "contact_normal_force", "contact_area")

    figures = {}
    for n in names:
        rows = []
        for run, (t, force, area) in members(n):
            fl, al = centred_mean(t, force, times, 2.5e-4), centred_mean(t, area, times, 2.5e-4)
            rows.append(
                [
                    (fl[i], 1e6 * al[i], o["windowed_normal_force"], 1e6 * o["windowed_area"], 1e-6 * o["averaged_peak_pressure"])
                    for i, o in enumerate(run["contact"]["at_outputs"])
                ]
            )
            print(f"{n} member {len(rows)}: {run['steps']} steps, contact impulse {time_integral(t, force):.4f} N s")
        figures[n] = rows
    labels = ("force +-0.25 ms (N)", "area +-0.25 ms (mm^2)", "windowed force (N)", "windowed area (mm^2)", "25 mm^2 peak (MPa)")
    print(
        f"\nensembles of {ensemble} runs per mesh (initial velocities x (1 + k 1e-6)): mean [min, max] per mesh; "
        "between meshes the difference of means and the larger ensemble spread, both relative to the first mesh's mean"
    )
    for q, label in enumerate(labels):
        print(f"\n{label}:")
        print("| t (ms) | " + " | ".join(names) + " | " + " | ".join(f"{a} / {b}: diff, spread" for a, b in zip(names, names[1:])) + " |")
        print("|---|" + "---|" * (2 * len(names) - 1))
        for i, t in enumerate(times):
            stats = []
            for n in names:
                v = [rows[i][q] for rows in figures[n]]
                stats.append((sum(v) / len(v), min(v), max(v)))
            cells = [f"{1e3 * t:.0f}"] + [f"{m:.3g} [{lo:.3g}, {hi:.3g}]" for m, lo, hi in stats]
            for (ma, la, ha), (mb, lb, hb) in zip(stats, stats[1:]):
                cells.append(f"{100 * (mb / ma - 1):+.1f} %, {100 * max(ha - la, hb - lb) / ma:.1f} %" if ma else "-")
            print("| " + " | ".join(cells) + " |")
