#!/bin/bash
# The shape diagram as a Slurm job array: one task per case, then one merge.
#
#   mkdir -p out/diagram
#   N=$(vesicle diagram runs/diagram.json --list | tail -1 | cut -d' ' -f1)
#   jid=$(sbatch --parsable --array=0-$((N - 1)) runs/diagram_slurm.sh)
#   sbatch --dependency=afterok:$jid --wrap "vesicle diagram runs/diagram.json --out out/diagram --merge"
#
# Each case runs on one thread (its numbers do not depend on the layout of the sweep) and
# writes out/diagram/cases/<case>/result.json last, atomically; a task that is rerun after a
# failure redoes only its own case (--force).
#SBATCH --job-name=vesicle-diagram
#SBATCH --cpus-per-task=1
#SBATCH --mem=2G
#SBATCH --time=00:30:00
#SBATCH --output=out/diagram/slurm-%A_%a.log
set -euo pipefail
vesicle diagram runs/diagram.json --out out/diagram --case "$SLURM_ARRAY_TASK_ID" --force
