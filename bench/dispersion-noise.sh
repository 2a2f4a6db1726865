#!/usr/bin/env bash
# usage: bench/dispersion-noise.sh [PENUMBRA] [OUTDIR]
# Issue 21, acceptance 4: colour noise of a dispersive rough glass in spectral mode. Renders
# scenes/dispersion/rough-glass.xml once at REF_SPP with the rough dielectric's MIS over the
# wavelengths (our own reference; both strategies converge to the same image, which the
# furnace test checks), then, RUNS times and alternating the order, each strategy (mis,
# terminate) for TIME_BUDGET seconds of wall time with a fresh seed, and prints each render's spp and
# relMSE against the reference (`penumbra compare`: mean over pixels and channels of
# (test − ref)² / (ref² + 0.01)), and the medians. Not run by CI; no timing is asserted.
# Environment: RES (96), REF_SPP (16384), TIME_BUDGET (seconds per render, 20), RUNS (3).
set -eu
ROOT=$(cd "$(dirname "$0")/.." && pwd)
P=${1:-$ROOT/target/release/penumbra}
O=${2:-$(mktemp -d)}
RES=${RES:-96}; REF_SPP=${REF_SPP:-16384}; BUDGET=${TIME_BUDGET:-20}; RUNS=${RUNS:-3}
S=$ROOT/scenes/dispersion/rough-glass.xml
mkdir -p "$O"
[ -x "$P" ] || (cd "$ROOT" && cargo build --release -p penumbra)

echo "reference: mis, $REF_SPP spp at ${RES}x$RES -> $O/ref.exr"
if [ ! -f "$O/ref.exr" ]; then
  "$P" render "$S" --mode spectral -D res=$RES -D sampling=mis --spp "$REF_SPP" --seed 1000 \
    -o "$O/ref.exr" --stderr "$O/ref.stderr.exr" 2>&1 | grep rendered
fi
declare -A spp err
for run in $(seq 1 "$RUNS"); do
  if [ $((run % 2)) -eq 1 ]; then order="mis terminate"; else order="terminate mis"; fi
  for s in $order; do
    out=$O/$s-$run
    line=$("$P" render "$S" --mode spectral -D res=$RES -D sampling=$s --spp 100000000 \
      --time "$BUDGET" --seed $((run * 7 + ${#s})) -o "$out.exr" --stderr "$out.stderr.exr" 2>&1 \
      | grep rendered)
    n=$(echo "$line" | sed -E 's/rendered ([0-9]+) spp.*/\1/')
    r=$("$P" compare "$O/ref" "$out.exr" --stderr "$out.stderr.exr" 2>&1 | sed -E 's/.*relMSE=([^ ]+).*/\1/' | head -1)
    echo "run $run $s: $n spp in ${BUDGET} s, relMSE $r"
    spp[$s]="${spp[$s]:-} $n"; err[$s]="${err[$s]:-} $r"
  done
done
median() { tr ' ' '\n' | grep -v '^$' | sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
for s in mis terminate; do
  echo "median $s: $(echo ${spp[$s]} | median) spp, relMSE $(echo ${err[$s]} | median)"
done
m=$(echo ${err[mis]} | median); t=$(echo ${err[terminate]} | median)
awk -v m="$m" -v t="$t" 'BEGIN { printf "relMSE terminate / mis at equal time: %.2f\n", t / m }'
