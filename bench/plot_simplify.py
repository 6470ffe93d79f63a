#!/usr/bin/python3
"""Charts from lodkit_bench_simplify's CSV: error against face count, and error against time.

    /usr/bin/python3 bench/plot_simplify.py docs/benchmarks/schroeder.csv docs/benchmarks/schroeder

writes <prefix>_error_vs_faces.{png,svg} and <prefix>_error_vs_time.{png,svg} (matplotlib, from
Debian's python3-matplotlib). One panel per mesh; log scales since the data spans decades.
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


if __name__ == "__main__":
    main()
