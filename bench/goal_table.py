#!/usr/bin/python3
"""The simplification issue's accuracy goals, row by row, from lodkit_bench_simplify's CSV.

    /usr/bin/python3 bench/goal_table.py docs/benchmarks/simplify_all.csv
    /usr/bin/python3 bench/goal_table.py docs/benchmarks/simplify.csv 0.1,0.01   # only these targets

For every mesh and target with a `quadric` row, compares it with the peers in the same CSV
(meshopt, openmesh, cgal; RMS against the quadric peers openmesh and cgal only) and with `hoppe`, and
prints a Markdown table with the goals each row misses, then the counts:
  - quadric's Hausdorff below every peer's (and whether its certified bound is below too), and below
    every peer whose output keeps quadric's components and Euler characteristic (quadric keeps the
    input's; a peer that cut the mesh along its UV seams or closed a handle may well be nearer),
  - quadric's RMS below every quadric peer's,
  - quadric with zero non-manifold edges and zero flipped faces,
  - hoppe's RMS below quadric's.
Only the standard library; the speed goals come from the timed runs, not from here.
"""
import csv
import sys

PEERS = ("meshopt", "openmesh", "cgal")
QUADRIC_PEERS = ("openmesh", "cgal")


def best(rows, key):
    """The lowest value of column `key` among rows, with the method that has it."""
    row = min(rows, key=lambda r: float(r[key]))
    return float(row[key]), row["method"]


def main() -> None:
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__)
    rows = list(csv.DictReader(open(sys.argv[1])))
    if len(sys.argv) == 3:
        # The bench's target for ratio r is round(r * faces_in).
        ratios = [float(x) for x in sys.argv[2].split(",")]
        rows = [r for r in rows if any(int(r["target"]) == round(x * int(r["faces_in"])) for x in ratios)]
    by_run = {}
    for r in rows:
        by_run.setdefault((r["mesh"], int(r["faces_in"]), int(r["target"])), {})[r["method"]] = r

    counts = dict(runs=0, hausdorff=0, certified=0, kept=0, rms=0, manifold=0, unflipped=0, hoppe=0, hoppe_runs=0)
    print("| mesh → target | quadric H % | best peer H % | quadric RMS % | best quadric peer RMS % "
          "| quadric flipped / nm | hoppe RMS % | goals missed | peers that changed the topology |")
    print("|---|---:|---:|---:|---:|---:|---:|---|---|")
    for (mesh, faces_in, target), run in sorted(by_run.items()):
        q = run.get("quadric")
        peers = [run[m] for m in PEERS if m in run]
        quadric_peers = [run[m] for m in QUADRIC_PEERS if m in run]
        if not q or not peers or not quadric_peers:
            continue
        counts["runs"] += 1
        h, r = float(q["hausdorff_pct"]), float(q["rms_pct"])
        peer_h, peer_h_method = best(peers, "hausdorff_pct")
        peer_r, peer_r_method = best(quadric_peers, "rms_pct")
        bound = float(q.get("hausdorff_bound_pct") or h)
        missed = []
        if h < peer_h:
            counts["hausdorff"] += 1
        else:
            missed.append(f"H vs {peer_h_method}")
        counts["certified"] += bound < peer_h
        topology = (q["components"], q["euler"])
        changed = [p for p in peers if (p["components"], p["euler"]) != topology]
        counts["kept"] += all(h < float(p["hausdorff_pct"]) for p in peers if p not in changed)
        changed_cell = ", ".join(f"{p['method']} ({p['components']} comp., χ {p['euler']})" for p in changed) or "—"
        if r < peer_r:
            counts["rms"] += 1
        else:
            missed.append(f"RMS vs {peer_r_method}")
        nm, flipped = int(q["non_manifold_edges"]), int(q["flipped"])
        counts["manifold"] += nm == 0
        counts["unflipped"] += flipped == 0
        if nm:
            missed.append(f"{nm} non-manifold")
        if flipped:
            missed.append(f"{flipped} flipped")
        hoppe = run.get("hoppe")
        hoppe_cell = "—"
        if hoppe:
            counts["hoppe_runs"] += 1
            hoppe_r = float(hoppe["rms_pct"])
            hoppe_cell = f"{hoppe_r:.5f}"
            if hoppe_r < r:
                counts["hoppe"] += 1
            else:
                missed.append("hoppe RMS")
        print(f"| {mesh} {faces_in} → {q['faces_out']} | {h:.4f} | {peer_h:.4f} ({peer_h_method}) | {r:.5f} "
              f"| {peer_r:.5f} ({peer_r_method}) | {flipped} / {nm} | {hoppe_cell} | {', '.join(missed) or '—'} "
              f"| {changed_cell} |")
    n = counts["runs"]
    print()
    print(f"- `quadric` Hausdorff below every peer's: {counts['hausdorff']} of {n} "
          f"(its certified bound below too: {counts['certified']}); below every peer that kept the "
          f"topology: {counts['kept']} of {n}")
    print(f"- `quadric` RMS below every quadric peer's: {counts['rms']} of {n}")
    print(f"- `quadric` with zero non-manifold edges: {counts['manifold']} of {n}; zero flipped faces: "
          f"{counts['unflipped']} of {n}")
    print(f"- `hoppe` RMS below `quadric`'s: {counts['hoppe']} of {counts['hoppe_runs']}")


if __name__ == "__main__":
    main()
