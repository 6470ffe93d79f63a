#!/usr/bin/python3
"""Charts from lodkit_bench_simplify's CSV: error against face count, and error against time.

    /usr/bin/python3 bench/plot_simplify.py docs/benchmarks/schroeder.csv docs/benchmarks/schroeder

writes <prefix>_error_vs_faces.{png,svg}, <prefix>_error_vs_time.{png,svg} (the Pareto view) and
<prefix>_validity_vs_reduction.{png,svg} (components, Euler characteristic and invalid elements --
non-manifold edges plus flipped faces -- against the fraction of faces kept), with matplotlib from
Debian's python3-matplotlib. One panel per mesh (at most three to a row, one legend for all); log
scales where the data spans decades.
"""
import csv
import math
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
    # Fixed colours per method: a panel where a method is missing (hoppe is skipped on large meshes)
    # must not shift the others' colours.
    colours = {m: plt.get_cmap("tab10")(i % 10) for i, m in enumerate(methods)}
    for x_key, x_label, name in (("faces_out", "output faces", "error_vs_faces"),
                                 ("seconds", "simplification time (s)", "error_vs_time")):
        cols = min(3, len(meshes))
        rows_of_panels = math.ceil(len(meshes) / cols)
        fig, axes = plt.subplots(rows_of_panels, cols, figsize=(4.6 * cols, 3.8 * rows_of_panels + 0.6),
                                 squeeze=False)
        for ax in axes.flat[len(meshes):]:
            ax.set_visible(False)
        for ax, mesh in zip(axes.flat, meshes):
            series = defaultdict(list)
            for r in rows:
                if r["mesh"] == mesh:
                    series[r["method"]].append((float(r[x_key]), float(r["hausdorff_pct"])))
            for method in methods:
                points = sorted(series.get(method, []))
                if points:
                    ax.plot([p[0] for p in points], [p[1] for p in points], marker=markers[method], color=colours[method],
                            label=method)
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_title(mesh, fontsize=9)
            ax.set_xlabel(x_label)
            ax.set_ylabel("symmetric Hausdorff (% of diagonal)")
            ax.grid(True, which="both", alpha=0.3)
        shared_legend(fig, axes)
        for ext in ("png", "svg"):
            fig.savefig(f"{prefix}_{name}.{ext}", dpi=110)
        plt.close(fig)

    plot_validity(rows, meshes, methods, markers, colours, prefix)


def plot_validity(rows, meshes, methods, markers, colours, prefix) -> None:
    """Where methods fail: a valid simplification keeps the input's components and Euler
    characteristic and has no non-manifold edges or flipped faces."""
    panels = (("components", "components"), ("euler", "Euler characteristic"),
              ("invalid", "non-manifold edges + flipped faces"))
    # One row per mesh, one column per measure.
    fig, axes = plt.subplots(len(meshes), len(panels), figsize=(4.6 * len(panels), 3.0 * len(meshes) + 0.6),
                             squeeze=False)
    for row, mesh in enumerate(meshes):
        for col, (key, label) in enumerate(panels):
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
                            color=colours[method], label=method)
            ax.set_xscale("log")
            ax.invert_xaxis()  # reduction grows to the right
            if key != "euler":
                ax.set_yscale("symlog", linthresh=1)
                ax.set_ylim(bottom=0)
            ax.set_xlabel("fraction of faces kept")
            ax.set_ylabel(label)
            ax.set_title(f"{mesh}: {label}", fontsize=9)
            ax.grid(True, which="both", alpha=0.3)
    shared_legend(fig, axes)
    for ext in ("png", "svg"):
        fig.savefig(f"{prefix}_validity_vs_reduction.{ext}", dpi=110)
    plt.close(fig)


def shared_legend(fig, axes) -> None:
    """One legend for every panel, in a row under the title area, so no panel's data is covered."""
    handles, labels = {}, []
    for ax in axes.flat:
        for h, l in zip(*ax.get_legend_handles_labels()):
            if l not in handles:
                handles[l] = h
                labels.append(l)
    fig.legend([handles[l] for l in labels], labels, loc="upper center", ncol=len(labels), fontsize=9,
               frameon=False)
    fig.tight_layout(rect=(0, 0, 1, 1 - 0.45 / fig.get_figheight()))


if __name__ == "__main__":
    main()
