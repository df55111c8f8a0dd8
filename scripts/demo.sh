#!/usr/bin/env bash
# The main job: shows the catalog, checks a Kummer node, and writes pictures and meshes to OUT.
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
