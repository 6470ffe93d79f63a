#!/usr/bin/python3
"""Charts from lodkit_bench_simplify's CSV: error against face count, and error against time.

    /usr/bin/python3 bench/plot_simplify.py docs/benchmarks/schroeder.csv docs/benchmarks/schroeder

writes <prefix>_error_vs_faces.{png,svg}, <prefix>_error_vs_time.{png,svg} (the Pareto view) and
<prefix>_validity_vs_reduction.{png,svg} (components, Euler characteristic and invalid elements --
non-manifold edges plus flipped faces -- against the fraction of faces kept), with matplotlib from
Debian's python3-matplotlib. One panel per mesh; log scales where the data spans decades.
"""
import csv
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main() -> None:
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    rows = list(csv.DictReader(open(sys.argv[1])))
    prefix = sys.argv[2]
    meshes = list(dict.fromkeys(r["mesh"] for r in rows))
    methods = list(dict.fromkeys(r["method"] for r in rows))
    markers = dict(zip(methods, "os^vDPX*<>"))
    for x_key, x_label, name in (("faces_out", "output faces", "error_vs_faces"),
                                 ("seconds", "simplification time (s)", "error_vs_time")):
        fig, axes = plt.subplots(1, len(meshes), figsize=(4.2 * len(meshes), 3.8), squeeze=False)
        for ax, mesh in zip(axes[0], meshes):
            series = defaultdict(list)
            for r in rows:
                if r["mesh"] == mesh:
                    series[r["method"]].append((float(r[x_key]), float(r["hausdorff_pct"])))
            for method in methods:
                points = sorted(series.get(method, []))
                if points:
                    ax.plot([p[0] for p in points], [p[1] for p in points], marker=markers[method], label=method)
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_title(mesh, fontsize=9)
            ax.set_xlabel(x_label)
            ax.set_ylabel("symmetric Hausdorff (% of diagonal)")
            ax.grid(True, which="both", alpha=0.3)
        axes[0][0].legend(fontsize=8)
        fig.tight_layout()
        for ext in ("png", "svg"):
            fig.savefig(f"{prefix}_{name}.{ext}", dpi=110)
        plt.close(fig)

    plot_validity(rows, meshes, methods, markers, prefix)


def plot_validity(rows, meshes, methods, markers, prefix) -> None:
    """Where methods fail: a valid simplification keeps the input's components and Euler
    characteristic and has no non-manifold edges or flipped faces."""
    panels = (("components", "components"), ("euler", "Euler characteristic"),
              ("invalid", "non-manifold edges + flipped faces"))
    fig, axes = plt.subplots(len(panels), len(meshes), figsize=(4.2 * len(meshes), 3.2 * len(panels)),
                             squeeze=False)
    for col, mesh in enumerate(meshes):
        for row, (key, label) in enumerate(panels):
            ax = axes[row][col]
            for method in methods:
                points = []
                for r in rows:
                    if r["mesh"] != mesh or r["method"] != method:
                        continue
                    kept = float(r["faces_out"]) / float(r["faces_in"])
                    value = (int(r["non_manifold_edges"]) + int(r["flipped"]) if key == "invalid"
                             else int(r[key]))
                    points.append((kept, value))
                points.sort()
                if points:
                    ax.plot([p[0] for p in points], [p[1] for p in points], marker=markers[method],
                            label=method)
            ax.set_xscale("log")
            ax.invert_xaxis()  # reduction grows to the right
            if key != "euler":
                ax.set_yscale("symlog", linthresh=1)
                ax.set_ylim(bottom=0)
            ax.set_xlabel("fraction of faces kept")
            ax.set_ylabel(label)
            if row == 0:
                ax.set_title(mesh, fontsize=9)
            ax.grid(True, which="both", alpha=0.3)
    axes[0][0].legend(fontsize=8)
    fig.tight_layout()
    for ext in ("png", "svg"):
        fig.savefig(f"{prefix}_validity_vs_reduction.{ext}", dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    main()
