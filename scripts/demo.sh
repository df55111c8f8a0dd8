#!/usr/bin/env bash
# The main job: shows the catalog, checks a Kummer node, and writes pictures and a mesh to OUT:
# the Kummer family ray traced as in the paper's figure 1, a few catalog surfaces, floaters on
# the Kummer surface, and its remeshed mesh.
# Usage: scripts/demo.sh ZEROSET_BINARY OUT_DIR
set -euo pipefail
zs=${1:?usage: demo.sh ZEROSET_BINARY OUT_DIR}
out=${2:-out}
mkdir -p "$out"

echo "== The catalog"
"$zs" list
echo
echo "== The Kummer surface at mu = 1.5 and one of its 16 nodes (F and grad F vanish there)"
"$zs" info kummer --param mu=1.5
echo
"$zs" eval kummer --param mu=1.5 --at 1.0606601718,-0.3535533906,-0.5
echo
echo "== Ray traced: the Kummer family (the paper's figure 1) and catalog surfaces"
for mu in 1.02 1.5 2.44 3.0; do
  "$zs" render kummer --param mu=$mu --size 600x600 --aa 2 -o "$out/kummer-$mu.png"
  echo "wrote $out/kummer-$mu.png"
done
for s in barth6 roman cayley dingdong; do
  "$zs" render $s --size 600x600 --aa 2 -o "$out/$s.png"
  echo "wrote $out/$s.png"
done
echo
echo "== Floaters on the Kummer surface, mu = 1.5 (the paper's figure 5(b))"
"$zs" sample kummer --param mu=1.5 --seed 1 -o "$out/kummer-floaters.ply" \
  --png "$out/kummer-floaters.png" --stats "$out/kummer-floaters.json"
echo "wrote $out/kummer-floaters.ply, .png, .json"
echo
echo "== Polygonized and remeshed mesh of the Kummer surface, mu = 1.5"
"$zs" mesh kummer --param mu=1.5 --resolution 128 -o "$out/kummer.glb" \
  --png "$out/kummer-mesh.png" --wireframe --size 600x600 --stats "$out/kummer-mesh.json"
echo "wrote $out/kummer.glb, $out/kummer-mesh.png, $out/kummer-mesh.json"
echo
echo "Done: pictures, floaters and a mesh are in $out/"
