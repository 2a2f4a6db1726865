#!/usr/bin/env bash
# Render one scene as a Slurm job array, one shard of the work per array task; the merge
# (slurm-merge.sh) gives the image a single process would render, bit for bit.
#
#   K=8
#   jid=$(sbatch --parsable --array=0-$((K-1)) slurm-render.sh SCENE $K OUTDIR [OPTIONS...])
#   sbatch --dependency=afterok:$jid slurm-merge.sh OUTDIR IMAGE.exr [IMAGE.png]
#
# OPTIONS are `penumbra render` options (--spp 1024, -D resx=1920, ...), the same for every
# task. Array indices must be 0..K-1: penumbra reads its shard from SLURM_ARRAY_TASK_ID.
# Each task writes OUTDIR/part-INDEX.state (atomically). A task that fails can be rerun
# alone (sbatch --array=INDEX ...); add `--checkpoint OUTDIR/part-INDEX.ckpt` to OPTIONS and
# `--resume` it to continue a preempted task instead of starting it again.
#SBATCH --job-name=penumbra
#SBATCH --cpus-per-task=8
#SBATCH --output=penumbra-%A_%a.log
set -euo pipefail
if [ $# -lt 3 ]; then
  echo "usage: sbatch --array=0-\$((K-1)) $0 SCENE K OUTDIR [RENDER OPTIONS...]" >&2
  exit 2
fi
scene=$1 shards=$2 out=$3
shift 3
penumbra=${PENUMBRA:-penumbra}
mkdir -p "$out"
exec "$penumbra" render "$scene" --shard "auto/$shards" --threads "${SLURM_CPUS_PER_TASK:-0}" \
  -o "$out/part-$SLURM_ARRAY_TASK_ID.state" "$@"
