#!/usr/bin/env bash
# Merge the shard states slurm-render.sh wrote into the image(s) (see that script).
#   sbatch --dependency=afterok:JOBID slurm-merge.sh OUTDIR IMAGE.exr [IMAGE.png ...]
#SBATCH --job-name=penumbra-merge
#SBATCH --cpus-per-task=2
#SBATCH --output=penumbra-merge-%j.log
set -euo pipefail
if [ $# -lt 2 ]; then
  echo "usage: $0 OUTDIR IMAGE..." >&2
  exit 2
fi
out=$1
shift
outputs=()
for image in "$@"; do outputs+=(-o "$image"); done
exec "${PENUMBRA:-penumbra}" merge "$out"/part-*.state "${outputs[@]}"
