#!/usr/bin/env bash
# Side-by-side geodesic benchmark, ours and the peers in one run (docs/benchmarks.md, geodesic
# section). Usage, from the repository root:
#
#   PEERS=/work/shared/peers/geodesic PY=/path/to/venv/bin/python \
#     crates/geodesic/benches/side_by_side.sh OUTDIR [MESH:SOURCE:CUTOFF ...]
#
# PY is a venv with numpy, scipy, potpourri3d and tvb-gdist. Without mesh arguments the
# unit icospheres ico5-ico7 (written by $PEERS/make_meshes.py into OUTDIR/meshes) from vertex 0
# are run. Each method runs as its own process (single-threaded peers); every field is written
# to OUTDIR and compared with our exact field (max |d - exact| / max exact over the finite
# entries; the peers have no cut-off, so they are compared where ours is finite).
set -euo pipefail
OUT=${1:?OUTDIR}; shift
: "${PEERS:?PEERS=shared/peers/geodesic}" "${PY:?PY=venv python}"
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-target}
cargo build --release -q -p geodesic --example geo_time
B=$CARGO_TARGET_DIR/release/examples/geo_time
mkdir -p "$OUT"
CASES=("$@")
if [ ${#CASES[@]} -eq 0 ]; then
  [ -f "$OUT/meshes/ico7.obj" ] || "$PY" "$PEERS/make_meshes.py" --outdir "$OUT/meshes" >/dev/null
  CASES=("$OUT/meshes/ico5.obj:0:-" "$OUT/meshes/ico6.obj:0:-" "$OUT/meshes/ico7.obj:0:-")
fi
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 RAYON_NUM_THREADS=1
for c in "${CASES[@]}"; do
  IFS=: read -r mesh src cut <<<"$c"
  tag=$(basename "$mesh" .obj)_s$src
  for m in exact fmm heat; do
    echo "$tag ours_$m $("$B" "$mesh" $m "$src" "$cut" 3 "$OUT/${tag}_ours_$m.txt" | sed 's/^JSON //')"
  done
  for m in fmm_pp3d heat_pp3d exact_gdist; do
    rep=3; [ $m = exact_gdist ] && rep=1
    line=$("$PY" "$PEERS/geodesic_peer.py" "$mesh" "$src" --method $m --repeat $rep --json \
      --out "$OUT/${tag}_$m.txt" 2>&1 | grep '^JSON ' | sed 's/^JSON //' || true)
    echo "$tag $m ${line:-failed}"
  done
done | tee "$OUT/times.txt"
"$PY" - "$OUT" <<'PYEOF'
import glob, os, sys
import numpy as np
out = sys.argv[1]
for ex in sorted(glob.glob(os.path.join(out, "*_ours_exact.txt"))):
    tag = os.path.basename(ex)[: -len("_ours_exact.txt")]
    ref = np.loadtxt(ex)
    fin = np.isfinite(ref)
    scale = ref[fin].max()
    for f in sorted(glob.glob(os.path.join(out, tag + "_*.txt"))):
        if f == ex:
            continue
        d = np.loadtxt(f)
        ok = fin & np.isfinite(d)
        rel = np.abs(d[ok] - ref[ok]) / np.maximum(ref[ok], 1e-300)
        print("%s %s: max |d - exact| / max exact %.2e, mean %.2e, max rel (d > 0) %.2e" % (
            tag, os.path.basename(f)[len(tag) + 1:-4],
            np.abs(d[ok] - ref[ok]).max() / scale, np.abs(d[ok] - ref[ok]).mean() / scale,
            rel[ref[ok] > 0].max()))
PYEOF
