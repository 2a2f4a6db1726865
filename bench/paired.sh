#!/usr/bin/env bash
# usage: bench/paired.sh BASE_BIN NEW_BIN [PAIRS]
# Paired benchmark of two binaries on bench-cbox (256², 64 spp, one thread), alternating
# base and new; prints mean wall and user CPU time and the mean ratio new/base ± its standard
# error.
B=$1; N=$2; K=${3:-10}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
S=${SHARED:-$ROOT/../shared}/references/scenes/bench-cbox.xml
for i in $(seq $K); do
  for which in B N; do
    bin=$B; [ $which = N ] && bin=$N
    /usr/bin/time -f "$which %e %U" $bin render $S -D resx=256 -D resy=256 --spp 64 --seed 1 --threads 1 -q -o /tmp/pb-$which.exr 2>&1 >/dev/null | tail -1
  done
done | python3 -c '
import sys,statistics as st
b=[];n=[]
for l in sys.stdin:
    w,e,u=l.split(); (b if w=="B" else n).append((float(e),float(u)))
for k,name in ((0,"wall"),(1,"user")):
    r=[y[k]/x[k] for x,y in zip(b,n)]
    print(f"{name}: base {st.mean(x[k] for x in b):.3f}s new {st.mean(y[k] for y in n):.3f}s ratio {st.mean(r):.4f} ± {st.stdev(r)/len(r)**0.5:.4f} (n={len(r)})")
'
