#!/usr/bin/env bash
# Makes the pictures of docs/meshing.md, section "The paper's figures 7–9", and prints the
# quality figures that go with them (from --stats).
#
#   docs/img/meshing-figures.sh path/to/zeroset [OUTDIR]
#
# OUTDIR defaults to this script's directory (docs/img). Needs python3 for the table; with
# ImageMagick's `convert` on PATH the pictures are quantized to 64 colours to keep them small.
set -euo pipefail

if [[ $# -lt 1 || $# -gt 2 ]]; then
  echo "usage: $0 ZEROSET [OUTDIR]" >&2
  exit 2
fi
ZS=$1
OUT=${2:-$(cd "$(dirname "$0")" && pwd)}
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
SIZE=300x300
NAMES=()
QUANTIZE=0
if convert -version 2>/dev/null | grep -q ImageMagick; then QUANTIZE=1; fi

# shot NAME SURFACE [zeroset mesh flags...]: one picture OUT/mesh-fig-NAME.png and its stats.
shot() {
  local name=$1 surface=$2
  shift 2
  "$ZS" --quiet mesh "$surface" "$@" --wireframe --size "$SIZE" \
    --png "$OUT/mesh-fig-$name.png" --stats "$TMP/$name.json" -o "$TMP/$name.obj"
  if [[ $QUANTIZE == 1 ]]; then
    convert "$OUT/mesh-fig-$name.png" -colors 64 -strip "PNG8:$OUT/mesh-fig-$name.png"
  fi
  NAMES+=("$name")
}

# Figure 7(a)/(b): marching cubes against the improvers on the ring torus, 16 cells.
shot 7ab-raw torus -r 16 --improve off
shot 7ab-paper torus -r 16 --improver paper
shot 7ab-nocurv torus -r 16 --improver paper --no-curvature
shot 7ab-remesh torus -r 16 --improver remesh

# Figure 7(c): a thin torus (tube radius 0.12, 1.2 cells across) at 16 cells.
T7=$TMP/thin-torus.json
cat >"$T7" <<'EOF'
{"name": "torus", "parameters": {"r": 0.12},
 "camera": {"azimuth_deg": 30, "elevation_deg": 35, "distance": 4, "fov_deg": 30}}
EOF
shot 7c-raw "$T7" -r 16 --improve off
shot 7c-paper "$T7" -r 16 --improver paper
shot 7c-nocurv "$T7" -r 16 --improver paper --no-curvature
shot 7c-remesh "$T7" -r 16 --improver remesh

# Figure 8: Kummer mu = 1.5 at 32 cells, the inner nodes and the small pieces between them.
K8=$TMP/kummer-view.json
cat >"$K8" <<'EOF'
{"name": "kummer", "parameters": {"mu": 1.5},
 "camera": {"azimuth_deg": 75, "elevation_deg": 40, "distance": 9, "fov_deg": 30}}
EOF
shot 8-raw "$K8" -r 32 --improve off
shot 8-paper "$K8" -r 32 --improver paper
shot 8-nocurv "$K8" -r 32 --improver paper --no-curvature
shot 8-remesh "$K8" -r 32 --improver remesh

# Figure 9: the node of the ding-dong surface seen from close by, 16 cells.
D9=$TMP/dingdong-node.json
cat >"$D9" <<'EOF'
{"name": "dingdong",
 "camera": {"azimuth_deg": 30, "elevation_deg": 10, "distance": 1.6, "fov_deg": 30, "target": [0, 0, 0]}}
EOF
shot 9-raw "$D9" -r 16 --improve off
shot 9-paper "$D9" -r 16 --improver paper
shot 9-nocurv "$D9" -r 16 --improver paper --no-curvature
shot 9-remesh "$D9" -r 16 --improver remesh

# Boundary (paper section 4.2): a paraboloid cut by a sphere, 10 cells, fixed or sliding.
PB=$TMP/paraboloid.json
cat >"$PB" <<'EOF'
{"name": "paraboloid", "equation": "x^2 + y^2 - z", "clip": ["sphere:1@0,0,0.6"],
 "camera": {"azimuth_deg": 30, "elevation_deg": 80, "fov_deg": 30, "target": [0, 0, 0.6]}}
EOF
shot bd-raw "$PB" -r 10 --improve off
shot bd-fix "$PB" -r 10 --boundary fix --improver paper
shot bd-constrain "$PB" -r 10 --boundary constrain --improver paper
shot bd-remesh "$PB" -r 10 --improver remesh

python3 - "$TMP" "${NAMES[@]}" <<'EOF'
import json, sys
tmp, names = sys.argv[1], sys.argv[2:]
# node gap: the largest distance from a known singular point to the nearest vertex, in mean
# edge lengths; against: triangles facing against the gradient.
print(f"{'picture':<16} {'verts':>5} {'<30° raw':>8} {'<30°':>6} {'mean min':>8} "
      f"{'steps':>5} {'at rest':>7} {'against':>7} {'node gap':>8} {'max res':>7}")
for n in names:
    s = json.load(open(f"{tmp}/{n}.json"))
    q = s["quality_after"]
    imp = s.get("improve")
    steps = "-" if imp is None else imp.get("steps", imp.get("iterations"))
    rest = "-" if imp is None else ("yes" if imp["converged"] else "no")
    gaps = [p["in_mean_edge_lengths"] for p in q.get("singular_points", [])]
    gap = f"{max(gaps):.2f}" if gaps else "-"
    print(f"{n:<16} {q['vertices']:>5} {s['quality_before']['percent_min_angle_below_30']:>7.1f}% "
          f"{q['percent_min_angle_below_30']:>5.1f}% {q['mean_min_angle_deg']:>7.1f}° "
          f"{steps!s:>5} {rest:>7} {q['normal_deviation_deg']['flipped_triangles']:>7} {gap:>8} {q['residual']['max']:>7.0e}")
EOF

# Figure 7(a)/(b): the density on the torus's inner side (distance from the z axis below the
# major radius 1, where the surface bends more) against its outer side: mean edge lengths.
python3 - "$TMP" <<'EOF'
import math, sys
for n in ["7ab-raw", "7ab-paper", "7ab-nocurv", "7ab-remesh"]:
    v, edges = [], set()
    for line in open(f"{sys.argv[1]}/{n}.obj"):
        p = line.split()
        if p and p[0] == "v":
            v.append(tuple(map(float, p[1:4])))
        elif p and p[0] == "f":
            f = [int(x.split("/")[0]) - 1 for x in p[1:]]
            edges |= {tuple(sorted((f[i], f[(i + 1) % 3]))) for i in range(3)}
    side = {True: [], False: []}
    for a, b in edges:
        m = [(v[a][k] + v[b][k]) / 2 for k in range(3)]
        side[math.hypot(m[0], m[1]) < 1].append(math.dist(v[a], v[b]))
    inner, outer = (sum(side[k]) / len(side[k]) for k in (True, False))
    print(f"{n:<16} edge inside {inner:.3f}, outside {outer:.3f}, ratio {inner / outer:.2f}")
EOF

# Boundary: the spacing of the vertices along the clip curve (edges with one triangle).
python3 - "$TMP" <<'EOF'
import math, statistics, sys
for n in ["bd-raw", "bd-fix", "bd-constrain", "bd-remesh"]:
    v, count = [], {}
    for line in open(f"{sys.argv[1]}/{n}.obj"):
        p = line.split()
        if p and p[0] == "v":
            v.append(tuple(map(float, p[1:4])))
        elif p and p[0] == "f":
            f = [int(x.split("/")[0]) - 1 for x in p[1:]]
            for i in range(3):
                e = tuple(sorted((f[i], f[(i + 1) % 3])))
                count[e] = count.get(e, 0) + 1
    lengths = [math.dist(v[a], v[b]) for (a, b), c in count.items() if c == 1]
    mean = statistics.mean(lengths)
    print(f"{n:<16} {len(lengths)} border edges, shortest/mean {min(lengths) / mean:.2f}, "
          f"longest/mean {max(lengths) / mean:.2f}, std/mean {statistics.pstdev(lengths) / mean:.2f}")
EOF

# Figure 8: at each node, the nearest vertex of another connected piece of the mesh than the
# one holding the node's nearest vertex (where marching cubes split the nappes there, the gap
# between them), in mean edge lengths: the median over the nodes, and at how many nodes another
# piece comes within one mean edge.
python3 - "$TMP" <<'EOF'
import json, math, statistics, sys
for n in ["8-raw", "8-paper", "8-nocurv", "8-remesh"]:
    v, tris = [], []
    for line in open(f"{sys.argv[1]}/{n}.obj"):
        p = line.split()
        if p and p[0] == "v":
            v.append(tuple(map(float, p[1:4])))
        elif p and p[0] == "f":
            tris.append([int(x.split("/")[0]) - 1 for x in p[1:]])
    parent = list(range(len(v)))
    def root(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a
    for t in tris:
        for j in t[1:]:
            parent[root(j)] = root(t[0])
    used = {j for t in tris for j in t}
    q = json.load(open(f"{sys.argv[1]}/{n}.json"))["quality_after"]
    gaps = []
    for s in q["singular_points"]:
        best = {}
        for j in used:
            d, r = math.dist(v[j], s["point"]), root(j)
            best[r] = min(best.get(r, math.inf), d)
        first, second = sorted(best.values())[:2]
        gaps.append(second / q["mean_edge_length"])
    near = sum(g < 1 for g in gaps)
    print(f"{n:<16} {len({root(j) for j in used})} pieces; other piece from a node: median "
          f"{statistics.median(gaps):.2f} mean edges, within one at {near} of {len(gaps)} nodes")
EOF
