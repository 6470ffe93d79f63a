#!/usr/bin/env bash
# `simplify --max-error e` against `--max-hausdorff e` (docs/commands/simplify.md, "A proved limit"):
# one Markdown row per mesh and limit, with the faces kept, the measured Hausdorff distance and the time
# of the whole call.
#
#   scripts/bench-within.sh                      # the default set from ../shared/models, 0.05 %, 0.2 %, 1 %
#   LIMITS="0.1%" scripts/bench-within.sh a.ply  # your meshes and limits
set -euo pipefail
cd "$(dirname "$0")/.."
lodkit=${LODKIT:-build/cli/lodkit}
m=../shared/models
meshes=("$@")
[ ${#meshes[@]} -eq 0 ] && meshes=("$m/scans/stanford_bunny_zipper.ply" "$m/scans/horse.ply" "$m/scans/nefertiti_100k.obj"
                                   "$m/cad/fandisk.obj" "$m/cad/rocker_arm.obj" "$m/large/igea_loop1.ply")
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo '| mesh | limit | `--max-error`: faces | its Hausdorff % | time s | `--max-hausdorff`: faces | proved at most % | measured % | checks | time s |'
echo '|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|'
for mesh in "${meshes[@]}"; do
  for limit in ${LIMITS:-0.05% 0.2% 1%}; do
    "$lodkit" simplify "$mesh" -o "$tmp/a.ply" --max-error "$limit" --measure --json > "$tmp/a.json" 2>/dev/null
    "$lodkit" simplify "$mesh" -o "$tmp/b.ply" --max-hausdorff "$limit" --measure --json > "$tmp/b.json" 2>/dev/null
    /usr/bin/python3 - "$mesh" "$limit" "$tmp/a.json" "$tmp/b.json" <<'EOF'
import json, os, sys
mesh, limit, a, b = sys.argv[1], sys.argv[2], json.load(open(sys.argv[3])), json.load(open(sys.argv[4]))
w = b["hausdorff_limit"]
print(f"| {os.path.basename(mesh)} | {limit} | {a['faces_out']:,} | {a['measured']['hausdorff_percent']:.4f} | {a['seconds']:.3f} "
      f"| {b['faces_out']:,} | {w['bound_percent']:.4f} | {b['measured']['hausdorff_percent']:.4f} | {w['checks']} | {b['seconds']:.3f} |")
EOF
  done
done
