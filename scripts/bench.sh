#!/usr/bin/env bash
# Runs every benchmark: zeroset's Google Benchmark programs and the peer comparisons
# (VTK, scikit-image, CGAL, surf, POV-Ray), and writes docs/benchmarks.md.
# Usage: scripts/bench.sh BUILD_DIR
set -euo pipefail
build=${1:?usage: bench.sh BUILD_DIR}
py=/usr/bin/python3   # Debian's Python, which has python3-vtk9 and python3-skimage
cd "$(dirname "$0")/.."
$py bench/field_report.py "$build"
$py bench/render_peers.py "$build"
$py bench/mesh_peers.py "$build"
$py bench/floaters_bench.py "$build"
$py bench/python_overhead.py "$build"
echo "bench: docs/benchmarks.md updated"
